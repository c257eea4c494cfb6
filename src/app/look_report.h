#pragma once
/// @file What `hgrasp model`, `plan` and `run` share: the report of the task's look and plan
/// stages (range, boxes, target, grasp, and the sim's ground truth) and their pictures.

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>

#include "app/devices.h"
#include "model/box_fit.h"
#include "sim/scan_truth.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "task/grasp_task.h"

namespace hgrasp::app {

/// The task's configuration from the scenario's task block (target, lift); defaults elsewhere.
task::TaskConfig TaskConfigFor(const sim::Scenario& scenario);

/// Truth regions (visible faces) of fewer range points are left out of the Hoover counts.
inline constexpr int kHooverMinCells = 50;

/// The true stripe of every frame of the task's look, recorded as the frames are made (nothing
/// when the robot has no truth, Robot::truth): on simulated devices from the cameras' rig as the
/// task's sink hands on each frame (OnFrame), in lockstep from the twin's renders until Stop.
class ScanTruthRecorder {
 public:
  explicit ScanTruthRecorder(Robot& robot);
  ~ScanTruthRecorder();
  ScanTruthRecorder(const ScanTruthRecorder&) = delete;
  ScanTruthRecorder& operator=(const ScanTruthRecorder&) = delete;

  /// The task's frame sink calls this for every frame: a frame of the look's sweep (laser on,
  /// with images) has its true stripe recorded.
  void OnFrame(const device::StereoFrame& frame, const task::TaskView& view);
  /// The look is over: frames after it (the lift's rise scan) are not the look's.
  void Stop();
  const sim::ScanTruth& truth() const { return truth_; }

 private:
  Robot& robot_;
  sim::ScanTruth truth_;
  bool recording_ = true;
};

/// The ground truth of the task's look and plan, as the world is now: call it after Look (and
/// Plan) and before anything touches the objects. Objects, cameras and head (sim::TruthJson);
/// `range`: the scan against the true surfaces and stripe (sim::ScanTruth); `hoover`: the
/// segmentation against the faces the left camera sees (sim::CompareSegmentations); `boxes`: per
/// true object the fitted box that models it (sim::MatchBoxes), its centre, edge and yaw errors
/// and its colour name against the true one; `grasp`: the contacts' distances from the target
/// object's true faces. Logs the figures.
nlohmann::json LookTruth(const TruthWorld& truth, const task::TaskResult& result,
                         const sim::ScanTruth& scan_truth);

/// The report's scenario, seed, range, boxes, target and (with `plan`) grasp from the task's
/// result, and `truth` (only when the robot has one, Robot::truth; LookTruth's, taken when the
/// look ended) as given. Writes segments.png and models.png, or with `plan` grasp.png, into
/// out_dir; unless `lean` (a sweep's scene) also range.ply, range.png, models.obj and, with `plan`,
/// models.png.
nlohmann::json LookReport(const sim::Scenario& scenario, const nlohmann::json* truth,
                          const task::TaskResult& result, const task::RobotModel& robot_model,
                          bool plan, const std::string& out_dir, bool lean);

/// Wall-clock seconds since t0.
inline double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The simulated object a fitted box models: the one whose centre is nearest the box's.
const sim::SimObject* TargetObject(const sim::World& world, const model::BoxModel& box);

}  // namespace hgrasp::app
