#include "robot/calibration.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <string_view>
#include <system_error>
#include <vector>

#include "common/error.h"
#include "common/write_file.h"
#include "common/yaml_file.h"
#include "common/yaml_reader.h"
#include "common/yaml_util.h"

namespace hgrasp::robot {
namespace {

// The frame a laser calibration is expressed in.
constexpr char kFrameH[] = "camera_bracket";
// Tolerance on the unit length of axis_H and normal0_H.
constexpr double kUnitTolerance = 1e-6;
// The two cameras' focal lengths, and fy against fx, agree within this ratio.
constexpr double kMaxFocalRatio = 1.1;
// Horizontal fields of view of real lenses (deg): 10 (a long lens) to 150 (a fisheye's edge).
constexpr double kMinFovDeg = 10.0, kMaxFovDeg = 150.0;
// The laser's axis and plane are on the head (m).
constexpr double kMaxLaserReach = 0.5;

// Strict scalars and message helpers: common/yaml_util.h.
using yaml::IsQuoted;
using yaml::Join;
using yaml::Keys;
using yaml::OneOf;
using yaml::ParseInteger;
using yaml::ParseNumber;
using yaml::QuoteHint;
using yaml::Render;

// %.17g: enough significant digits for any double to read back exactly.
std::string Exact(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// The reader: every check names "FILE:LINE", the field path, the value and what was expected.

using yaml::Entries;

// The common reader (common/yaml_reader.h) and what these files need beyond it.
class Reader : public yaml::Reader {
 public:
  using yaml::Reader::Reader;

  // The file's single YAML document, a map.
  YAML::Node Root(const std::string& text, const std::string& expected) const {
    const YAML::Node root = yaml::LoadDocument(text, path(), expected);
    if (!root.IsMap()) Fail(root, "top level", expected);
    return root;
  }

  long long Integer(const YAML::Node& n, const std::string& field,
                    const std::string& expected) const {
    const std::optional<long long> v = ParseInteger(n);
    if (!v) Fail(n, field, expected + QuoteHint(n));
    return *v;
  }

  Eigen::Vector3d Vector3(const YAML::Node& n, const std::string& field,
                          const std::string& expected) const {
    return Numbers(n, field, 3, expected);
  }
};

// Runs `parse`, turning anything yaml-cpp throws beyond a syntax error into an InputError.
template <typename Parse>
auto Guarded(const std::string& path, const std::string& expected, Parse parse) {
  try {
    return parse();
  } catch (const YAML::Exception& e) {
    const std::string where = e.mark.line < 0 ? path : path + ":" + std::to_string(e.mark.line + 1);
    throw InputError(where, "", e.msg, expected);
  }
}

// ---------------------------------------------------------------------------------------------
// Intrinsics.

PinholeCamera ParseCamera(const Reader& r, const YAML::Node& n, const std::string& field) {
  const Entries e = r.MapOf(n, field, {"width", "height", "fx", "fy", "cx", "cy"},
                            "a camera: a map with width, height, fx, fy, cx, cy");
  PinholeCamera c;
  const auto size = [&](std::string_view key, const std::string& what) {
    const std::string expected = "the image " + what + ", a positive integer number of pixels";
    const YAML::Node& v = r.Require(e, n, field, key, expected);
    const long long pixels = r.Integer(v, Join(field, key), expected);
    if (pixels <= 0 || pixels > 100000) r.Fail(v, Join(field, key), expected);
    return static_cast<int>(pixels);
  };
  c.width = size("width", "width");
  c.height = size("height", "height");

  const auto focal = [&](std::string_view key, const char* axis) {
    const std::string expected =
        std::string("a positive focal length along ") + axis + " in pixels";
    const YAML::Node& v = r.Require(e, n, field, key, expected);
    const double f = r.Number(v, Join(field, key), expected);
    if (f <= 0.0) r.Fail(v, Join(field, key), expected);
    return f;
  };
  c.fx = focal("fx", "u");
  c.fy = focal("fy", "v");
  // A real camera: its pixels square within 10 % (PAL digitised at 320 x 240 is square within
  // 2 %), its horizontal field of view that of a lens one can buy.
  const double aspect = c.fy / c.fx;
  if (aspect < 1.0 / kMaxFocalRatio || aspect > kMaxFocalRatio) {
    r.Fail(n["fy"], Join(field, "fy"),
           "a focal length within 10% of fx (square pixels; fx is " + Exact(c.fx) + ")");
  }
  const double hfov_deg = 2.0 * std::atan(0.5 * c.width / c.fx) * 180.0 / kPi;
  if (hfov_deg < kMinFovDeg || hfov_deg > kMaxFovDeg) {
    r.Fail(n["fx"], Join(field, "fx"),
           "a focal length giving a horizontal field of view of " +
               std::to_string(int(kMinFovDeg)) + "-" + std::to_string(int(kMaxFovDeg)) +
               " deg over the image's " + std::to_string(c.width) + " pixels (this one gives " +
               std::to_string(hfov_deg) + " deg)");
  }

  const auto centre = [&](std::string_view key, const char* axis, int pixels) {
    const std::string expected = std::string("the principal point's ") + axis +
                                 " in pixels, inside the image (-0.5 to " +
                                 std::to_string(pixels - 1) + ".5)";
    const YAML::Node& v = r.Require(e, n, field, key, expected);
    const double x = r.Number(v, Join(field, key), expected);
    if (x < -0.5 || x > pixels - 0.5) r.Fail(v, Join(field, key), expected);
    return x;
  };
  c.cx = centre("cx", "u", c.width);
  c.cy = centre("cy", "v", c.height);
  return c;
}

// ---------------------------------------------------------------------------------------------
// Laser.

// Why `c` cannot be saved or was not loaded; empty when it is consistent. `field` is set to the
// offending field.
std::string LaserProblem(const LaserCalibration& c, std::string* field) {
  const auto finite = [](const Eigen::Vector3d& v) { return v.allFinite(); };
  if (!finite(c.axis_H) || std::abs(c.axis_H.norm() - 1.0) > kUnitTolerance) {
    *field = "axis_H";
    return "a unit vector (length 1 within 1e-6)";
  }
  if (!finite(c.point_H)) {
    *field = "point_H";
    return "a finite point";
  }
  if (!finite(c.normal0_H) || std::abs(c.normal0_H.norm() - 1.0) > kUnitTolerance) {
    *field = "normal0_H";
    return "a unit vector (length 1 within 1e-6)";
  }
  // A lens a little off square on its mount turns the sheet's normal on a cone about the axis:
  // the normal need not be perpendicular to the axis, but a sheet whose normal lies within
  // 60 deg of its turning axis is no stripe scanner.
  const double cos_angle = c.axis_H.dot(c.normal0_H);
  if (std::abs(cos_angle) > 0.5) {
    *field = "normal0_H";
    char dot[32];
    std::snprintf(dot, sizeof dot, "%.3g", cos_angle);
    return std::string("a normal at least 60 deg from axis_H (axis_H . normal0_H is ") + dot + ")";
  }
  if (c.point_H.norm() > kMaxLaserReach) {
    *field = "point_H";
    return "a point on the head, within 0.5 m of the camera bracket";
  }
  if (!std::isfinite(c.offset_m) || std::abs(c.offset_m) > kMaxLaserReach) {
    *field = "offset_m";
    return "a distance of the plane from its axis within 0.5 m (the laser is on the head)";
  }
  if (!std::isfinite(c.rad_per_count) || c.rad_per_count <= 0.0) {
    *field = "rad_per_count";
    return "a positive encoder resolution in rad per count";
  }
  if (!std::isfinite(c.rms_residual_px) || c.rms_residual_px < 0.0) {
    *field = "rms_residual_px";
    return "a non-negative RMS residual in pixels";
  }
  if (c.counts_used < 0) {
    *field = "counts_used";
    return "a non-negative number of encoder counts";
  }
  return "";
}

LaserCalibration ParseLaser(const std::string& text, const std::string& path) {
  const Reader r(path);
  const std::string top_expected =
      "a laser calibration: a map with frame, axis_H, point_H, normal0_H, offset_m, "
      "rad_per_count, rms_residual_px, counts_used";
  const YAML::Node root = r.Root(text, top_expected);
  const Entries e = r.MapOf(root, "",
                            {"frame", "axis_H", "point_H", "normal0_H", "offset_m", "rad_per_count",
                             "rms_residual_px", "counts_used"},
                            top_expected);
  std::map<std::string, YAML::Node> nodes;  // by field, for the checks across fields
  const auto get = [&](const std::string& key, const std::string& expected) {
    const YAML::Node& n = r.Require(e, root, "", key, expected);
    nodes.emplace(key, n);
    return n;
  };

  const std::string frame_expected = std::string("the frame ") + kFrameH;
  const YAML::Node frame = get("frame", frame_expected);
  if (r.Text(frame, "frame", frame_expected) != kFrameH) r.Fail(frame, "frame", frame_expected);

  LaserCalibration c;
  const std::string axis_expected = "the unit rotation axis in H, as [x, y, z]";
  c.axis_H = r.Vector3(get("axis_H", axis_expected), "axis_H", axis_expected);
  const std::string point_expected = "a point on the rotation axis in H in m, as [x, y, z]";
  c.point_H = r.Vector3(get("point_H", point_expected), "point_H", point_expected);
  const std::string normal_expected = "the plane's unit normal at count 0 in H, as [x, y, z]";
  c.normal0_H = r.Vector3(get("normal0_H", normal_expected), "normal0_H", normal_expected);
  const std::string offset_expected = "the plane's distance from the axis in m";
  c.offset_m = r.Number(get("offset_m", offset_expected), "offset_m", offset_expected);
  const std::string rpc_expected = "a positive encoder resolution in rad per count";
  c.rad_per_count = r.Number(get("rad_per_count", rpc_expected), "rad_per_count", rpc_expected);
  const std::string rms_expected = "a non-negative RMS residual in pixels";
  c.rms_residual_px =
      r.Number(get("rms_residual_px", rms_expected), "rms_residual_px", rms_expected);
  const std::string used_expected = "a non-negative number of encoder counts";
  const YAML::Node used = get("counts_used", used_expected);
  const long long counts_used = r.Integer(used, "counts_used", used_expected);
  if (counts_used < 0 || counts_used > 2147483647LL) r.Fail(used, "counts_used", used_expected);
  c.counts_used = static_cast<int>(counts_used);

  std::string field;
  const std::string expected = LaserProblem(c, &field);
  if (!expected.empty()) r.Fail(nodes.at(field), field, expected);
  return c;
}

}  // namespace

StereoIntrinsics LoadStereoIntrinsics(const std::string& path) {
  return ParseStereoIntrinsics(yaml::ReadText(path, "a readable camera intrinsics file"), path);
}

StereoIntrinsics ParseStereoIntrinsics(const std::string& text, const std::string& path) {
  const std::string top_expected =
      "camera intrinsics: a map with left and right, each {width, height, fx, fy, cx, cy}";
  return Guarded(path, top_expected, [&] {
    const Reader r(path);
    const YAML::Node root = r.Root(text, top_expected);
    const Entries e = r.MapOf(root, "", {"left", "right"}, top_expected);
    StereoIntrinsics s;
    s.path = path;
    const YAML::Node& left = r.Require(e, root, "", "left", "the left camera's intrinsics");
    const YAML::Node& right = r.Require(e, root, "", "right", "the right camera's intrinsics");
    s.left = ParseCamera(r, left, "left");
    s.right = ParseCamera(r, right, "right");
    // The two cameras of one head: the same frame grabber, the same lens model.
    if (s.right.width != s.left.width || s.right.height != s.left.height) {
      r.Fail(right, "right", "the left camera's image size, " + std::to_string(s.left.width) +
                                 " x " + std::to_string(s.left.height) + " (one frame grabber)");
    }
    const double ratio = s.right.fx / s.left.fx;
    if (ratio < 1.0 / kMaxFocalRatio || ratio > kMaxFocalRatio) {
      r.Fail(right, "right.fx",
             "a focal length within " + std::to_string(int(std::lround(100 * (kMaxFocalRatio - 1)))) +
                 "% of the left camera's (the same lens on both)");
    }
    return s;
  });
}

void SaveStereoIntrinsics(const StereoIntrinsics& s, const std::string& path,
                          const std::string& note) {
  const auto camera = [](const PinholeCamera& c) {
    std::string line = "{width: ";
    line.append(std::to_string(c.width)).append(", height: ").append(std::to_string(c.height));
    line.append(", fx: ").append(Exact(c.fx)).append(", fy: ").append(Exact(c.fy));
    line.append(", cx: ").append(Exact(c.cx)).append(", cy: ").append(Exact(c.cy));
    return line.append("}");
  };
  std::string text =
      "# hgrasp camera intrinsics: each camera an ideal pinhole (no distortion), in pixels, with\n"
      "# the centre of pixel (column i, row j) at (i, j) (src/common/pinhole_camera.h).\n"
      "# Read by hgrasp::robot::LoadStereoIntrinsics.\n";
  std::istringstream lines(note);
  for (std::string line; std::getline(lines, line);) text.append("# ").append(line).append("\n");
  text.append("left: ").append(camera(s.left)).append("\n");
  text.append("right: ").append(camera(s.right)).append("\n");
  // What is written must read back: the reader's checks, before the file exists.
  ParseStereoIntrinsics(text, path);
  const std::string expected = "a writable path for the camera intrinsics";
  if (path.empty()) throw InputError("", "output file", "", expected);
  try {
    WriteFileWhole(path, text);
  } catch (const std::runtime_error& e) {
    throw InputError(path, "", path, expected + ": " + e.what());
  }
}

Plane LaserCalibration::PlaneH(std::int32_t count) const {
  const double theta = rad_per_count * static_cast<double>(count);
  Plane plane;
  plane.n = Eigen::AngleAxisd(theta, axis_H) * normal0_H;
  plane.d = -plane.n.dot(point_H) - offset_m;
  return plane;
}

LaserCalibration LoadLaserCalibration(const std::string& path) {
  return ParseLaserCalibration(yaml::ReadText(path, "a readable laser calibration file"), path);
}

LaserCalibration ParseLaserCalibration(const std::string& text, const std::string& path) {
  return Guarded(path, "a laser calibration file", [&] { return ParseLaser(text, path); });
}

void SaveLaserCalibration(const LaserCalibration& c, const std::string& path) {
  std::string field;
  const std::string problem = LaserProblem(c, &field);
  HGRASP_DEMAND_MSG(problem.empty(), "laser calibration " + field + ": expected " + problem);

  const auto vec = [](const Eigen::Vector3d& v) {
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "[" + std::string.
    std::string s("[");
    s.append(Exact(v.x())).append(", ").append(Exact(v.y())).append(", ").append(Exact(v.z()));
    return s.append("]");
  };
  std::string text;
  text +=
      "# hgrasp laser calibration: the laser's light plane turning about an axis fixed in the\n"
      "# head. Frame H is the URDF link camera_bracket (models/humanoid.urdf), the head platform\n"
      "# carrying the cameras and the laser. Lengths in m, angles in rad. At encoder count e:\n"
      "#   theta = rad_per_count * e\n"
      "#   n(e) = Rot(axis_H, theta) * normal0_H\n"
      "#   light plane = {p in H : n(e) . (p - point_H) - offset_m = 0}\n"
      "# frame:           the frame of the vectors below, always camera_bracket\n"
      "# axis_H:          unit direction of the rotation axis, in H\n"
      "# point_H:         a point on the rotation axis, in H (m)\n"
      "# normal0_H:       unit normal of the plane at count 0 (turning on a cone about axis_H), in "
      "H\n"
      "# offset_m:        signed distance of the plane from the axis along n(e) (m)\n"
      "# rad_per_count:   encoder resolution (rad per count)\n"
      "# rms_residual_px: RMS residual of the fit (pixels), for information\n"
      "# counts_used:     how many encoder counts the fit used, for information\n";
  text += std::string("frame: ") + kFrameH + "\n";
  text += "axis_H: " + vec(c.axis_H) + "\n";
  text += "point_H: " + vec(c.point_H) + "\n";
  text += "normal0_H: " + vec(c.normal0_H) + "\n";
  text += "offset_m: " + Exact(c.offset_m) + "\n";
  text += "rad_per_count: " + Exact(c.rad_per_count) + "\n";
  text += "rms_residual_px: " + Exact(c.rms_residual_px) + "\n";
  text += "counts_used: " + std::to_string(c.counts_used) + "\n";

  // Written whole or not at all: a temporary file next to the target, renamed into place.
  namespace fs = std::filesystem;
  const std::string expected = "a writable path for the laser calibration";
  if (path.empty()) throw InputError("", "output file", "", expected);
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, "", path, expected + ": " + std::strerror(errno));
    out << text;
    out.close();
    if (!out) {
      std::error_code ignored;
      fs::remove(tmp, ignored);
      throw InputError(path, "", path, expected + ": write failed");
    }
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    fs::remove(tmp, ignored);
    throw InputError(path, "", path, expected + ": " + ec.message());
  }
}

}  // namespace hgrasp::robot
