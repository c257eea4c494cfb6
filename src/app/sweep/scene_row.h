#pragma once
/// @file A sweep's row for one scene: how its process ended and its figures against the
/// simulator's truth, taken from the scene's report.json (whose `truth` the sim's truth code
/// wrote: sim/truth.h, sim/scan_truth.h, sim/box_truth.h, sim/hoover.h), never recomputed by the
/// pipeline. The row's fields are those of summary.json's `scenes` (README, "hgrasp sweep").

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "app/sweep/scene_process.h"

namespace hgrasp::app::sweep {

/// A box counts as within tolerance when found with the right colour name and its centre, worst
/// edge and yaw errors are at most these (mm, mm, deg).
inline constexpr double kCenterToleranceMm = 3.0;
inline constexpr double kEdgeToleranceMm = 4.0;
inline constexpr double kYawToleranceDeg = 2.0;
/// A held box counts as truly lifted when it rose at least this fraction of the task's lift.
inline constexpr double kTrueLiftFraction = 0.9;

/// The stages a sweep runs its scenes to, in order.
inline constexpr const char* kStages[] = {"scan", "model", "plan", "run"};

/// What the sweep knows of a scene before it runs.
struct SceneEntry {
  std::string scene;  ///< its key: unique in the sweep (the scenario file's stem)
  std::string file;   ///< the scenario file (absolute)
};

/// The row of a scene whose process ended with `outcome`. `report` is its report.json (nullopt
/// when it wrote none), `log_tail` the last lines of its output (for the failure's detail),
/// `dir` its output folder relative to the sweep's folder (the pictures' paths start with it),
/// `existing_pictures` says which picture files (relative paths) are there.
nlohmann::json MakeRow(const SceneEntry& entry, const std::string& stage,
                       const ProcessOutcome& outcome, const std::optional<nlohmann::json>& report,
                       const std::string& log_tail, const std::string& dir,
                       const std::vector<std::string>& existing_pictures);

/// The pictures a scene of `stage` writes, by file name (segments.png, grasp.png, ...).
std::vector<std::string> PictureNames(const std::string& stage);

/// The last `lines` lines of a text file ("" when it cannot be read).
std::string Tail(const std::string& path, int lines);

}  // namespace hgrasp::app::sweep
