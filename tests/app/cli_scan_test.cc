// `hgrasp scan` and `hgrasp calibrate laser` as a user runs them: bad calibration files and usage
// errors exit 2 with a message naming the file, the field and the value, before any simulation
// runs and without writing output.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "tests/app/cli_util.h"

namespace {

using hgrasp::testing::RunHgrasp;
using ScanCliResult = hgrasp::testing::CliResult;

std::string Calibration(const std::string& name) {
  return std::string(HGRASP_TEST_DATA) + "/calibration/" + name;
}

std::string DefaultScenario() { return std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml"; }

std::filesystem::path FreshOutDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("hgrasp_cli_scan_" + name);
  std::filesystem::remove_all(dir);
  return dir;
}

struct BadFileCase {
  const char* option;  // --laser or --cameras
  const char* file;
  const char* field;
  const char* value;
};

class ScanBadCalibrationTest : public ::testing::TestWithParam<BadFileCase> {};

TEST_P(ScanBadCalibrationTest, ExitsTwoNamingFileFieldAndValue) {
  const BadFileCase& c = GetParam();
  const auto out_dir = FreshOutDir(c.file);
  const ScanCliResult r = RunHgrasp("scan " + DefaultScenario() + " --out " + out_dir.string() +
                                    " " + c.option + " " + Calibration(c.file));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(Calibration(c.file)), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.field), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(std::string("got '") + c.value + "'"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out_dir)) << "output written for a bad calibration";
}

INSTANTIATE_TEST_SUITE_P(
    Cli, ScanBadCalibrationTest,
    ::testing::Values(
        BadFileCase{"--laser", "bad_laser_wrong_type.yaml", "offset_m", "small"},
        BadFileCase{"--laser", "bad_laser_axis_not_unit.yaml", "axis_H", "[0, 0, 1.001]"},
        BadFileCase{"--laser", "bad_laser_frame.yaml", "frame", "camera_left_optical"},
        BadFileCase{"--cameras", "bad_cameras_wrong_type.yaml", "left.cx", "centre"},
        BadFileCase{"--cameras", "bad_cameras_negative_width.yaml", "right.width", "-320"}),
    [](const ::testing::TestParamInfo<BadFileCase>& info) {
      const std::string name = info.param.file;
      return name.substr(0, name.find('.'));
    });

TEST(CliScanTest, MissingLaserFileExitsTwoNamingIt) {
  const auto out_dir = FreshOutDir("missing_laser");
  const std::string missing = "/nonexistent_hgrasp_laser.yaml";
  const ScanCliResult r =
      RunHgrasp("scan " + DefaultScenario() + " --out " + out_dir.string() + " --laser " + missing);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(missing), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out_dir));
}

TEST(CliScanTest, MissingCamerasFileExitsTwoNamingIt) {
  const auto out_dir = FreshOutDir("missing_cameras");
  const std::string missing = "/nonexistent_hgrasp_cameras.yaml";
  const ScanCliResult r = RunHgrasp("scan " + DefaultScenario() + " --out " + out_dir.string() +
                                    " --cameras " + missing);
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(missing), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out_dir));
}

TEST(CliScanTest, CalibrateLaserWithBadCamerasExitsTwoAndWritesNothing) {
  const auto out_dir = FreshOutDir("calibrate_bad_cameras");
  const auto out_file = out_dir / "laser.yaml";
  const ScanCliResult r =
      RunHgrasp("calibrate laser " + DefaultScenario() + " --out " + out_file.string() +
                " --cameras " + Calibration("bad_cameras_zero_fx.yaml"));
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("bad_cameras_zero_fx.yaml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("left.fx"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out_file));
}

TEST(CliScanTest, UsageErrorsExitTwo) {
  EXPECT_EQ(RunHgrasp("calibrate laser " + DefaultScenario()).status, 2);  // no --out
  EXPECT_EQ(RunHgrasp("calibrate").status, 2);                             // no subcommand
  EXPECT_EQ(RunHgrasp("calibrate laser --out /tmp/x.yaml").status, 2);     // no scenario
  EXPECT_EQ(RunHgrasp("scan " + DefaultScenario()).status, 2);             // no --out
  EXPECT_EQ(RunHgrasp("scan --out /tmp/hgrasp_cli_scan_never").status, 2);
  EXPECT_EQ(
      RunHgrasp("scan " + DefaultScenario() + " --out /tmp/hgrasp_cli_scan_never --laser").status,
      2);  // option without its value
}

// Issue 15: when report.json could not be written, scan left range.ply and range.png behind.
TEST(CliScanTest, AReportThatCannotBeWrittenLeavesNoScanBehind) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_scan_unwritable";
  fs::remove_all(dir);
  fs::create_directories(dir / "report.json");
  const ScanCliResult r = RunHgrasp("scan " + std::string(HGRASP_ROOT_DIR) +
                                    "/scenarios/default.yaml --out " + dir.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find((dir / "report.json").string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "range.ply"));
  EXPECT_FALSE(fs::exists(dir / "range.png"));
  int entries = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir)) ++entries;
  EXPECT_EQ(entries, 1) << "a staging folder or output was left";
  fs::remove_all(dir);
}

// Issue 15: the default scene (two boxes, no calibration target) gave a plane 45 deg and 207 mm
// from the truth, written with exit 0. The calibration measures its own quality now.
TEST(CliScanTest, CalibrationBelowItsQualityIsRefusedWithTheFigures) {
  namespace fs = std::filesystem;
  const fs::path out = fs::temp_directory_path() / "hgrasp_cli_bad_calibration.yaml";
  fs::remove(out);
  const ScanCliResult r = RunHgrasp("calibrate laser " + std::string(HGRASP_ROOT_DIR) +
                                    "/scenarios/default.yaml --out " + out.string());
  EXPECT_EQ(r.status, 1) << r.output;
  EXPECT_NE(r.output.find("the rotating-plane model does not fit the stripes"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("deg (median) from the model"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("not written"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out));
}

// --out of calibrate laser is checked before the sweep: a folder, or a path under a file.
TEST(CliScanTest, CalibrationOutThatCannotBeAFileExitsTwoAtOnce) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / "hgrasp_cli_cal_out";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "a_file") << "mine\n";
  for (const fs::path& out : {dir, dir / "a_file" / "laser.yaml"}) {
    const ScanCliResult r = RunHgrasp("calibrate laser " + std::string(HGRASP_ROOT_DIR) +
                                      "/scenarios/calibration_target.yaml --out " + out.string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("--out: got '" + out.string() + "'"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("stripe positions"), std::string::npos) << "it swept first";
  }
  fs::remove_all(dir);
}

}  // namespace
