#pragma once
/// @file What `hgrasp model`, `plan` and `run` share: the report of the task's look and plan
/// stages (range, boxes, target, grasp, and the sim's ground truth) and their pictures.

#include <chrono>
#include <nlohmann/json.hpp>
#include <string>

#include "model/box_fit.h"
#include "sim/scenario.h"
#include "sim/sim_devices.h"
#include "task/grasp_task.h"

namespace hgrasp::app {

/// The task's configuration from the scenario's task block (target, lift); defaults elsewhere.
task::TaskConfig TaskConfigFor(const sim::Scenario& scenario);

/// The report's scenario, seed, range, boxes, target and (with `plan`) grasp from the task's
/// result; with `robot` (only when every device is simulated) the ground truth of the boxes
/// and the grasp contacts. Writes range.ply, range.png, segments.png, models.png, models.obj
/// (and with `plan` grasp.png) into out_dir.
nlohmann::json LookReport(const sim::Scenario& scenario, sim::SimRobot* robot,
                          const task::TaskResult& result, const task::RobotModel& robot_model,
                          bool plan, const std::string& out_dir);

/// Wall-clock seconds since t0.
inline double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// The simulated object a fitted box models: the one whose centre is nearest the box's.
const sim::SimObject* TargetObject(const sim::World& world, const model::BoxModel& box);

}  // namespace hgrasp::app
