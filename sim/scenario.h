#pragma once
/// @file Scenario files (DESIGN.md, "Scenario files (YAML)"): the objects on the table, the
/// lighting, an optional wall, other robots' laser stripes, the task and the device backends.
/// A scenario is ground truth: only sim/, src/app/ and tests read it, never the pipeline.
///
/// Every value is checked when the file is loaded; a bad one throws hgrasp::InputError naming
/// "FILE:LINE", the field path (e.g. "objects[1].size"), the value as written and what was
/// expected (DESIGN.md rule 5). Unknown keys are errors at every level.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "common/geometry.h"
#include "config/device_config.h"

namespace hgrasp::sim {

/// Table top extent in W (m). The table top is the plane z = 0. Must match the table geom in
/// models/humanoid.xml; every object's footprint must lie inside it.
constexpr double kTableMinX = 0.08, kTableMaxX = 0.90, kTableMinY = -0.60, kTableMaxY = 0.60;

/// Accepted range of each object edge length (m).
constexpr double kMinObjectEdge = 0.01, kMaxObjectEdge = 0.5;

/// A wall, when present, must stand beyond this x (m) as well as beyond every object.
constexpr double kMinWallX = 0.5;

/// Largest accepted task lift (m): the Puma 260 reaches about 0.4 m from its shoulder.
constexpr double kMaxLift = 0.3;

/// Physical ranges of the other scenario fields: what a real table, box, camera and room can be.
/// Camera noise (grey levels of 255, std. dev.): a PAL camera through a frame grabber shows 1-3;
/// 25 is a very poor one, and past it no stripe is found at all.
constexpr double kMaxCameraNoise = 25.0;
/// Object mass (kg): a 10 g box is paper the hand would crush; the Puma 260 carries about 1 kg,
/// of which the hand takes about half.
constexpr double kMinMass = 0.01, kMaxMass = 0.5;
/// Yaw (deg): one turn either way.
constexpr double kMaxYawDeg = 360.0;
/// Another robot's laser (m, W): in the room around the table, above the table top, and not
/// inside any object.
constexpr double kMaxInterferenceReach = 5.0, kMaxInterferenceHeight = 3.0;
/// Its sweep (deg, each end) and period (s).
constexpr double kMaxSweepDeg = 180.0, kMaxPeriodS = 60.0;
/// The farthest wall (m, x in W): a room's wall.
constexpr double kMaxWallX = 5.0;

/// Colour names accepted in task.target.color.
inline constexpr std::array<std::string_view, 10> kColorNames = {
    "red", "orange", "yellow", "green", "cyan", "blue", "magenta", "white", "grey", "black"};

/// One object resting on the table.
struct ObjectSpec {
  std::string name;                                      ///< unique within the scenario
  std::string shape = "box";                             ///< only "box" for now
  Eigen::Vector3d size_O = Eigen::Vector3d::Zero();      ///< full edge lengths along O x, y, z (m)
  Eigen::Vector2d position_W = Eigen::Vector2d::Zero();  ///< x, y of the box centre in W (m)
  double yaw = 0.0;                                      ///< rad about W z (YAML field yaw_deg)
  Eigen::Vector3d color_rgb = Eigen::Vector3d::Zero();   ///< RGB, each 0-1
  double mass = 0.2;                                     ///< kg, > 0
  bool specular = false;  ///< true: the surface mirrors the laser (spurious reflections)
  /// The colour's name (one of kColorNames) that a person would give it: truth for the
  /// pipeline's colour namer (YAML color_name). Empty: the palette colour nearest to color_rgb
  /// (sim::TrueColorName).
  std::string color_name;

  /// Pose of the box centre in W: translation (x, y, size_O.z / 2), rotation RotZ(yaw).
  Pose3 X_WO() const;
};

/// Another robot's laser stripe (cross-talk): a vertical light plane from origin_W whose angle
/// about the source's vertical axis sweeps back and forth.
struct InterferenceSpec {
  Eigen::Vector3d origin_W = Eigen::Vector3d::Zero();  ///< source position in W (m)
  double sweep_min = 0.0;  ///< rad (YAML sweep_deg: [min, max]); sweep_min < sweep_max
  double sweep_max = 0.0;  ///< rad
  double period_s = 1.0;   ///< s, > 0: one full sweep min -> max -> min

  /// Plane angle (rad) about the source's vertical axis at time t_s (s): a triangle wave going
  /// sweep_min -> sweep_max -> sweep_min over one period, at sweep_min when t_s = 0. Periodic for
  /// negative times too.
  double AngleAt(double t_s) const;
};

/// Accepted chessboard geometry (scenario list `boards`): inner corners along each side and
/// the square's edge (m); OpenCV's detector needs at least 3 corners a side.
constexpr int kMinBoardCorners = 3, kMaxBoardCorners = 20;
constexpr double kMinBoardSquare = 0.005, kMaxBoardSquare = 0.1;
/// A board's face centre stands over the table, at most this high (m).
constexpr double kMaxBoardHeight = 1.0;

/// A calibration chessboard on a stand (`hgrasp calibrate cameras`): a white plate printed with
/// (cols + 1) x (rows + 1) squares, the one at the plate's -x, -y corner black, with a white
/// border one square wide (OpenCV's detector needs it). The stand is not modelled: the board is
/// a static body of the world. Its frame B: origin at the centre of the printed face, x along
/// the cols, y along the rows, z out of the face.
struct BoardSpec {
  int cols = 9;                                          ///< inner corners along B x
  int rows = 6;                                          ///< inner corners along B y
  double square_m = 0.025;                               ///< square edge (YAML square_mm)
  Eigen::Vector3d position_W = Eigen::Vector3d::Zero();  ///< the face centre in W (m)
  double yaw = 0.0;                                      ///< rad about W z (YAML yaw_deg)
  double tilt = 0.0;  ///< rad about the turned board's y axis (YAML tilt_deg); 0: face up

  /// X_WB = Translation(position_W) * RotZ(yaw) * RotY(tilt): at tilt -45 deg and yaw 0 the face
  /// looks up and back towards the robot (-x).
  Pose3 X_WB() const;
  /// Inner corner (i, j), i < cols, j < rows, in B: ((i - (cols - 1) / 2) s, (j - (rows - 1) / 2)
  /// s, 0), in the order OpenCV's findChessboardCorners lists them (row by row).
  Eigen::Vector3d CornerB(int i, int j) const;
  /// Half the plate's extent in B x and y (m): the squares and the border.
  Eigen::Vector2d HalfExtent() const;
};

/// What to grasp. Exactly one of target_color and target_name is non-empty.
struct TaskSpec {
  std::string target_color;  ///< one of kColorNames, or empty
  std::string target_name;   ///< the name of one of the scenario's objects, or empty
  double lift_m = 0.05;      ///< m, > 0 and <= kMaxLift
};

/// How far the twin's robot differs from its nominal model (models/humanoid.xml and .urdf,
/// which the pipeline reads): the scenario block robot_errors. The values of one robot are
/// drawn from these from the scenario's seed (sim/robot_errors.h); every value is >= 0, and 0
/// switches that error off. The defaults are a real, carefully assembled robot's:
struct RobotErrorsSpec {
  bool enabled = true;  ///< false: the robot is exactly its model (every value below ignored)
  /// Std. dev. of each Puma joint's zero: the encoder's index pulse against the link's
  /// kinematic zero. The Puma 260 finds its zero at power-up from potentiometers and the
  /// encoders' index pulses, set at assembly; kinematic calibrations of Pumas find joint offsets
  /// of 0.02-0.3 deg. 0.1 deg puts the gripper 1-3 mm off at the table.
  double arm_joint_zero_deg = 0.1;
  /// Std. dev. of each coordinate of each Puma link's offset from its parent (the DH lengths
  /// and the joint axes' positions): machined parts and their assembly, 0.1-0.5 mm.
  double arm_link_mm = 0.25;
  /// Full backlash of each Puma joint's gear train after adjustment: the link lags its motor
  /// (whose encoder the controller reads) by half of it in the direction of the last move.
  double arm_backlash_deg = 0.03;
  /// The Puma joints' encoder resolution at the joint: incremental encoders on the motor,
  /// 1000 counts a motor turn through gear ratios of 50-100 (joint readings in steps of it).
  double arm_encoder_deg = 0.005;
  /// From a command to the arm's first motion: VAL II plans each move at its next 28 ms
  /// trajectory tick.
  double arm_latency_ms = 28.0;
  /// The Biclops joints' encoder resolution: 12000 counts a joint turn (0.03 deg a count).
  double head_encoder_deg = 0.03;
  /// From a command to the head's first motion: the PMD chips' trajectory generators start on
  /// their next cycle (a few ms; a command's bytes on the 19200 baud line are the driver's).
  double head_latency_ms = 5.0;
  /// Std. dev. of each coordinate of the head's mounting on the torso (mm) and of each angle of
  /// it (deg). The servo needs no camera-to-arm calibration, so this error is the paper's
  /// point; it is off by default until the report's truth is taken in the W the pipeline
  /// believes (a mounting error moves every modelled box in W, which is not perception's).
  double head_mount_mm = 0.0;
  double head_mount_deg = 0.0;
  /// Std. dev. of each camera's focal length against its datasheet (%): lenses of one type
  /// differ by 1-2% in focal length, and the grabber's pixel clock adds its own scale; the
  /// calibration files the scanner reads are nominal until `hgrasp calibrate cameras` measures
  /// them. Off by default while the shipped calibration/sim/cameras.yaml is the nominal file
  /// for every seed's robot (the scenes would need one calibration each);
  /// scenarios/calibration_boards.yaml switches it on.
  double camera_focal_pct = 0.0;
};

/// A parsed and checked scenario file.
struct Scenario {
  std::string path;           ///< the file it came from (as given to LoadScenario)
  std::string name;           ///< required
  std::uint64_t seed = 0;     ///< every random draw in sim derives from it (DESIGN.md rule 6)
  double camera_noise = 0.0;  ///< std. dev. of Gaussian pixel noise, grey levels 0-255, >= 0
  /// Samples a pixel of the twin's colour frames (1, 4, 9 or 16: 1x1 to 4x4 on a grid): a real
  /// camera integrates the light over each pixel, so an edge crossing it gives a grey between
  /// its two sides; one sample a pixel aliases every edge by up to half a pixel. (The stripe
  /// keeps one sample a pixel: it is drawn from the labels and depth.) Sub-pixel corners need
  /// it (a chessboard's: calibration RMS 0.30 px at 1, 0.14 px at 4); the scenes keep 1 until
  /// their baselines are measured again with more.
  int camera_samples = 1;
  double ambient = 0.35;         ///< lighting.ambient, 0-1
  std::optional<double> wall_x;  ///< wall: {x: ...}: the plane x = wall_x (m), facing the robot
  std::vector<ObjectSpec> objects;
  std::vector<InterferenceSpec> interference;
  std::vector<BoardSpec> boards;  ///< calibration chessboards on stands
  std::optional<TaskSpec> task;
  RobotErrorsSpec robot_errors;  ///< robot_errors: {...}; absent: the defaults
  /// Each device's backend (drivers/config/device_config.h); a device not listed is simulated.
  drivers::DevicesConfig devices;
};

/// Reads and checks the scenario file at `path` (used as given; resolve it first with
/// hgrasp::ResolveDataPath where needed). Throws hgrasp::InputError when the file is missing or
/// unreadable, is not valid YAML, or holds a bad value.
Scenario LoadScenario(const std::string& path);

/// The scenario as YAML text that ParseScenario reads back to the same values (each number in the
/// shortest text that reads back to the same double; angles in degrees as the schema has them,
/// so they come back within 1e-12 rad): for `hgrasp generate`, which writes the scenes of a family
/// for users to read and keep. Throws std::invalid_argument when a device is not simulated (the
/// devices block is written only empty: generated scenes run on the twin).
std::string ScenarioYaml(const Scenario& scenario);

/// The corners of an object's footprint on the table, in W (x, y), counter-clockwise.
std::array<Eigen::Vector2d, 4> ObjectFootprint(const ObjectSpec& o);

/// Whether two footprints' interiors intersect (separating axis test on convex quadrilaterals);
/// footprints that merely touch (within 1 nm) do not.
bool FootprintsOverlap(const std::array<Eigen::Vector2d, 4>& a,
                       const std::array<Eigen::Vector2d, 4>& b);

/// Distance between two footprints (0 when their interiors overlap): for disjoint convex
/// polygons the nearest points include a vertex of one of them.
double FootprintDistance(const std::array<Eigen::Vector2d, 4>& a,
                         const std::array<Eigen::Vector2d, 4>& b);

/// Whether every corner of the footprint lies on the table top (kTableMinX..kTableMaxY).
bool FootprintOnTable(const std::array<Eigen::Vector2d, 4>& f);

/// Parses and checks scenario YAML text; `path_for_errors` names it in error messages and becomes
/// Scenario::path. Throws hgrasp::InputError.
Scenario ParseScenario(const std::string& yaml_text, const std::string& path_for_errors);

}  // namespace hgrasp::sim
