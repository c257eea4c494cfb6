// The `hgrasp` command as a user runs it: exit status and messages for bad input, and the files
// a render leaves.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "tests/app/cli_util.h"

namespace {

using hgrasp::testing::RunHgrasp;
using Result = hgrasp::testing::CliResult;

std::string Data(const std::string& name) {
  return std::string(HGRASP_TEST_DATA) + "/scenarios/" + name;
}

struct BadCase {
  const char* file;
  const char* field;
  const char* value;
};

class BadScenarioTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadScenarioTest, ExitsTwoNamingFileFieldAndValue) {
  const BadCase& c = GetParam();
  const auto out_dir =
      std::filesystem::temp_directory_path() / ("hgrasp_bad_" + std::string(c.file));
  std::filesystem::remove_all(out_dir);
  const Result r = RunHgrasp("render " + Data(c.file) + " --out " + out_dir.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find(c.file), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.field), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.value), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(out_dir)) << "output written for a bad scenario";
}

INSTANTIATE_TEST_SUITE_P(
    Cli, BadScenarioTest,
    ::testing::Values(BadCase{"bad_unknown_key.yaml", "camera_nosie", "camera_nosie"},
                      BadCase{"bad_wrong_type.yaml", "seed", "abc"},
                      BadCase{"bad_negative_size.yaml", "objects[1].size", "[0.06, -0.09, 0.12]"},
                      BadCase{"bad_off_table.yaml", "objects[0].position", "[0.86, 0.0]"},
                      BadCase{"bad_duplicate_name.yaml", "objects[1].name", "twin"},
                      BadCase{"no_such_file.yaml", "no_such_file.yaml", "no_such_file.yaml"},
                      BadCase{"bad_driver.yaml", "devices.head.driver", "pmd9000"},
                      BadCase{"bad_device_port.yaml", "devices.arm_left.port", "serial port"},
                      BadCase{"bad_device_baud.yaml", "devices.hand_left.baud", "9601"}),
    [](const ::testing::TestParamInfo<BadCase>& info) {
      const std::string name = info.param.file;
      return name.substr(0, name.find('.'));
    });

TEST(CliTest, UsageErrorsExitTwo) {
  EXPECT_EQ(RunHgrasp("").status, 2);
  EXPECT_EQ(RunHgrasp("frobnicate").status, 2);
  EXPECT_EQ(RunHgrasp("render").status, 2);  // scenario and --out missing
  EXPECT_EQ(RunHgrasp("render x.yaml --out /tmp/x --encoder many").status, 2);
}

TEST(CliTest, RenderWritesImagesAndTruth) {
  const auto out = std::filesystem::temp_directory_path() / "hgrasp_cli_render";
  std::filesystem::remove_all(out);
  const Result r =
      RunHgrasp("render " + std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml --out " +
                out.string() + " --encoder -500 0 500");
  ASSERT_EQ(r.status, 0) << r.output;
  for (const char* f : {"left.png", "right.png", "left_stripe_-500.png", "right_stripe_500.png",
                        "depth_left.png", "labels_right.png", "stereo_pair.png", "truth.json"}) {
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  }
}

}  // namespace
