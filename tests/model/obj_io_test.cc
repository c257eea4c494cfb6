#include "model/obj_io.h"

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/imgcodecs.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "common/error.h"
#include "tests/model/textured_box_scene.h"

namespace hgrasp::model {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector2d;
using Eigen::Vector3d;

/// A fresh directory under the system's temporary directory, removed at the end of the test.
class TempDir {
 public:
  TempDir() {
    const auto ticks = std::chrono::steady_clock::now().time_since_epoch().count();
    path_ = fs::temp_directory_path() / ("hgrasp_obj_io_test_" + std::to_string(ticks));
    fs::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// One "f" line: vertex and texture-coordinate indices (1-based; vt 0 when absent) and the
/// material in use.
struct ObjFace {
  std::vector<int> v, vt;
  std::string material;
  std::string object;
};

struct ParsedObj {
  std::vector<Vector3d> v;
  std::vector<Vector2d> vt;
  std::vector<ObjFace> faces;
  std::vector<std::string> objects;
  std::string mtllib;
};

ParsedObj ReadObj(const fs::path& path) {
  ParsedObj out;
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  std::string line, material, object;
  while (std::getline(f, line)) {
    std::istringstream in(line);
    std::string tag;
    in >> tag;
    if (tag == "v") {
      Vector3d p;
      in >> p.x() >> p.y() >> p.z();
      out.v.push_back(p);
    } else if (tag == "vt") {
      Vector2d t;
      in >> t.x() >> t.y();
      out.vt.push_back(t);
    } else if (tag == "f") {
      ObjFace face;
      face.material = material;
      face.object = object;
      std::string corner;
      while (in >> corner) {
        const size_t slash = corner.find('/');
        face.v.push_back(std::stoi(corner.substr(0, slash)));
        face.vt.push_back(slash == std::string::npos ? 0 : std::stoi(corner.substr(slash + 1)));
      }
      out.faces.push_back(face);
    } else if (tag == "usemtl") {
      in >> material;
    } else if (tag == "o") {
      in >> object;
      out.objects.push_back(object);
    } else if (tag == "mtllib") {
      in >> out.mtllib;
    }
  }
  return out;
}

/// Materials of an MTL file: name -> map_Kd ("" when none); Kd per name.
struct ParsedMtl {
  std::map<std::string, std::string> map_kd;
  std::map<std::string, Eigen::Vector3d> kd;
};

ParsedMtl ReadMtl(const fs::path& path) {
  ParsedMtl out;
  std::ifstream f(path);
  EXPECT_TRUE(f.good()) << path;
  std::string line, current;
  while (std::getline(f, line)) {
    std::istringstream in(line);
    std::string tag;
    in >> tag;
    if (tag == "newmtl") {
      in >> current;
      out.map_kd[current] = "";
    } else if (tag == "map_Kd") {
      in >> out.map_kd[current];
    } else if (tag == "Kd") {
      Vector3d kd;
      in >> kd.x() >> kd.y() >> kd.z();
      out.kd[current] = kd;
    }
  }
  return out;
}

/// Two boxes: the scene's, textured on its top and one side, and a plain one beside it.
struct TwoBoxes {
  testing::TexturedBoxScene scene;
  std::vector<BoxModel> boxes;
  std::vector<std::vector<FaceTexture>> textures;
  std::vector<Eigen::Vector3f> colours;

  TwoBoxes() {
    boxes.push_back(scene.box);
    BoxModel other = scene.box;
    other.X_WO.translation() += Vector3d(0, 0.2, 0);
    for (Vector3d& p : other.vertices_W) p += Vector3d(0, 0.2, 0);
    boxes.push_back(other);
    textures.push_back(MakeFaceTextures(scene.box, scene.segments, scene.range, 32));
    textures.emplace_back();
    colours = {Eigen::Vector3f(0.8f, 0.1f, 0.1f), Eigen::Vector3f(0.1f, 0.2f, 0.6f)};
  }
};

TEST(WriteObj, FilesParseBackWithMaterialsTexturesAndOutwardWinding) {
  const TwoBoxes in;
  ASSERT_EQ(in.textures[0].size(), 2u);  // top (4) and side (3)
  const TempDir dir;
  WriteObj(in.boxes, in.textures, in.colours, dir.path().string(), "scene");

  const ParsedObj obj = ReadObj(dir.path() / "scene.obj");
  EXPECT_EQ(obj.mtllib, "scene.mtl");
  EXPECT_EQ(obj.objects, (std::vector<std::string>{"box0", "box1"}));
  ASSERT_EQ(obj.v.size(), 16u);
  EXPECT_EQ(obj.vt.size(), 8u);  // 4 per textured face
  ASSERT_EQ(obj.faces.size(), 12u);
  for (int i = 0; i < 2; ++i) {
    for (int k = 0; k < 8; ++k) {
      EXPECT_LT((obj.v[8 * i + k] - in.boxes[i].vertices_W[k]).norm(), 1e-8);
    }
  }

  const ParsedMtl mtl = ReadMtl(dir.path() / "scene.mtl");
  std::set<std::string> textured;
  for (const ObjFace& f : obj.faces) {
    SCOPED_TRACE(f.object + " " + f.material);
    ASSERT_EQ(f.v.size(), 4u);
    ASSERT_TRUE(mtl.map_kd.contains(f.material));
    const int box = (f.v[0] - 1) / 8;
    EXPECT_EQ(f.object, "box" + std::to_string(box));
    std::vector<Vector3d> p;
    for (int v : f.v) {
      ASSERT_GE(v, 8 * box + 1);
      ASSERT_LE(v, 8 * box + 8);
      p.push_back(obj.v[v - 1]);
    }
    // Newell's normal of the vertex order points away from the box centre: counter-clockwise
    // seen from outside.
    Vector3d n = Vector3d::Zero();
    for (int k = 0; k < 4; ++k) n += p[k].cross(p[(k + 1) % 4]);
    const Vector3d centre = in.boxes[box].X_WO.translation();
    const Vector3d mid = 0.25 * (p[0] + p[1] + p[2] + p[3]);
    EXPECT_GT(n.normalized().dot((mid - centre).normalized()), 1.0 - 1e-9);

    const std::string& png = mtl.map_kd.at(f.material);
    if (png.empty()) {
      EXPECT_EQ(f.material, "box" + std::to_string(box));
      for (int t : f.vt) EXPECT_EQ(t, 0);
      continue;
    }
    // A textured face: its PNG loads at the texture's size, and its texture coordinates put the
    // texture's top-left (corner 0) at the top-left of the image (OBJ's v runs up).
    textured.insert(f.material);
    EXPECT_FALSE(fs::path(png).is_absolute());
    const cv::Mat image = cv::imread((dir.path() / png).string(), cv::IMREAD_COLOR);
    ASSERT_FALSE(image.empty()) << png;
    EXPECT_EQ(image.rows, 32);
    EXPECT_EQ(image.cols, 32);
    const int face = f.material.back() - '0';
    const std::array<Vector3d, 4> corners = FaceCorners(in.boxes[box], face);
    for (int k = 0; k < 4; ++k) {
      ASSERT_GE(f.vt[k], 1);
      const Vector2d t = obj.vt[f.vt[k] - 1];
      int corner = -1;
      for (int c = 0; c < 4; ++c) {
        if ((p[k] - corners[c]).norm() < 1e-8) corner = c;
      }
      ASSERT_GE(corner, 0);
      const bool right = corner == 1 || corner == 2, bottom = corner == 2 || corner == 3;
      EXPECT_NEAR(t.x(), right ? 1 - 0.5 / 32 : 0.5 / 32, 1e-9);
      EXPECT_NEAR(t.y(), bottom ? 0.5 / 32 : 1 - 0.5 / 32, 1e-9);
    }
    // The PNG is the texture.
    for (const FaceTexture& ft : in.textures[box]) {
      if (ft.face == face) {
        EXPECT_EQ(cv::norm(ft.image, image, cv::NORM_INF), 0.0);
      }
    }
  }
  EXPECT_EQ(textured, (std::set<std::string>{"box0_face3", "box0_face4"}));
  EXPECT_TRUE(fs::exists(dir.path() / "scene_box0_face3.png"));
  EXPECT_TRUE(fs::exists(dir.path() / "scene_box0_face4.png"));
  EXPECT_LT((mtl.kd.at("box1") - Vector3d(0.1, 0.2, 0.6)).norm(), 1e-6);
  EXPECT_LT((mtl.kd.at("box0") - Vector3d(0.8, 0.1, 0.1)).norm(), 1e-6);
}

TEST(WriteObj, CreatesTheDirectoryAndDefaultsToGrey) {
  const TwoBoxes in;
  const TempDir dir;
  const fs::path sub = dir.path() / "a" / "b";
  WriteObj(in.boxes, {}, {}, sub.string());
  EXPECT_TRUE(fs::exists(sub / "models.obj"));
  const ParsedObj obj = ReadObj(sub / "models.obj");
  EXPECT_EQ(obj.faces.size(), 12u);
  EXPECT_TRUE(obj.vt.empty());
  const ParsedMtl mtl = ReadMtl(sub / "models.mtl");
  EXPECT_EQ(mtl.map_kd.size(), 2u);
  EXPECT_LT((mtl.kd.at("box0") - Vector3d::Constant(0.7)).norm(), 1e-6);
}

TEST(WriteObj, BadInputAndUnwritableDirectoryThrow) {
  const TwoBoxes in;
  const TempDir dir;
  EXPECT_THROW(WriteObj(in.boxes, {{}}, {}, dir.path().string()), InputError);
  EXPECT_THROW(WriteObj(in.boxes, {}, {Eigen::Vector3f::Ones()}, dir.path().string()), InputError);
  // A regular file where the directory should be.
  const fs::path file = dir.path() / "not_a_dir";
  std::ofstream(file) << "x";
  try {
    WriteObj(in.boxes, in.textures, in.colours, (file / "sub").string());
    FAIL() << "no exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("not_a_dir"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hgrasp::model
