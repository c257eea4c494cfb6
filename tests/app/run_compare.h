#pragma once
// Comparing a run through the real drivers (against `hgrasp twin`, or in lockstep) with the
// simulated-device run of the same scene: the boxes each modelled, and where the twin's truth
// had the gripper when the hand began to close on the box.

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

namespace hgrasp::testing {

inline Eigen::Vector3d Vec(const nlohmann::json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

inline Eigen::Matrix3d Mat(const nlohmann::json& j) {
  Eigen::Matrix3d R;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R(r, c) = j[r][c].get<double>();
  return R;
}

// The largest difference between two boxes' edge lengths, each edge of `a` against the edge of
// `b` along the same direction (a box's axes may come in another order, or turned half a turn).
inline double SizeError(const nlohmann::json& a, const nlohmann::json& b) {
  const Eigen::Matrix3d Ra = Mat(a["R_WO"]), Rb = Mat(b["R_WO"]);
  const Eigen::Vector3d sa = Vec(a["size"]), sb = Vec(b["size"]);
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) {
    int along = 0;
    (Rb.transpose() * Ra.col(i)).cwiseAbs().maxCoeff(&along);
    worst = std::max(worst, std::abs(sa[i] - sb[along]));
  }
  return worst;
}

// Each box of `report` against the nearest box of `other`: the worst centre distance and the
// worst edge difference (m); both 1e9 when the counts differ.
struct BoxAgreement {
  double centre_m = 0.0, size_m = 0.0;
};
inline BoxAgreement CompareBoxes(const nlohmann::json& report, const nlohmann::json& other) {
  BoxAgreement a;
  if (report["boxes"].size() != other["boxes"].size()) return {1e9, 1e9};
  for (const nlohmann::json& b : report["boxes"]) {
    double best = 1e9, size_err = 1e9;
    for (const nlohmann::json& s : other["boxes"]) {
      const double d = (Vec(b["center_W"]) - Vec(s["center_W"])).norm();
      if (d < best) {
        best = d;
        size_err = SizeError(b, s);
      }
    }
    a.centre_m = std::max(a.centre_m, best);
    a.size_m = std::max(a.size_m, size_err);
  }
  return a;
}

// The twin's true gripper when the plan's hand began its last close against the plan (mm, deg);
// false when the twin saw no close of that hand.
inline bool GripError(const nlohmann::json& twin_truth, const nlohmann::json& report, double* mm,
                      double* deg) {
  if (!report["grasp"].is_object()) return false;
  const std::string side = report["grasp"]["arm"];
  nlohmann::json grip;
  for (const nlohmann::json& g : twin_truth["grips"]) {
    if (g["side"] == side) grip = g;
  }
  if (!grip.is_object()) return false;
  *mm = 1e3 * (Vec(grip["p"]) - Vec(report["grasp"]["p_WE"])).norm();
  const Eigen::AngleAxisd turn(Mat(grip["R"]).transpose() * Mat(report["grasp"]["R_WE"]));
  *deg = turn.angle() * 180.0 / 3.14159265358979323846;
  return true;
}

}  // namespace hgrasp::testing
