#include "model/obj_io.h"

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "common/error.h"
#include "common/write_file.h"

namespace hgrasp::model {
namespace {

namespace fs = std::filesystem;

void WritePng(const fs::path& path, const cv::Mat& image) {
  std::vector<uchar> png;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, png);
  } catch (const cv::Exception& e) {
    throw std::runtime_error(path.string() + ": PNG encoding failed: " + e.what());
  }
  if (!ok) throw std::runtime_error(path.string() + ": PNG encoding failed");
  WriteFileWhole(path.string(), {reinterpret_cast<const char*>(png.data()), png.size()});
}

// Counter-clockwise from outside: texture order 0, 3, 2, 1.
constexpr std::array<int, 4> kCcw = {0, 3, 2, 1};

/// The first usable texture of each face (null where there is none).
std::array<const FaceTexture*, 6> FirstTextures(const std::vector<FaceTexture>& textures) {
  std::array<const FaceTexture*, 6> tex{};
  for (const FaceTexture& t : textures) {
    if (t.face >= 0 && t.face < 6 && !t.image.empty() && tex[t.face] == nullptr) tex[t.face] = &t;
  }
  return tex;
}

/// Face f of the box `name` (its vertices from OBJ index v0) with texture t: the PNG beside
/// the OBJ, its material, four texture coordinates (after *vt_count of them) and the face.
void WriteTexturedFace(const FaceTexture& t, int f, int v0, const std::string& dir,
                       const std::string& stem, const std::string& name, int* vt_count,
                       std::ostringstream* obj, std::ostringstream* mtl) {
  const std::array<int, 4> corner = FaceCornerIndices(f);
  const std::string material = name + "_face" + std::to_string(f);
  const std::string png = stem + "_" + material + ".png";
  WritePng(fs::path(dir) / png, t.image);
  *mtl << "\nnewmtl " << material << "\nKa 1 1 1\nKd 1 1 1\nKs 0 0 0\nillum 1\nmap_Kd " << png
       << '\n';
  // Corner k sits at the centre of its corner texel; OBJ's v is 0 at the image's bottom.
  const double w = t.image.cols, h = t.image.rows;
  constexpr std::array<std::array<int, 2>, 4> kTexel = {{{0, 0}, {1, 0}, {1, 1}, {0, 1}}};
  for (const auto& [tx, ty] : kTexel) {
    const double x = tx ? w - 0.5 : 0.5, y = ty ? h - 0.5 : 0.5;
    *obj << "vt " << x / w << ' ' << 1.0 - y / h << '\n';
  }
  *obj << "usemtl " << material << "\nf";
  for (int k : kCcw) *obj << ' ' << v0 + corner[k] << '/' << *vt_count + k + 1;
  *obj << '\n';
  *vt_count += 4;
}

}  // namespace

void WriteObj(const std::vector<BoxModel>& boxes,
              const std::vector<std::vector<FaceTexture>>& textures,
              const std::vector<Eigen::Vector3f>& colours_rgb, const std::string& dir,
              const std::string& stem) {
  const std::string per_box = "0 or " + std::to_string(boxes.size()) + " entries (one per box)";
  if (!textures.empty() && textures.size() != boxes.size()) {
    throw InputError("", "textures", std::to_string(textures.size()) + " entries", per_box);
  }
  if (!colours_rgb.empty() && colours_rgb.size() != boxes.size()) {
    throw InputError("", "colours_rgb", std::to_string(colours_rgb.size()) + " entries", per_box);
  }
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot create the directory: " + ec.message());

  std::ostringstream obj, mtl;
  obj.precision(9);
  mtl.precision(6);
  obj << "# hgrasp box models: vertices in W (m)\n"
      << "mtllib " << stem << ".mtl\n";
  mtl << "# hgrasp box models\n";
  int vt_count = 0;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const BoxModel& box = boxes[i];
    const std::string name = "box" + std::to_string(i);
    const int v0 = static_cast<int>(8 * i) + 1;  // OBJ indices are 1-based and global

    const std::array<const FaceTexture*, 6> tex =
        textures.empty() ? std::array<const FaceTexture*, 6>{} : FirstTextures(textures[i]);

    const Eigen::Vector3f kd = colours_rgb.empty()
                                   ? Eigen::Vector3f::Constant(0.7f)
                                   : Eigen::Vector3f(colours_rgb[i].cwiseMax(0).cwiseMin(1));
    mtl << "\nnewmtl " << name << "\nKa " << kd.x() << ' ' << kd.y() << ' ' << kd.z() << "\nKd "
        << kd.x() << ' ' << kd.y() << ' ' << kd.z() << "\nKs 0 0 0\nillum 1\n";

    obj << "\no " << name << '\n';
    for (const Eigen::Vector3d& p : box.vertices_W) {
      obj << "v " << p.x() << ' ' << p.y() << ' ' << p.z() << '\n';
    }
    bool plain_used = false;
    for (int f = 0; f < 6; ++f) {
      if (tex[f] == nullptr) continue;
      WriteTexturedFace(*tex[f], f, v0, dir, stem, name, &vt_count, &obj, &mtl);
    }
    for (int f = 0; f < 6; ++f) {
      if (tex[f] != nullptr) continue;
      if (!plain_used) obj << "usemtl " << name << '\n';
      plain_used = true;
      const std::array<int, 4> corner = FaceCornerIndices(f);
      obj << "f";
      for (int k : kCcw) obj << ' ' << v0 + corner[k];
      obj << '\n';
    }
  }
  const fs::path base = fs::path(dir) / stem;
  WriteFileWhole(base.string() + ".mtl", mtl.str());
  WriteFileWhole(base.string() + ".obj", obj.str());
}

}  // namespace hgrasp::model
