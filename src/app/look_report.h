#pragma once
/// @file What `hgrasp model`, `plan` and `run` share: the report of the task's look and plan
/// stages (range, boxes, target, grasp, and the sim's ground truth) and their pictures.

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>

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

/// The task's frame sink calls this for every frame: a frame of the look's sweep (laser on) has
/// its true stripe recorded in `truth` (nothing when `robot` is null: not every device is
/// simulated).
void RecordScanTruth(sim::SimRobot* robot, sim::ScanTruth* truth,
                     const device::StereoFrame& frame, const task::TaskView& view);

/// The ground truth of the task's look and plan, as the world is now: call it after Look (and
/// Plan) and before anything touches the objects. Objects, cameras and head (sim::TruthJson);
/// `range`: the scan against the true surfaces and stripe (sim::ScanTruth); `hoover`: the
/// segmentation against the faces the left camera sees (sim::CompareSegmentations); `boxes`: per
/// true object the fitted box that models it (sim::MatchBoxes), its centre, edge and yaw errors
/// and its colour name against the true one; `grasp`: the contacts' distances from the target
/// object's true faces. Logs the figures.
nlohmann::json LookTruth(sim::SimRobot& robot, const task::TaskResult& result,
                         const sim::ScanTruth& scan_truth);

/// The report's scenario, seed, range, boxes, target and (with `plan`) grasp from the task's
/// result, and `truth` (only when every device is simulated; LookTruth's, taken when the look
/// ended) as given. Writes segments.png and models.png, or with `plan` grasp.png, into out_dir;
/// unless `lean` (a sweep's scene) also range.ply, range.png, models.obj and, with `plan`,
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
