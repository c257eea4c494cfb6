#include "robot/calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/error.h"
#include "common/geometry.h"
#include "common/paths.h"
#include "tests/common/yaml_bombs.h"

namespace hgrasp::robot {
namespace {

namespace fs = std::filesystem;
using Eigen::Vector3d;

std::string TempPath(const std::string& name) {
  return (fs::path(::testing::TempDir()) / name).string();
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

// --- intrinsics ------------------------------------------------------------------------------

TEST(StereoIntrinsicsTest, SimCamerasAreThoseMujocoRenders) {
  const StereoIntrinsics s = LoadStereoIntrinsics(ResolveDataPath("calibration/sim/cameras.yaml"));
  const PinholeCamera expected = PinholeCamera::FromFovy(320, 240, DegToRad(55.0));
  for (const PinholeCamera* c : {&s.left, &s.right}) {
    EXPECT_EQ(c->width, 320);
    EXPECT_EQ(c->height, 240);
    EXPECT_EQ(c->fx, expected.fx);  // written with full precision: exactly
    EXPECT_EQ(c->fy, expected.fy);
    EXPECT_NEAR(c->fx, 120.0 / std::tan(DegToRad(27.5)), 1e-12);
    EXPECT_EQ(c->cx, 159.5);
    EXPECT_EQ(c->cy, 119.5);
  }
}

TEST(StereoIntrinsicsTest, FlowStyleAndDistinctCameras) {
  const std::string path = TempPath("hgrasp_cameras_flow.yaml");
  WriteText(path,
            "left: {width: 640, height: 480, fx: 500, fy: 501.5, cx: 319.25, cy: 240}\n"
            "right: {cy: 10, cx: 20, fy: 490.5, fx: 490, height: 480, width: 640}\n");
  const StereoIntrinsics s = LoadStereoIntrinsics(path);
  EXPECT_EQ(s.left.width, 640);
  EXPECT_EQ(s.left.height, 480);
  EXPECT_EQ(s.left.fx, 500.0);
  EXPECT_EQ(s.left.fy, 501.5);
  EXPECT_EQ(s.left.cx, 319.25);
  EXPECT_EQ(s.left.cy, 240.0);
  EXPECT_EQ(s.right.width, 640);
  EXPECT_EQ(s.right.height, 480);
  EXPECT_EQ(s.right.fx, 490.0);
  EXPECT_EQ(s.right.fy, 490.5);
  EXPECT_EQ(s.right.cx, 20.0);
  EXPECT_EQ(s.right.cy, 10.0);
  fs::remove(path);
}

TEST(StereoIntrinsicsTest, MissingFileNamesIt) {
  const std::string path = "/nonexistent/cameras.yaml";
  try {
    LoadStereoIntrinsics(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.value(), path);
    EXPECT_NE(std::string(e.what()).find("a readable camera intrinsics file"), std::string::npos);
  }
}

// --- laser calibration: the plane ------------------------------------------------------------

void ExpectPlane(const Plane& p, const Vector3d& n, double d) {
  EXPECT_LE((p.n - n).cwiseAbs().maxCoeff(), 1e-15) << p.n.transpose() << " vs " << n.transpose();
  EXPECT_NEAR(p.d, d, 1e-15);
}

TEST(LaserCalibrationTest, PlaneAboutZThroughTheOrigin) {
  const LaserCalibration c;  // axis z, point 0, normal0 y, offset 0, 0.01 deg per count
  ExpectPlane(c.PlaneH(0), Vector3d(0, 1, 0), 0.0);       // the plane y = 0
  ExpectPlane(c.PlaneH(9000), Vector3d(-1, 0, 0), 0.0);   // 90 deg: x = 0
  ExpectPlane(c.PlaneH(-9000), Vector3d(1, 0, 0), 0.0);   // -90 deg
  ExpectPlane(c.PlaneH(18000), Vector3d(0, -1, 0), 0.0);  // 180 deg
  const double h = std::sqrt(0.5);
  ExpectPlane(c.PlaneH(4500), Vector3d(-h, h, 0), 0.0);  // 45 deg
  ExpectPlane(c.PlaneH(-4500), Vector3d(h, h, 0), 0.0);
}

TEST(LaserCalibrationTest, PlaneWithAxisPointAndOffset) {
  LaserCalibration c;
  c.point_H = Vector3d(1, 0, 0);
  c.offset_m = 0.01;
  // Count 0: normal y, the plane y = 0.01 (0.01 m from the axis along the normal).
  ExpectPlane(c.PlaneH(0), Vector3d(0, 1, 0), -0.01);
  // 90 deg: normal -x, the plane -x + 0.99 = 0, i.e. x = 0.99.
  ExpectPlane(c.PlaneH(9000), Vector3d(-1, 0, 0), 0.99);
  // -90 deg: normal +x, the plane x = 1.01.
  ExpectPlane(c.PlaneH(-9000), Vector3d(1, 0, 0), -1.01);
  // The axis's height along z does not matter.
  c.point_H = Vector3d(1, 0, 5);
  ExpectPlane(c.PlaneH(9000), Vector3d(-1, 0, 0), 0.99);
}

TEST(LaserCalibrationTest, PlaneAboutAnotherAxisAndResolution) {
  LaserCalibration c;
  c.axis_H = Vector3d(1, 0, 0);
  c.normal0_H = Vector3d(0, 0, 1);
  c.point_H = Vector3d(0, 0.2, 0.3);
  c.offset_m = -0.02;
  c.rad_per_count = DegToRad(0.5);
  // 180 counts = 90 deg about x: z turns into -y. Plane -y + 0.2 + 0.02 = 0.
  ExpectPlane(c.PlaneH(180), Vector3d(0, -1, 0), 0.22);
}

TEST(LaserCalibrationTest, EveryPlaneKeepsItsDistanceFromTheAxis) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_int_distribution<std::int32_t> count(-36000, 36000);
  for (int trial = 0; trial < 100; ++trial) {
    LaserCalibration c;
    c.axis_H = Vector3d(u(rng), u(rng), u(rng)).normalized();
    c.normal0_H = c.axis_H.cross(Vector3d(u(rng), u(rng), u(rng))).normalized();
    c.point_H = 0.1 * Vector3d(u(rng), u(rng), u(rng));
    c.offset_m = 0.01 * u(rng);
    const Plane p = c.PlaneH(count(rng));
    EXPECT_NEAR(p.n.norm(), 1.0, 1e-15);
    EXPECT_NEAR(p.n.dot(c.axis_H), 0.0, 1e-15);  // the plane stays parallel to the axis
    for (double t : {-1.0, 0.0, 2.0}) {          // every point of the axis is offset_m away
      EXPECT_NEAR(p.SignedDistance(c.point_H + t * c.axis_H), -c.offset_m, 1e-15);
    }
  }
}

// --- laser calibration: files ----------------------------------------------------------------

LaserCalibration RandomCalibration(std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  LaserCalibration c;
  c.axis_H = Vector3d(u(*rng), u(*rng), u(*rng)).normalized();
  c.normal0_H = c.axis_H.cross(Vector3d(u(*rng), u(*rng), u(*rng))).normalized();
  c.point_H = Vector3d(u(*rng), u(*rng), u(*rng)) / 3.0;
  c.offset_m = u(*rng) * 1e-3;
  c.rad_per_count = 2.0 * kPi / 36000.0 * (1.0 + 1e-3 * u(*rng));
  c.rms_residual_px = 0.5 * (1.0 + u(*rng));
  c.counts_used = std::uniform_int_distribution<int>(0, 9000)(*rng);
  return c;
}

TEST(StereoIntrinsicsTest, SaveLoadRoundTripIsExactWithTheNoteAsComments) {
  const std::string path = TempPath("hgrasp_cameras_roundtrip.yaml");
  StereoIntrinsics s;
  s.left = {320, 240, 232.10000000000002, 231.7, 158.29999999999998, 121.2};
  s.right = {320, 240, 1.0 / 3.0 * 690.0, 229.0, 160.1, 1e-3 + 119.0};
  SaveStereoIntrinsics(s, path, "measured by a test\nsecond line");
  const std::string text = ReadText(path);
  EXPECT_NE(text.find("# measured by a test\n# second line\n"), std::string::npos) << text;
  const StereoIntrinsics back = LoadStereoIntrinsics(path);
  for (const auto& [got, want] : {std::pair{back.left, s.left}, {back.right, s.right}}) {
    EXPECT_EQ(got.width, want.width);
    EXPECT_EQ(got.height, want.height);
    EXPECT_EQ(got.fx, want.fx);
    EXPECT_EQ(got.fy, want.fy);
    EXPECT_EQ(got.cx, want.cx);
    EXPECT_EQ(got.cy, want.cy);
  }
  fs::remove(path);
}

TEST(StereoIntrinsicsTest, SavingCamerasTheReaderWouldRefuseWritesNothing) {
  const std::string path = TempPath("hgrasp_cameras_bad.yaml");
  fs::remove(path);
  StereoIntrinsics s;
  s.left = {320, 240, 230, 230, 159.5, 119.5};
  s.right = {320, 240, 300, 300, 159.5, 119.5};  // 30% off the left: not the same lens
  EXPECT_THROW(SaveStereoIntrinsics(s, path), InputError);
  EXPECT_FALSE(fs::exists(path));
}

TEST(LaserCalibrationTest, SaveLoadRoundTripIsExact) {
  const std::string path = TempPath("hgrasp_laser_roundtrip.yaml");
  std::mt19937 rng(2002);
  for (int trial = 0; trial < 20; ++trial) {
    const LaserCalibration c = trial == 0 ? LaserCalibration{} : RandomCalibration(&rng);
    SaveLaserCalibration(c, path);
    const LaserCalibration back = LoadLaserCalibration(path);
    EXPECT_EQ(back, c) << ReadText(path);
    EXPECT_EQ(back.axis_H, c.axis_H);
    EXPECT_EQ(back.point_H, c.point_H);
    EXPECT_EQ(back.normal0_H, c.normal0_H);
    EXPECT_EQ(back.offset_m, c.offset_m);
    EXPECT_EQ(back.rad_per_count, c.rad_per_count);
    EXPECT_EQ(back.rms_residual_px, c.rms_residual_px);
    EXPECT_EQ(back.counts_used, c.counts_used);
  }
  EXPECT_FALSE(fs::exists(path + ".tmp"));
  fs::remove(path);
}

TEST(LaserCalibrationTest, SavedFileExplainsItself) {
  const std::string path = TempPath("hgrasp_laser_header.yaml");
  SaveLaserCalibration(LaserCalibration{}, path);
  const std::string text = ReadText(path);
  EXPECT_EQ(text.rfind("# ", 0), 0u) << text;  // starts with the header comment
  for (const char* word :
       {"camera_bracket", "frame:", "axis_H:", "point_H:", "normal0_H:", "offset_m:",
        "rad_per_count:", "rms_residual_px:", "counts_used:", "(m)", "rad"}) {
    EXPECT_NE(text.find(word), std::string::npos) << word;
  }
  EXPECT_NE(text.find("rad_per_count: 0.0001745329251994329"), std::string::npos) << text;
  fs::remove(path);
}

TEST(LaserCalibrationTest, UnwritablePathThrowsAndWritesNothing) {
  const std::string path = TempPath("hgrasp_no_such_dir/laser.yaml");
  try {
    SaveLaserCalibration(LaserCalibration{}, path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path + ".tmp"));
}

TEST(LaserCalibrationTest, MissingFileNamesIt) {
  const std::string path = "/nonexistent/laser.yaml";
  try {
    LoadLaserCalibration(path);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), "");
    EXPECT_EQ(e.value(), path);
    EXPECT_NE(std::string(e.what()).find("a readable laser calibration file"), std::string::npos);
  }
}

TEST(LaserCalibrationDeathTest, SavingAnInconsistentCalibrationAborts) {
  LaserCalibration c;
  c.normal0_H = Vector3d(0, 0.6, 0.8);  // unit, but 37 deg from the axis
  EXPECT_DEATH(SaveLaserCalibration(c, TempPath("hgrasp_never_written.yaml")), "normal0_H");
  c = LaserCalibration{};
  c.rad_per_count = 0.0;
  EXPECT_DEATH(SaveLaserCalibration(c, TempPath("hgrasp_never_written.yaml")), "rad_per_count");
}

// --- bad files -------------------------------------------------------------------------------

struct BadFile {
  const char* file;   // in tests/data/calibration/
  int line;           // 1-based; 0: no line
  const char* field;  // as InputError::field()
  const char* value;  // as InputError::value(); "" for missing or empty
};

std::ostream& operator<<(std::ostream& os, const BadFile& b) { return os << b.file; }

class BadCalibrationFileTest : public ::testing::TestWithParam<BadFile> {};

TEST_P(BadCalibrationFileTest, ThrowsInputErrorNamingFileLineFieldAndValue) {
  const BadFile& b = GetParam();
  const std::string path = std::string(HGRASP_TEST_DATA) + "/calibration/" + b.file;
  ASSERT_TRUE(fs::exists(path)) << path;
  const bool laser = std::string(b.file).rfind("bad_laser_", 0) == 0;
  try {
    if (laser) {
      LoadLaserCalibration(path);
    } else {
      LoadStereoIntrinsics(path);
    }
    FAIL() << "expected InputError for " << path;
  } catch (const InputError& e) {
    const std::string what = e.what();
    const std::string where = b.line > 0 ? path + ":" + std::to_string(b.line) : path;
    EXPECT_EQ(e.file(), where) << what;
    EXPECT_EQ(e.field(), b.field) << what;
    EXPECT_EQ(e.value(), b.value) << what;
    EXPECT_EQ(what.rfind(where + ": ", 0), 0u) << what;  // "FILE:LINE: ..."
    EXPECT_NE(what.find(std::string(": ") + b.field + ": "), std::string::npos) << what;
    const std::string value =
        std::string(b.value).empty() ? "missing or empty" : "got '" + std::string(b.value) + "'";
    EXPECT_NE(what.find(value), std::string::npos) << what;
    EXPECT_NE(what.find("; expected "), std::string::npos) << what;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Laser, BadCalibrationFileTest,
    ::testing::Values(
        BadFile{"bad_laser_unknown_key.yaml", 10, "scale", "scale"},
        BadFile{"bad_laser_missing_field.yaml", 2, "offset_m", ""},
        BadFile{"bad_laser_wrong_type.yaml", 6, "offset_m", "small"},
        BadFile{"bad_laser_quoted_number.yaml", 7, "rad_per_count", "0.00017453292519943296"},
        BadFile{"bad_laser_axis_not_unit.yaml", 3, "axis_H", "[0, 0, 1.001]"},
        BadFile{"bad_laser_normal_not_unit.yaml", 5, "normal0_H", "[0, 0.9, 0]"},
        BadFile{"bad_laser_not_perpendicular.yaml", 5, "normal0_H", "[0, 0.6, 0.8]"},
        BadFile{"bad_laser_rad_per_count.yaml", 7, "rad_per_count", "-0.00017453292519943296"},
        BadFile{"bad_laser_zero_rad_per_count.yaml", 7, "rad_per_count", "0"},
        BadFile{"bad_laser_frame.yaml", 2, "frame", "camera_left_optical"},
        BadFile{"bad_laser_vector_count.yaml", 4, "point_H", "[0.03, 0.06]"},
        BadFile{"bad_laser_counts_used.yaml", 9, "counts_used", "12.5"},
        BadFile{"bad_laser_negative_rms.yaml", 8, "rms_residual_px", "-0.1"},
        BadFile{"bad_laser_duplicate_key.yaml", 10, "offset_m", "offset_m"},
        BadFile{"bad_laser_syntax.yaml", 4, "YAML syntax", "point_H: [0.03, 0, 0.06]"},
        BadFile{"bad_laser_empty.yaml", 0, "top level", ""},
        BadFile{"bad_laser_not_map.yaml", 2, "top level",
                "[{frame: camera_bracket}, {axis_H: [0, 0, 1]}]"}),
    [](const ::testing::TestParamInfo<BadFile>& info) {
      std::string name = info.param.file;
      return name.substr(0, name.find('.'));
    });

INSTANTIATE_TEST_SUITE_P(
    Cameras, BadCalibrationFileTest,
    ::testing::Values(BadFile{"bad_cameras_unknown_key.yaml", 9, "left.k1", "k1"},
                      BadFile{"bad_cameras_missing_right.yaml", 2, "right", ""},
                      BadFile{"bad_cameras_missing_fy.yaml", 10, "right.fy", ""},
                      BadFile{"bad_cameras_zero_fx.yaml", 5, "left.fx", "0"},
                      BadFile{"bad_cameras_negative_width.yaml", 10, "right.width", "-320"},
                      BadFile{"bad_cameras_fractional_height.yaml", 4, "left.height", "240.5"},
                      BadFile{"bad_cameras_wrong_type.yaml", 7, "left.cx", "centre"},
                      BadFile{"bad_cameras_cx_outside.yaml", 14, "right.cx", "400"},
                      BadFile{"bad_cameras_not_map.yaml", 2, "left",
                              "[320, 240, 230.5, 230.5, 159.5, 119.5]"}),
    [](const ::testing::TestParamInfo<BadFile>& info) {
      std::string name = info.param.file;
      return name.substr(0, name.find('.'));
    });

// Hostile and careless files (issue 15): each loaded, or crashed the loader, before.
TEST(CalibrationHostileTest, CamerasNoRealHeadHasAreRefused) {
  const std::string good = "{width: 320, height: 240, fx: 230.5, fy: 230.5, cx: 159.5, cy: 119.5}";
  const struct {
    std::string left, right, field;
  } cases[] = {
      {"{width: 320, height: 240, fx: 230.5, fy: 461, cx: 159.5, cy: 119.5}", good, "left.fy"},
      {"{width: 320, height: 240, fx: 5, fy: 5, cx: 159.5, cy: 119.5}", good, "left.fx"},
      {"{width: 320, height: 240, fx: 9000, fy: 9000, cx: 159.5, cy: 119.5}", good, "left.fx"},
      {good, "{width: 640, height: 480, fx: 461, fy: 461, cx: 319.5, cy: 239.5}", "right"},
      {good, "{width: 320, height: 240, fx: 300, fy: 300, cx: 159.5, cy: 119.5}", "right.fx"},
  };
  for (const auto& c : cases) {
    try {
      ParseStereoIntrinsics("left: " + c.left + "\nright: " + c.right + "\n", "cams.yaml");
      ADD_FAILURE() << "accepted: " << c.left << " / " << c.right;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), c.field) << e.what();
    }
  }
}

TEST(CalibrationHostileTest, LaserOffTheHeadIsRefused) {
  const std::string text = ReadText(ResolveDataPath("calibration/sim/laser.yaml"));
  for (const auto& [key, bad] : std::vector<std::pair<std::string, std::string>>{
           {"point_H:", "point_H: [10, 0, 0]"}, {"offset_m:", "offset_m: 1e300"}}) {
    std::string changed;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      changed += (line.rfind(key, 0) == 0 ? bad : line) + "\n";
    }
    try {
      ParseLaserCalibration(changed, "laser.yaml");
      ADD_FAILURE() << "accepted " << bad;
    } catch (const InputError& e) {
      EXPECT_EQ(e.field(), key.substr(0, key.size() - 1)) << e.what();
    }
  }
}

// A self-referencing alias crashed every loader; a billion laughs ran for 40 s in 2 GB.
TEST(CalibrationHostileTest, AliasBombsAreRefused) {
  // Each shaped so that the loader reaches the alias and shows it in its message.
  const std::string cameras[] = {"right: {width: 1}\nleft: &n [*n]\n",
                                 testing::BillionLaughs("right", "left")};
  const std::string lasers[] = {"frame: camera_bracket\naxis_H: &n [*n]\n",
                                "frame: camera_bracket\n" + testing::BillionLaughs("point_H", "axis_H")};
  const std::string path = TempPath("hgrasp_alias_bomb.yaml");
  for (const std::string& text : cameras) {
    WriteText(path, text);
    EXPECT_THROW(LoadStereoIntrinsics(path), InputError) << text;
  }
  for (const std::string& text : lasers) {
    WriteText(path, text);
    EXPECT_THROW(LoadLaserCalibration(path), InputError) << text;
  }
  fs::remove(path);
}

}  // namespace
}  // namespace hgrasp::robot
