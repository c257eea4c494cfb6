// The `hgrasp` command as a user runs it: exit status and messages for bad input, and the files
// a render leaves.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

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

// ---------------------------------------------------------------------------------------------
// Hostile and careless input (issue 15).

const std::string kDefault = std::string(HGRASP_ROOT_DIR) + "/scenarios/default.yaml";
namespace fs = std::filesystem;

// A fresh folder under the temporary directory for one test.
fs::path Fresh(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / name;
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// `hgrasp twin` refuses bad input before it serves anything: exit 2 naming the option or file.
TEST(CliHostileTest, TwinRefusesBadInputWithTheFieldNamed) {
  const fs::path dir = Fresh("hgrasp_cli_twin_bad");
  struct Case {
    std::string args, expected;
  };
  for (const Case& c : {Case{"--rate 2 " + kDefault, "--rate"},
                        Case{"--rate 0 " + kDefault, "--rate"},
                        Case{"--corrupt 0.7 " + kDefault, "--corrupt"},
                        Case{"--at soon:cut " + kDefault, "--at"},
                        Case{(dir / "missing.yaml").string(), "missing.yaml"}}) {
    const Result r = RunHgrasp("twin --dir " + (dir / "ports").string() + " " + c.args);
    EXPECT_EQ(r.status, 2) << c.args << ": " << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "ports" / "ready"));
  }
  fs::remove_all(dir);
}

// "hgrasp frobnicate" said only that a subcommand is required; "hgrasp twin --help" printed the
// main help and exited 0 (before `twin` was a command; "simulate" stands in for it now).
TEST(CliHostileTest, AWordThatIsNoCommandIsNamed) {
  for (const char* args : {"frobnicate", "simulate --help", "simulate scenarios/default.yaml"}) {
    const Result r = RunHgrasp(args);
    EXPECT_EQ(r.status, 2) << args << ": " << r.output;
    const std::string word = std::string(args).substr(0, std::string(args).find(' '));
    EXPECT_NE(r.output.find("'" + word + "' is no command"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("render, calibrate, scan, model, plan, run, generate, sweep, emulate"),
              std::string::npos)
        << r.output;
  }
  const Result r = RunHgrasp("calibrate head x.yaml");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(
      r.output.find("hgrasp calibrate: 'head' is no command; expected one of: laser, cameras"),
      std::string::npos)
      << r.output;
  EXPECT_EQ(RunHgrasp("render --help").status, 0);  // help itself still works
}

// "--encoder abc" gave no expected value.
TEST(CliHostileTest, ABadEncoderCountSaysWhatIsExpected) {
  const Result r = RunHgrasp("render " + kDefault + " --out /tmp/hgrasp_enc --encoder 0 abc");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("--encoder: got 'abc'; expected an integer laser encoder count"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists("/tmp/hgrasp_enc"));
}

// --out naming a file, a virtual file system, nothing, or too long a name exited 1 with a raw
// filesystem error, after the work was done.
TEST(CliHostileTest, OutProblemsExitTwoNamingThePath) {
  const fs::path dir = Fresh("hgrasp_cli_out");
  std::ofstream(dir / "a_file") << "mine\n";
  const std::string long_name = (dir / std::string(300, 'x')).string();
  const std::string bad[] = {(dir / "a_file").string(), (dir / "a_file" / "sub").string(),
                             "/proc/hgrasp_out", "/sys/hgrasp_out", long_name, "''"};
  for (const std::string& out : bad) {
    for (const char* command : {"render", "scan", "model", "plan", "run"}) {
      const Result r = RunHgrasp(std::string(command) + " " + kDefault + " --out " + out);
      EXPECT_EQ(r.status, 2) << command << " --out " << out << ": " << r.output;
      EXPECT_NE(r.output.find("--out"), std::string::npos) << r.output;
      if (out != "''") {
        EXPECT_NE(r.output.find(out.substr(0, 80)), std::string::npos) << r.output;
      }
    }
  }
  std::ifstream mine(dir / "a_file");
  std::string text;
  std::getline(mine, text);
  EXPECT_EQ(text, "mine");
  EXPECT_FALSE(fs::exists("/proc/hgrasp_out"));
  fs::remove_all(dir);
}

// When an output could not be written, the others were left behind (and report.json or
// truth.json unwritten still exited 0 saying "wrote").
TEST(CliHostileTest, AnOutputThatCannotBeWrittenLeavesNothing) {
  const fs::path dir = Fresh("hgrasp_cli_unwritable");
  fs::create_directories(dir / "truth.json");  // a folder where render's truth.json goes
  const Result r = RunHgrasp("render " + kDefault + " --out " + dir.string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find((dir / "truth.json").string()), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("wrote"), std::string::npos) << r.output;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"truth.json"}) << "half-written output left behind";
  fs::remove_all(dir);
}

// A folder that did not exist and whose command fails is not left behind either.
TEST(CliHostileTest, AFailedCommandLeavesNoFolderItMade) {
  const fs::path dir = Fresh("hgrasp_cli_made");
  const fs::path out = dir / "new" / "deeper";
  const Result r = RunHgrasp("render " + kDefault + " --out " + out.string() + " --encoder 99999");
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_FALSE(fs::exists(dir / "new")) << r.output;
  fs::remove_all(dir);
}

// A scenario with no task ran the whole scan before failing as "target name '' names no
// colour"; a target name without a colour word likewise.
TEST(CliHostileTest, ATaskIsNeededBeforeAnythingRuns) {
  const fs::path dir = Fresh("hgrasp_cli_no_task");
  std::ofstream(dir / "no_task.yaml") << "name: no_task\nobjects: [{name: crate, shape: box, "
                                         "size: [0.06, 0.06, 0.06], position: [0.3, 0], color: "
                                         "[1, 1, 0]}]\n";
  std::ofstream(dir / "colourless.yaml") << "name: colourless\nobjects: [{name: crate, shape: "
                                            "box, size: [0.06, 0.06, 0.06], position: [0.3, 0], "
                                            "color: [1, 1, 0]}]\ntask: {target: {name: crate}}\n";
  for (const char* command : {"model", "plan", "run"}) {
    Result r = RunHgrasp(std::string(command) + " " + (dir / "no_task.yaml").string() +
                         " --out " + (dir / "out").string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("no_task.yaml: task: missing or empty; expected a task"),
              std::string::npos)
        << r.output;
    r = RunHgrasp(std::string(command) + " " + (dir / "colourless.yaml").string() + " --out " +
                  (dir / "out").string());
    EXPECT_EQ(r.status, 2) << r.output;
    EXPECT_NE(r.output.find("task.target.name: got 'crate'"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "out"));
  }
  // render and scan need no task.
  EXPECT_EQ(RunHgrasp("render " + (dir / "no_task.yaml").string() + " --out " +
                      (dir / "render").string())
                .status,
            0);
  fs::remove_all(dir);
}

// Camera intrinsics of another resolution were used on 320 x 240 frames.
TEST(CliHostileTest, CamerasOfAnotherSizeThanTheFramesAreRefused) {
  const fs::path dir = Fresh("hgrasp_cli_cameras");
  std::ofstream(dir / "vga.yaml")
      << "left: {width: 640, height: 480, fx: 461, fy: 461, cx: 319.5, cy: 239.5}\n"
         "right: {width: 640, height: 480, fx: 461, fy: 461, cx: 319.5, cy: 239.5}\n";
  const Result r = RunHgrasp("scan " + kDefault + " --out " + (dir / "out").string() +
                             " --cameras " + (dir / "vga.yaml").string());
  EXPECT_EQ(r.status, 2) << r.output;
  EXPECT_NE(r.output.find("vga.yaml"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("640 x 480"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("320 x 240"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  fs::remove_all(dir);
}

}  // namespace
