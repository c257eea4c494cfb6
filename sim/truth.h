#pragma once
/// @file Simulator ground truth for reports and tests (never read by the pipeline).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <vector>

#include "sim/stereo_rig.h"
#include "sim/world.h"

namespace hgrasp::sim {

/// JSON of a pose: {"p": [x, y, z], "R": [[...], [...], [...]]} (row-major rotation).
nlohmann::json PoseJson(const Pose3& X);

/// Ground truth now: objects (centre pose, size, colour), head joints, both cameras (optical
/// frame pose X_WC and intrinsics), and the laser's light plane in W for each encoder count in
/// `encoder_counts` with the head where it is now: {"count", "n_W", "d"} meaning n.p + d = 0.
nlohmann::json TruthJson(const World& world, const StereoRig& rig,
                         const std::vector<std::int32_t>& encoder_counts);

}  // namespace hgrasp::sim
