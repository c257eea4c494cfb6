#include "sim/scenario.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/geometry.h"
#include "common/paths.h"
#include "tests/common/yaml_bombs.h"

namespace hgrasp::sim {
namespace {

// The InputError that parsing `yaml` (named "inline.yaml") throws; a failure if none.
InputError ParseError(const std::string& yaml) {
  SCOPED_TRACE(yaml);
  try {
    ParseScenario(yaml, "inline.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no error for: " << yaml;
  return InputError("", "", "", "");
}

namespace fs = std::filesystem;

const std::string kFixtures = std::string(HGRASP_TEST_DATA) + "/scenarios/";
constexpr double kEps = 1e-12;

std::vector<std::string> FilesIn(const std::string& dir, const std::string& prefix) {
  std::vector<std::string> files;
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (e.path().extension() == ".yaml" && name.rfind(prefix, 0) == 0) {
      files.push_back(e.path().string());
    }
  }
  std::sort(files.begin(), files.end());
  return files;
}

// ---------------------------------------------------------------------------------------------
// Good files.

TEST(ScenarioTest, EveryGoodFixtureAndShippedScenarioLoads) {
  std::vector<std::string> files = FilesIn(kFixtures, "good_");
  const std::vector<std::string> shipped = FilesIn(ProjectRoot() + "/scenarios", "");
  files.insert(files.end(), shipped.begin(), shipped.end());
  ASSERT_GE(files.size(), 7u);
  for (const std::string& f : files) {
    SCOPED_TRACE(f);
    EXPECT_NO_THROW({
      const Scenario s = LoadScenario(f);
      EXPECT_EQ(s.path, f);
    });
  }
}

TEST(ScenarioTest, MinimalTakesDefaults) {
  const Scenario s = LoadScenario(kFixtures + "good_minimal.yaml");
  EXPECT_EQ(s.name, "minimal");
  EXPECT_EQ(s.seed, 0u);
  EXPECT_EQ(s.camera_noise, 0.0);
  EXPECT_EQ(s.ambient, 0.35);
  EXPECT_FALSE(s.wall_x.has_value());
  EXPECT_TRUE(s.objects.empty());
  EXPECT_TRUE(s.interference.empty());
  EXPECT_FALSE(s.task.has_value());
  EXPECT_TRUE(s.devices.entries.empty());
}

TEST(ScenarioTest, RobotErrorsTakeTheRealRobotsDefaultsAndEachCanBeSet) {
  const Scenario d = ParseScenario("name: t\n", "t.yaml");
  EXPECT_TRUE(d.robot_errors.enabled);
  EXPECT_EQ(d.robot_errors.arm_joint_zero_deg, 0.1);
  EXPECT_EQ(d.robot_errors.head_encoder_deg, 0.03);
  const Scenario s = ParseScenario(
      "name: t\nrobot_errors:\n  arm_joint_zero_deg: 0.2\n  arm_link_mm: 0\n"
      "  head_mount_mm: 2\n  arm_latency_ms: 40\n",
      "t.yaml");
  EXPECT_TRUE(s.robot_errors.enabled);
  EXPECT_EQ(s.robot_errors.arm_joint_zero_deg, 0.2);
  EXPECT_EQ(s.robot_errors.arm_link_mm, 0.0);
  EXPECT_EQ(s.robot_errors.head_mount_mm, 2.0);
  EXPECT_EQ(s.robot_errors.arm_latency_ms, 40.0);
  EXPECT_EQ(s.robot_errors.arm_backlash_deg, 0.03);  // not given: the default
  EXPECT_FALSE(ParseScenario("name: t\nrobot_errors: {enabled: false}\n", "t.yaml")
                   .robot_errors.enabled);
}

TEST(ScenarioTest, FullBlockStyleValues) {
  const Scenario s = LoadScenario(kFixtures + "good_full.yaml");
  EXPECT_EQ(s.name, "full");
  EXPECT_EQ(s.seed, 12345678901234u);
  EXPECT_EQ(s.camera_noise, 1.5);
  EXPECT_EQ(s.ambient, 0.5);
  ASSERT_TRUE(s.wall_x.has_value());
  EXPECT_EQ(*s.wall_x, 0.8);

  ASSERT_EQ(s.objects.size(), 2u);
  const ObjectSpec& red = s.objects[0];
  EXPECT_EQ(red.name, "red_box");
  EXPECT_EQ(red.shape, "box");
  EXPECT_TRUE(red.size_O.isApprox(Eigen::Vector3d(0.10, 0.04, 0.20)));
  EXPECT_TRUE(red.position_W.isApprox(Eigen::Vector2d(0.30, 0.10)));
  EXPECT_NEAR(red.yaw, kPi / 2, kEps);
  EXPECT_EQ(red.color_rgb, Eigen::Vector3d(1.0, 0.0, 0.0));
  EXPECT_EQ(red.mass, 0.5);
  EXPECT_TRUE(red.specular);
  // yaw 90 deg: the box's own x axis points along W y; its centre is half its height up.
  const Pose3 X_WO = red.X_WO();
  EXPECT_TRUE(X_WO.translation().isApprox(Eigen::Vector3d(0.30, 0.10, 0.10)));
  EXPECT_TRUE((X_WO.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
  EXPECT_TRUE((X_WO.linear() * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitZ()));

  const ObjectSpec& green = s.objects[1];
  EXPECT_EQ(green.name, "green_box");
  EXPECT_TRUE(green.size_O.isApprox(Eigen::Vector3d(0.05, 0.05, 0.05)));
  EXPECT_TRUE(green.position_W.isApprox(Eigen::Vector2d(0.30, -0.10)));
  EXPECT_EQ(green.yaw, 0.0);     // default
  EXPECT_EQ(green.mass, 0.2);    // default
  EXPECT_FALSE(green.specular);  // default
  EXPECT_NEAR(green.X_WO().translation().z(), 0.025, kEps);
  EXPECT_TRUE(green.X_WO().linear().isIdentity());

  ASSERT_EQ(s.interference.size(), 1u);
  EXPECT_TRUE(s.interference[0].origin_W.isApprox(Eigen::Vector3d(0.6, -0.8, 0.5)));
  EXPECT_NEAR(s.interference[0].sweep_min, -kPi / 9, kEps);
  EXPECT_NEAR(s.interference[0].sweep_max, kPi / 9, kEps);
  EXPECT_EQ(s.interference[0].period_s, 2.0);

  ASSERT_TRUE(s.task.has_value());
  EXPECT_EQ(s.task->target_name, "green_box");
  EXPECT_EQ(s.task->target_color, "");
  EXPECT_EQ(s.task->lift_m, 0.08);

  ASSERT_EQ(s.devices.entries.size(), 5u);
  using drivers::Parity;
  const auto* head = s.devices.Backend<drivers::BiclopsBackend>("head");
  ASSERT_NE(head, nullptr);
  EXPECT_EQ(s.devices.Find("head")->driver(), "biclops");
  EXPECT_EQ(head->serial.port, "/dev/ttyS1");
  EXPECT_EQ(head->serial.baud, 9600);  // the driver's default
  EXPECT_EQ(drivers::Framing(head->serial), "8N1");
  EXPECT_NE(s.devices.Find("head")->serial(), nullptr);
  const auto* arm = s.devices.Backend<drivers::Val2Backend>("arm_left");
  ASSERT_NE(arm, nullptr);
  EXPECT_EQ(arm->serial.baud, 19200);
  EXPECT_EQ(arm->serial.data_bits, 7);
  EXPECT_EQ(arm->serial.parity, Parity::kEven);
  EXPECT_EQ(arm->serial.stop_bits, 2);
  // The laser and the LEDs share one board, hence one port.
  EXPECT_EQ(s.devices.Backend<drivers::LaserBoardBackend>("laser")->serial.port, "/dev/ttyUSB0");
  EXPECT_EQ(s.devices.Backend<drivers::LaserBoardBackend>("leds")->serial.port, "/dev/ttyUSB0");
  EXPECT_EQ(s.devices.Backend<drivers::LaserBoardBackend>("leds")->serial.baud, 115200);
  const auto* cameras = s.devices.Backend<drivers::GstreamerBackend>("cameras");
  ASSERT_NE(cameras, nullptr);
  EXPECT_EQ(s.devices.Find("cameras")->serial(), nullptr);
  EXPECT_EQ(cameras->cameras.left, "v4l2src device=/dev/video0 ! videoconvert ! appsink");
  EXPECT_EQ(cameras->cameras.right, "v4l2src device=/dev/video1 ! videoconvert ! appsink");
  EXPECT_FALSE(s.devices.AllSimulated());
  EXPECT_TRUE(s.devices.AnySimulated());  // the arm_right and both hands
}

TEST(ScenarioTest, JsonFlowStyle) {
  const Scenario s = LoadScenario(kFixtures + "good_flow.yaml");
  EXPECT_EQ(s.name, "flow");
  EXPECT_EQ(s.seed, 3u);
  EXPECT_EQ(s.camera_noise, 0.0);
  EXPECT_EQ(s.ambient, 0.2);
  ASSERT_EQ(s.objects.size(), 1u);
  EXPECT_EQ(s.objects[0].name, "cube");
  EXPECT_NEAR(s.objects[0].yaw, -kPi / 4, kEps);
  EXPECT_TRUE(s.objects[0].color_rgb.isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  EXPECT_FALSE(s.objects[0].specular);
  EXPECT_NEAR(s.objects[0].X_WO().translation().z(), 0.035, kEps);
  ASSERT_EQ(s.interference.size(), 1u);
  EXPECT_EQ(s.interference[0].period_s, 1.0);
  ASSERT_TRUE(s.task.has_value());
  EXPECT_EQ(s.task->target_color, "blue");
  EXPECT_EQ(s.task->target_name, "");
  EXPECT_EQ(s.task->lift_m, 0.05);  // default
  EXPECT_TRUE(s.devices.entries.empty());
}

TEST(ScenarioTest, TouchingAndEdgeOfTableAreValid) {
  const Scenario s = LoadScenario(kFixtures + "good_edges.yaml");
  EXPECT_EQ(s.objects.size(), 5u);
}

TEST(ScenarioTest, DefaultScenarioIsThePapersExperiment) {
  const Scenario s = LoadScenario(ResolveDataPath("scenarios/default.yaml"));
  EXPECT_EQ(s.name, "default");
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.camera_noise, 2.0);
  ASSERT_EQ(s.objects.size(), 2u);
  EXPECT_EQ(s.objects[0].name, "yellow_box");
  EXPECT_TRUE(s.objects[0].size_O.isApprox(Eigen::Vector3d(0.06, 0.09, 0.12)));
  EXPECT_NEAR(s.objects[0].yaw, DegToRad(25), kEps);
  EXPECT_NEAR(s.objects[1].yaw, DegToRad(-10), kEps);
  EXPECT_NEAR(s.objects[0].X_WO().translation().z(), 0.06, kEps);
  // Both centres in the workspace.
  for (const ObjectSpec& o : s.objects) {
    EXPECT_GE(o.position_W.x(), 0.20);
    EXPECT_LE(o.position_W.x(), 0.40);
    EXPECT_GE(o.position_W.y(), -0.15);
    EXPECT_LE(o.position_W.y(), 0.15);
  }
  ASSERT_TRUE(s.task.has_value());
  EXPECT_EQ(s.task->target_color, "yellow");
  EXPECT_EQ(s.task->lift_m, 0.05);
}

TEST(ScenarioTest, ShippedVariants) {
  const Scenario interference =
      LoadScenario(ResolveDataPath("scenarios/two_boxes_interference.yaml"));
  EXPECT_EQ(interference.interference.size(), 2u);
  int specular = 0;
  for (const ObjectSpec& o : interference.objects) specular += o.specular ? 1 : 0;
  EXPECT_EQ(specular, 1);

  const Scenario wall = LoadScenario(ResolveDataPath("scenarios/plane_wall.yaml"));
  ASSERT_TRUE(wall.wall_x.has_value());
  EXPECT_EQ(*wall.wall_x, 0.9);
  EXPECT_EQ(wall.objects.size(), 1u);
}

TEST(ScenarioTest, ParseScenarioFromText) {
  const Scenario s = ParseScenario("{name: t, seed: 42}", "<inline>");
  EXPECT_EQ(s.path, "<inline>");
  EXPECT_EQ(s.name, "t");
  EXPECT_EQ(s.seed, 42u);
}

// ---------------------------------------------------------------------------------------------
// Interference sweep: a triangle wave min -> max -> min.

TEST(ScenarioInterferenceTest, AngleAtKnownTimes) {
  InterferenceSpec s;
  s.sweep_min = -0.2;
  s.sweep_max = 0.4;
  s.period_s = 2.0;
  EXPECT_NEAR(s.AngleAt(0.0), -0.2, kEps);
  EXPECT_NEAR(s.AngleAt(0.5), 0.1, kEps);   // a quarter period: halfway up
  EXPECT_NEAR(s.AngleAt(1.0), 0.4, kEps);   // half a period: the top
  EXPECT_NEAR(s.AngleAt(1.5), 0.1, kEps);   // halfway down
  EXPECT_NEAR(s.AngleAt(2.0), -0.2, kEps);  // a full period: back to the start
  EXPECT_NEAR(s.AngleAt(4.5), 0.1, kEps);   // periodic
  EXPECT_NEAR(s.AngleAt(-0.5), 0.1, kEps);  // and for negative times
  for (double t = -3.0; t < 3.0; t += 0.01) {
    EXPECT_GE(s.AngleAt(t), s.sweep_min - kEps);
    EXPECT_LE(s.AngleAt(t), s.sweep_max + kEps);
  }
}

// ---------------------------------------------------------------------------------------------
// Bad files: one fault each, reported with file:line, field path and the value as written.

struct BadCase {
  const char* file;   // under tests/data/scenarios/
  int line;           // 1-based line the error points at; 0: none (the whole file)
  const char* field;  // InputError::field()
  const char* value;  // InputError::value(), as written in the file
};

void PrintTo(const BadCase& c, std::ostream* os) { *os << c.file; }

class BadScenarioTest : public ::testing::TestWithParam<BadCase> {};

TEST_P(BadScenarioTest, ThrowsInputErrorNamingFileLineFieldAndValue) {
  const BadCase& c = GetParam();
  const std::string path = kFixtures + c.file;
  try {
    LoadScenario(path);
    FAIL() << "no error for " << c.file;
  } catch (const InputError& e) {
    const std::string what = e.what();
    SCOPED_TRACE(what);
    const std::string where = c.line > 0 ? path + ":" + std::to_string(c.line) : path;
    EXPECT_EQ(e.file(), where);
    EXPECT_EQ(e.field(), c.field);
    EXPECT_EQ(e.value(), c.value);
    EXPECT_NE(what.find(c.file), std::string::npos);
    EXPECT_NE(what.find(where + ": "), std::string::npos);
    if (*c.field != '\0') {
      EXPECT_NE(what.find(std::string(c.field) + ": "), std::string::npos);
    }
    if (*c.value != '\0') {
      EXPECT_NE(what.find("'" + std::string(c.value) + "'"), std::string::npos);
    }
    EXPECT_NE(what.find("; expected "), std::string::npos);
  }
}

const BadCase kBadCases[] = {
    {"bad_ambient.yaml", 2, "lighting.ambient", "1.5"},
    {"bad_color_name.yaml", 3, "task.target.color", "purple"},
    {"bad_color_range.yaml", 7, "objects[0].color", "[1.2, 0.5, 0.1]"},
    {"bad_device_key.yaml", 3, "devices.gripper", "gripper"},
    {"bad_driver.yaml", 3, "devices.head.driver", "pmd9000"},
    {"bad_device_baud.yaml", 5, "devices.hand_left.baud", "9601"},
    {"bad_device_port.yaml", 3, "devices.arm_left.port", ""},
    {"bad_cameras_without_board.yaml", 6, "devices.cameras.driver", "gstreamer"},
    {"bad_duplicate_key.yaml", 4, "seed", "seed"},
    {"bad_duplicate_name.yaml", 8, "objects[1].name", "twin"},
    {"bad_empty.yaml", 0, "top level", ""},
    {"bad_lift.yaml", 4, "task.lift", "-0.05"},
    {"bad_missing_name.yaml", 2, "name", ""},
    {"bad_missing_object_field.yaml", 3, "objects[0].color", ""},
    {"bad_negative_mass.yaml", 8, "objects[0].mass", "-0.1"},
    {"bad_negative_noise.yaml", 2, "camera_noise", "-1.5"},
    {"bad_negative_size.yaml", 10, "objects[1].size", "[0.06, -0.09, 0.12]"},
    {"bad_not_map.yaml", 2, "top level", "[{name: not_a_map}]"},
    {"bad_object_name.yaml", 3, "objects[0].name", "my box"},
    {"bad_objects_not_list.yaml", 2, "objects", "{name: a}"},
    {"bad_off_table.yaml", 7, "objects[0].position", "[0.86, 0.0]"},
    {"bad_overlap.yaml", 13, "objects[1].position", "[0.40, 0.0]"},
    {"bad_period.yaml", 5, "interference[0].period_s", "0"},
    {"bad_position_count.yaml", 6, "objects[0].position", "[0.30]"},
    {"bad_quoted_number.yaml", 2, "camera_noise", "2.0"},
    {"bad_shape.yaml", 4, "objects[0].shape", "cylinder"},
    {"bad_size_range.yaml", 5, "objects[0].size", "[0.06, 0.09, 0.6]"},
    {"bad_sweep.yaml", 4, "interference[0].sweep_deg", "[20, -20]"},
    {"bad_syntax.yaml", 6, "YAML syntax", "position: [0.30, 0.0]"},
    {"bad_target_both.yaml", 9, "task.target", "{color: yellow, name: a}"},
    {"bad_target_name.yaml", 9, "task.target.name", "purple_box"},
    {"bad_target_neither.yaml", 3, "task.target", "{}"},
    {"bad_two_documents.yaml", 2, "top level", "---"},
    {"bad_unknown_key.yaml", 2, "camera_nosie", "camera_nosie"},
    {"bad_unknown_object_key.yaml", 8, "objects[0].texture", "texture"},
    {"bad_wall.yaml", 3, "wall.x", "0.6"},
    {"bad_wrong_type.yaml", 2, "seed", "abc"},
    {"bad_wrong_type_bool.yaml", 8, "objects[0].specular", "maybe"},
    {"bad_wrong_type_size.yaml", 5, "objects[0].size", "0.05"},
};

INSTANTIATE_TEST_SUITE_P(Fixtures, BadScenarioTest, ::testing::ValuesIn(kBadCases),
                         [](const ::testing::TestParamInfo<BadCase>& info) {
                           std::string name = fs::path(info.param.file).stem().string();
                           return name;
                         });

TEST(ScenarioTest, EveryBadFixtureHasACase) {
  std::set<std::string> covered;
  for (const BadCase& c : kBadCases) covered.insert(c.file);
  for (const std::string& f : FilesIn(kFixtures, "bad_")) {
    EXPECT_EQ(covered.count(fs::path(f).filename().string()), 1u) << f << " has no test case";
  }
}

TEST(ScenarioTest, MissingFile) {
  const std::string path = kFixtures + "no_such_scenario.yaml";
  try {
    LoadScenario(path);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.field(), "");
    EXPECT_EQ(e.value(), path);
    EXPECT_NE(std::string(e.what()).find("no such file"), std::string::npos) << e.what();
  }
}

TEST(ScenarioTest, DirectoryIsNotAFile) { EXPECT_THROW(LoadScenario(kFixtures), InputError); }

// Unknown keys are errors at every level; the error names the key's path and line.
TEST(ScenarioTest, UnknownKeyAtEveryLevel) {
  const std::string object =
      "{name: a, shape: box, size: [0.05, 0.05, 0.05], position: [0.3, 0], color: [1, 0, 0]";
  const std::string interference = "{origin: [1, 0, 0.5], sweep_deg: [-10, 10], period_s: 1";
  const struct {
    std::string yaml, field;
  } cases[] = {
      {"name: t\nbogus: 1\n", "bogus"},
      {"name: t\nobjects:\n  - " + object + ", bogus: 1}\n", "objects[0].bogus"},
      {"name: t\nlighting:\n  bogus: 1\n", "lighting.bogus"},
      {"name: t\nwall:\n  bogus: 1\n", "wall.bogus"},
      {"name: t\ninterference:\n  - " + interference + ", bogus: 1}\n", "interference[0].bogus"},
      {"name: t\ntask:\n  bogus: 1\n", "task.bogus"},
      {"name: t\ntask:\n  target: {color: red,\n    bogus: 1}\n", "task.target.bogus"},
      {"name: t\ndevices:\n  bogus: {driver: sim}\n", "devices.bogus"},
      {"name: t\ndevices:\n  head: {driver: sim,\n    bogus: 1}\n", "devices.head.bogus"},
  };
  for (const auto& c : cases) {
    const InputError e = ParseError(c.yaml);
    EXPECT_EQ(e.field(), c.field);
    EXPECT_EQ(e.value(), "bogus");
    const int line = static_cast<int>(std::count(c.yaml.begin(), c.yaml.end(), '\n'));
    EXPECT_EQ(e.file(), "inline.yaml:" + std::to_string(line)) << e.what();
  }
}

// A one-object scenario in flow style; `extra` adds fields, the others may be replaced.
std::string OneBox(const std::string& size = "[0.05, 0.05, 0.05]",
                   const std::string& position = "[0.3, 0]", const std::string& color = "[1, 0, 0]",
                   const std::string& extra = "") {
  return "name: t\nobjects: [{name: a, shape: box, size: " + size + ", position: " + position +
         ", color: " + color + extra + "}]\n";
}

// Further faults, inline: each must throw InputError naming the field.
TEST(ScenarioTest, MoreBadValues) {
  const struct {
    std::string yaml, field;
  } cases[] = {
      {"seed: 1\n", "name"},
      {"name: ''\n", "name"},
      {"name: [a, b]\n", "name"},
      {"name: t\nseed: -1\n", "seed"},
      {"name: t\nseed: 1.5\n", "seed"},
      {"name: t\nseed: 99999999999999999999999\n", "seed"},
      {"name: t\nseed:\n", "seed"},
      {"name: t\ncamera_noise: .nan\n", "camera_noise"},
      {"name: t\ncamera_noise: .inf\n", "camera_noise"},
      {"name: t\ncamera_noise: 0x10\n", "camera_noise"},
      {"name: t\nlighting: 0.3\n", "lighting"},
      {"name: t\nlighting: {ambient: -0.1}\n", "lighting.ambient"},
      {"name: t\nwall: {x: 0.4}\n", "wall.x"},
      {"name: t\nwall: {}\n", "wall.x"},
      {"name: t\nwall: 0.9\n", "wall"},
      {"name: t\nrobot_errors: off\n", "robot_errors"},
      {"name: t\nrobot_errors: {enabled: maybe}\n", "robot_errors.enabled"},
      {"name: t\nrobot_errors: {arm_joint_zero_deg: -0.1}\n", "robot_errors.arm_joint_zero_deg"},
      {"name: t\nrobot_errors: {arm_link_mm: 11}\n", "robot_errors.arm_link_mm"},
      {"name: t\nrobot_errors: {head_latency_ms: .nan}\n", "robot_errors.head_latency_ms"},
      {"name: t\nrobot_errors: {arm_zero_deg: 0.1}\n", "robot_errors.arm_zero_deg"},
      {OneBox("[0, 0.05, 0.05]"), "objects[0].size"},
      {OneBox("[0.005, 0.05, 0.05]"), "objects[0].size"},
      {OneBox("[0.05, 0.05]"), "objects[0].size"},
      {OneBox("[0.05, a, 0.05]"), "objects[0].size"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[-0.1, 0, 0]"), "objects[0].color"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0]"), "objects[0].color"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0, 0]", ", mass: 0"), "objects[0].mass"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0, 0]", ", yaw_deg: ninety"),
       "objects[0].yaw_deg"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.05, 0]"), "objects[0].position"},     // behind x 0.08
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0.59]"), "objects[0].position"},   // past y 0.60
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, -0.59]"), "objects[0].position"},  // past y -0.60
      {"name: t\nobjects: [{name: a, size: [0.05, 0.05, 0.05], position: [0.3, 0], "
       "color: [1, 0, 0]}]\n",
       "objects[0].shape"},
      {"name: t\nobjects: [{shape: box, size: [0.05, 0.05, 0.05], position: [0.3, 0], "
       "color: [1, 0, 0]}]\n",
       "objects[0].name"},
      {"name: t\nobjects: [5]\n", "objects[0]"},
      {"name: t\ninterference: [{origin: [1, 0], sweep_deg: [-1, 1], period_s: 1}]\n",
       "interference[0].origin"},
      {"name: t\ninterference: [{origin: [1, 0, 0.5], sweep_deg: [1, 1], period_s: 1}]\n",
       "interference[0].sweep_deg"},
      {"name: t\ninterference: [{origin: [1, 0, 0.5], sweep_deg: [-1, 1], period_s: -2}]\n",
       "interference[0].period_s"},
      {"name: t\ninterference: [{origin: [1, 0, 0.5], sweep_deg: [-1, 1]}]\n",
       "interference[0].period_s"},
      {"name: t\ninterference: {origin: [1, 0, 0]}\n", "interference"},
      {"name: t\ntask: {lift: 0.05}\n", "task.target"},
      {"name: t\ntask: {target: yellow}\n", "task.target"},
      {"name: t\ntask: {target: {color: yellow}, lift: 0.5}\n", "task.lift"},
      {"name: t\ntask: {target: {name: ghost}}\n", "task.target.name"},
      {"name: t\ntask: 1\n", "task"},
      {"name: t\ndevices: {head: {}}\n", "devices.head.driver"},
      {"name: t\ndevices: {head: sim}\n", "devices.head"},
      {"name: t\ndevices: {head: {driver: sim, port: /dev/ttyS0}}\n", "devices.head.port"},
      {"name: t\ndevices: {head: {driver: val2, port: /dev/ttyS0}}\n", "devices.head.driver"},
      {"name: t\ndevices: {arm_left: {driver: val2}}\n", "devices.arm_left.port"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: [a]}}\n", "devices.arm_left.port"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: a, baud: fast}}\n",
       "devices.arm_left.baud"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: a, baud: -9600}}\n",
       "devices.arm_left.baud"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: a, framing: 9N1}}\n",
       "devices.arm_left.framing"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: a, framing: 8X1}}\n",
       "devices.arm_left.framing"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: a, pipeline: b}}\n",
       "devices.arm_left.pipeline"},
      {"name: t\ndevices: {cameras: {driver: gstreamer, left: a}}\n", "devices.cameras.right"},
      {"name: t\ndevices: {arm_left: {driver: val2, port: a},\n  arm_right: {driver: val2, port: "
       "a}}\n",
       "devices.arm_right.port"},
      {"name: t\ndevices: {laser: {driver: laser_board, port: a},\n  leds: {driver: laser_board, "
       "port: a, "
       "baud: 9600}}\n",
       "devices.leds.port"},
      {"name: t\ndevices: []\n", "devices"},
  };
  for (const auto& c : cases) {
    const InputError e = ParseError(c.yaml);
    EXPECT_EQ(e.field(), c.field) << e.what();
    EXPECT_EQ(std::string(e.what()).rfind("inline.yaml", 0), 0u) << e.what();
  }
}

TEST(ScenarioTest, SyntaxErrorInFlowStyleNamesTheLine) {
  try {
    ParseScenario("{\"name\": \"x\",\n \"seed\": 3,\n \"objects\": [}\n", "flow.yaml");
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "YAML syntax");
    EXPECT_EQ(e.file().rfind("flow.yaml:", 0), 0u) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------
// Hostile and careless input (issue 15): each case was accepted, crashed or ran away before.

// A self-referencing alias crashed the loader (unbounded recursion while rendering it).
TEST(ScenarioHostileTest, SelfReferencingAliasIsRefused) {
  for (const char* yaml : {"name: &n [*n]\n", "name: t\nobjects: &o [{name: *o}]\n",
                                 "&m {name: t, devices: *m}\n"}) {
    const InputError e = ParseError(yaml);
    EXPECT_NE(std::string(e.what()).find("alias inside the node it names"), std::string::npos)
        << e.what();
  }
}

// Nine levels of nine aliases each: 9^9 values once expanded. Refused by counting, before
// anything expands them (before, the message for the name expanded them: 36-46 s and 2 GB).
TEST(ScenarioHostileTest, BillionLaughsIsRefusedByItsSize) {
  const std::string yaml = testing::BillionLaughs("objects", "name");
  const InputError e = ParseError(yaml);
  EXPECT_NE(std::string(e.what()).find("aliases expanded"), std::string::npos) << e.what();
  EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();
}

// 5000 nested lists: refused with a short message (it echoed 100-200 kB of brackets).
TEST(ScenarioHostileTest, DeepNestingGivesAShortMessage) {
  for (int depth : {40, 5000}) {
    const std::string yaml = "name: " + std::string(depth, '[') + std::string(depth, ']') + "\n";
    const InputError e = ParseError(yaml);
    EXPECT_NE(std::string(e.what()).find("nest"), std::string::npos) << e.what();
    EXPECT_LT(std::string(e.what()).size(), 400u) << e.what();
  }
}

// Control characters and bytes that are no UTF-8 are no YAML; yaml-cpp 0.7 looped without end,
// allocating, on a 0x14 inside a flow collection and on 0xff bytes in a comment (both found by
// the loaders' fuzzer).
TEST(ScenarioHostileTest, ControlCharactersAreRefusedBeforeTheParser) {
  EXPECT_NO_THROW(ParseScenario("# gr\xc3\xbcn \xe2\x80\x94 \xf0\x9f\x93\xa6\nname: t\n",
                                "inline.yaml"));  // UTF-8 text passes
  for (const std::string& yaml : {std::string("{\"name\": \"f\", \"seed\": [1, \x14\0, 2]}\n", 34),
                                 std::string("name: t\nseed: [1, \x14, 2]\n"),
                                 std::string("name: t\x7f\n"),
                                 std::string("# gripper\xff\xff\xff per's frame\n,# x\n"),
                                 std::string("name: \xc0\xaf\n"),  // an overlong '/'
                                 std::string("name: t\xe2\x82\n")}) {  // cut short
    const InputError e = ParseError(yaml);
    EXPECT_NE(std::string(e.what()).find("at byte"), std::string::npos) << e.what();
  }
}

// yaml-cpp's LoadAll looped without end on a stray ',' before a document, making documents out
// of nothing until memory ran out (found by the loaders' fuzzer; plain text, so any user could
// type it).
TEST(ScenarioHostileTest, AStrayCommaIsASyntaxError) {
  for (const char* yaml : {",\n", ",x\n", "# a comment\n,# another\nname: t\n"}) {
    const InputError e = ParseError(yaml);
    EXPECT_EQ(e.field(), "YAML syntax") << e.what();
    EXPECT_NE(std::string(e.what()).find("stray ','"), std::string::npos) << e.what();
  }
}

// A tag makes a string of a number: refused, not read as the number.
TEST(ScenarioHostileTest, TaggedNumberIsRefused) {
  const InputError e = ParseError("name: t\ncamera_noise: !!str 2.0\n");
  EXPECT_NE(std::string(e.what()).find("tag"), std::string::npos) << e.what();
  EXPECT_EQ(e.file(), "inline.yaml:2");
}

// Values no real table, box, camera or room can have, which loaded before.
TEST(ScenarioHostileTest, PhysicalRangesWithUnits) {
  const std::string interference = "name: t\ninterference: [{sweep_deg: [-1, 1], period_s: 1, origin: ";
  const struct {
    std::string yaml, field, unit;
  } cases[] = {
      {"name: t\ncamera_noise: 1e6\n", "camera_noise", "grey levels"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0, 0]", ", yaw_deg: 1e9"), "objects[0].yaw_deg",
       "deg"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0, 0]", ", mass: 1e30"), "objects[0].mass",
       "kg"},
      {OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0, 0]", ", mass: 0.001"), "objects[0].mass",
       "kg"},
      {interference + "[1e300, 0, 0.5]}]\n", "interference[0].origin", "m"},
      {interference + "[1, 0, -0.2]}]\n", "interference[0].origin", "m"},
      {"name: t\ninterference: [{origin: [1, 0, 0.5], sweep_deg: [-1e9, 1], period_s: 1}]\n",
       "interference[0].sweep_deg", "degrees"},
      {"name: t\ninterference: [{origin: [1, 0, 0.5], sweep_deg: [-1, 1], period_s: 1e9}]\n",
       "interference[0].period_s", " s"},
      {"name: t\nwall: {x: 1e300}\n", "wall.x", " m"},
  };
  for (const auto& c : cases) {
    const InputError e = ParseError(c.yaml);
    EXPECT_EQ(e.field(), c.field) << e.what();
    EXPECT_NE(std::string(e.what()).find(c.unit), std::string::npos) << e.what();
  }
  // The limits themselves are accepted.
  EXPECT_NO_THROW(ParseScenario("name: t\ncamera_noise: 25\n", "inline.yaml"));
  EXPECT_NO_THROW(ParseScenario(
      OneBox("[0.05, 0.05, 0.05]", "[0.3, 0]", "[1, 0, 0]", ", mass: 0.5, yaw_deg: -360"),
      "inline.yaml"));
}

// Another robot's laser inside a box lights nothing.
TEST(ScenarioHostileTest, InterferenceInsideABoxIsRefused) {
  const std::string yaml = "name: t\nobjects: [{name: a, shape: box, size: [0.1, 0.1, 0.1], "
                           "position: [0.3, 0], color: [1, 0, 0]}]\ninterference: [{origin: "
                           "[0.31, 0.02, 0.05], sweep_deg: [-1, 1], period_s: 1}]\n";
  const InputError e = ParseError(yaml);
  EXPECT_EQ(e.field(), "interference[0].origin") << e.what();
  EXPECT_NE(std::string(e.what()).find("objects[0] 'a'"), std::string::npos) << e.what();
  // Just above it is fine.
  std::string above = yaml;
  above.replace(above.find("0.05], sweep"), 4, "0.15");
  EXPECT_NO_THROW(ParseScenario(above, "inline.yaml"));
}

// A chessboard on a stand: its frame, its corners and each field's checks.
TEST(ScenarioBoardTest, FrameAndCornersByHand) {
  const Scenario s = ParseScenario(
      "name: t\nboards: [{cols: 4, rows: 3, square_mm: 20, position: [0.4, 0.1, 0.3], yaw_deg: "
      "90, tilt_deg: -90}]\n",
      "inline.yaml");
  ASSERT_EQ(s.boards.size(), 1u);
  const BoardSpec& b = s.boards[0];
  EXPECT_EQ(b.cols, 4);
  EXPECT_EQ(b.rows, 3);
  EXPECT_NEAR(b.square_m, 0.02, 1e-15);
  // Turned 90 deg about z, then stood up by -90 deg about its y: the face looks along -y of W
  // (RotZ(90) * RotY(-90) * z = RotZ(90) * -x = -y), its x axis straight up.
  const Pose3 X = b.X_WB();
  EXPECT_TRUE((X.linear().col(2) - Eigen::Vector3d(0, -1, 0)).norm() < 1e-12);
  EXPECT_TRUE((X.linear().col(0) - Eigen::Vector3d(0, 0, 1)).norm() < 1e-12);
  EXPECT_TRUE((X.translation() - Eigen::Vector3d(0.4, 0.1, 0.3)).norm() < 1e-15);
  // Corner (0, 0) at (-1.5, -1) squares from the centre; (3, 2) at (1.5, 1).
  EXPECT_TRUE((b.CornerB(0, 0) - Eigen::Vector3d(-0.03, -0.02, 0)).norm() < 1e-15);
  EXPECT_TRUE((b.CornerB(3, 2) - Eigen::Vector3d(0.03, 0.02, 0)).norm() < 1e-15);
  // 5 x 4 squares and a border of one square: 7 x 6 squares of plate.
  EXPECT_TRUE((b.HalfExtent() - Eigen::Vector2d(0.07, 0.06)).norm() < 1e-15);
}

TEST(ScenarioBoardTest, EachBadFieldIsNamed) {
  const auto board = [](const std::string& fields) {
    return "name: t\nobjects: [{name: a, shape: box, size: [0.1, 0.1, 0.1], position: [0.3, 0], "
           "color: [1, 0, 0]}]\nboards: [{" + fields + "}]\n";
  };
  const std::string ok = "square_mm: 25, position: [0.3, 0.3, 0.3]";
  const struct {
    std::string yaml, field;
  } cases[] = {
      {board("cols: 8, rows: 6.5, " + ok), "boards[0].rows"},
      {board("cols: 2, rows: 6, " + ok), "boards[0].cols"},
      {board("cols: 21, rows: 6, " + ok), "boards[0].cols"},
      {board("cols: 6, rows: 6, " + ok), "boards[0].rows"},  // square pattern
      {board("cols: 8, rows: 6, square_mm: 2, position: [0.3, 0.3, 0.3]"), "boards[0].square_mm"},
      {board("cols: 8, rows: 6, square_mm: 25, position: [0.3, 0.3]"), "boards[0].position"},
      {board("cols: 8, rows: 6, square_mm: 25, position: [0.3, 0.3, 0]"), "boards[0].position"},
      {board("cols: 8, rows: 6, square_mm: 25, position: [1.3, 0.3, 0.3]"), "boards[0].position"},
      // Standing on its edge 5 cm up: its plate reaches through the table top.
      {board("cols: 8, rows: 6, square_mm: 25, position: [0.3, 0.3, 0.05], tilt_deg: 90"),
       "boards[0].position"},
      // Lying just over box a.
      {board("cols: 8, rows: 6, square_mm: 25, position: [0.3, 0.0, 0.102]"), "boards[0].position"},
      {board("cols: 8, rows: 6, " + ok + ", tilt_deg: 91"), "boards[0].tilt_deg"},
      {board("cols: 8, rows: 6, " + ok + ", colour: red"), "boards[0].colour"},
      {board("rows: 6, " + ok), "boards[0].cols"},
      {"name: t\nboards: {cols: 8}\n", "boards"},
      {"name: t\nrobot_errors: {camera_focal_pct: 11}\n", "robot_errors.camera_focal_pct"},
      {"name: t\ncamera_samples: 3\n", "camera_samples"},
      {"name: t\ncamera_samples: 2\n", "camera_samples"},
      {"name: t\ncamera_samples: 1.5\n", "camera_samples"},
  };
  for (const auto& c : cases) {
    const InputError e = ParseError(c.yaml);
    EXPECT_EQ(e.field(), c.field) << c.yaml << "\n" << e.what();
  }
  // Two boards through each other.
  const InputError e = ParseError(
      "name: t\nboards: [{cols: 8, rows: 6, " + ok + "}, {cols: 8, rows: 6, square_mm: 25, "
      "position: [0.32, 0.3, 0.3], yaw_deg: 30}]\n");
  EXPECT_EQ(e.field(), "boards[1].position") << e.what();
  EXPECT_NE(std::string(e.what()).find("boards[0]"), std::string::npos) << e.what();
  // Lying 1 cm over the box is clear of it.
  EXPECT_NO_THROW(ParseScenario(
      board("cols: 8, rows: 6, square_mm: 25, position: [0.3, 0.0, 0.115]"), "inline.yaml"));
}

// Two spellings of one port, and a symlink to it, are one port (compared by string before).
TEST(ScenarioHostileTest, PortsAreComparedByTheDeviceTheyOpen) {
  const fs::path dir = fs::temp_directory_path() / "hgrasp_port_identity";
  fs::remove_all(dir);
  fs::create_directories(dir);
  { std::ofstream(dir / "ttyS9") << ""; }
  fs::create_symlink(dir / "ttyS9", dir / "by-id");
  const std::string port = (dir / "ttyS9").string();
  for (const std::string& other :
       {dir.string() + "//ttyS9", dir.string() + "/./ttyS9", (dir / "by-id").string(),
        std::string("/dev//null")}) {
    const std::string first = other == "/dev//null" ? "/dev/null" : port;
    const InputError e = ParseError("name: t\ndevices: {arm_left: {driver: val2, port: " + first +
                                    "},\n  arm_right: {driver: val2, port: " + other + "}}\n");
    EXPECT_EQ(e.field(), "devices.arm_right.port") << e.what();
  }
  // A port that does not exist yet is compared by its path, made canonical.
  const InputError e = ParseError(
      "name: t\ndevices: {arm_left: {driver: val2, port: /nonexistent/ttyX},\n  arm_right: "
      "{driver: val2, port: /nonexistent//ttyX}}\n");
  EXPECT_EQ(e.field(), "devices.arm_right.port") << e.what();
  EXPECT_NO_THROW(ParseScenario("name: t\ndevices: {arm_left: {driver: val2, port: " + port +
                                    "},\n  arm_right: {driver: val2, port: /dev/null}}\n",
                                "inline.yaml"));
  fs::remove_all(dir);
}

// The laser and the LEDs are one board: one port (accepted at load before, failing later).
TEST(ScenarioHostileTest, LaserAndLedsOnDifferentPortsAreRefused) {
  const InputError e = ParseError(
      "name: t\ndevices: {laser: {driver: laser_board, port: /tmp/a},\n  leds: {driver: "
      "laser_board, port: /tmp/b}}\n");
  EXPECT_EQ(e.field(), "devices.leds.port") << e.what();
  EXPECT_NO_THROW(ParseScenario("name: t\ndevices: {laser: {driver: laser_board, port: /tmp/a},"
                                "\n  leds: {driver: laser_board, port: /tmp//a}}\n",
                                "inline.yaml"));
}

// What no file the project reads can be: a device that never ends, binary data, a huge file.
TEST(ScenarioHostileTest, FilesThatAreNoScenario) {
  try {
    LoadScenario("/dev/zero");
    ADD_FAILURE() << "/dev/zero loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("character device"), std::string::npos) << e.what();
  }
  const fs::path dir = fs::temp_directory_path() / "hgrasp_not_scenarios";
  fs::create_directories(dir);
  {
    std::ofstream(dir / "binary.yaml", std::ios::binary) << std::string("name: ab\0\x01\xff\n", 11);
    std::ofstream big(dir / "big.yaml");
    big << "name: t\n";
    for (int i = 0; i < 70000; ++i) big << "# a comment line of padding\n";
  }
  try {
    LoadScenario((dir / "binary.yaml").string());
    ADD_FAILURE() << "binary loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("NUL byte at byte 8"), std::string::npos) << e.what();
  }
  try {
    LoadScenario((dir / "big.yaml").string());
    ADD_FAILURE() << "a 2 MB file loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("more than 1048576 bytes"), std::string::npos)
        << e.what();
  }
  fs::remove_all(dir);
}

}  // namespace
}  // namespace hgrasp::sim
