#include "grasp/grasp_planner.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace hgrasp::grasp {
namespace {

using Eigen::Vector3d;

OrientedBox BoxOf(const model::BoxModel& b) {
  return {b.X_WO.translation(), b.X_WO.linear(), b.size_O};
}

/// Whether the hand at X_WE with this opening clears the table and every box but `target`.
bool HandClear(const Pose3& X_WE, double opening, const std::vector<model::BoxModel>& boxes,
               int target, const GraspConfig& config) {
  for (const OrientedBox& part : HandBoxes(X_WE, opening, config.hand)) {
    double lowest = part.centre.z();
    for (int k = 0; k < 3; ++k) lowest -= 0.5 * part.size[k] * std::abs(part.R(2, k));
    if (lowest < config.table_clearance_m) return false;
    for (size_t i = 0; i < boxes.size(); ++i) {
      if (static_cast<int>(i) != target && Overlap(part, BoxOf(boxes[i]))) return false;
    }
  }
  return true;
}

/// Whether the arm's links clear the boxes and the table at arm_path_steps steps of the
/// joint-space move from q0 to q1, both ends included.
bool PathClear(const robot::ArmKinematics& arm, const device::Joint6& q0, const device::Joint6& q1,
               const std::vector<model::BoxModel>& boxes, const GraspConfig& config) {
  const int steps = std::max(1, config.arm_path_steps);
  for (int k = 0; k <= steps; ++k) {
    const device::Joint6 q = q0 + (q1 - q0) * (static_cast<double>(k) / steps);
    if (!ArmClear(arm, q, boxes, config)) return false;
  }
  return true;
}

double PointBoxDistance(const Vector3d& p, const OrientedBox& box) {
  const Vector3d local = box.R.transpose() * (p - box.centre);
  return (local.cwiseAbs() - 0.5 * box.size).cwiseMax(0.0).norm();
}

}  // namespace

double SegmentBoxDistance(const Vector3d& a, const Vector3d& b, const OrientedBox& box) {
  const Vector3d ab = b - a;
  // The distance to a convex set is convex along the segment: a golden-section search finds its
  // minimum (to 1e-8 of the segment's length in 40 steps).
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  double lo = 0.0, hi = 1.0;
  double t1 = hi - g * (hi - lo), t2 = lo + g * (hi - lo);
  double f1 = PointBoxDistance(a + t1 * ab, box), f2 = PointBoxDistance(a + t2 * ab, box);
  for (int i = 0; i < 40; ++i) {
    if (f1 <= f2) {
      hi = t2, t2 = t1, f2 = f1;
      t1 = hi - g * (hi - lo);
      f1 = PointBoxDistance(a + t1 * ab, box);
    } else {
      lo = t1, t1 = t2, f1 = f2;
      t2 = lo + g * (hi - lo);
      f2 = PointBoxDistance(a + t2 * ab, box);
    }
  }
  return std::min({f1, f2, PointBoxDistance(a, box), PointBoxDistance(b, box)});
}

bool ArmClear(const robot::ArmKinematics& arm, const device::Joint6& q,
              const std::vector<model::BoxModel>& boxes, const GraspConfig& config) {
  for (const robot::Capsule& c : arm.LinkCapsules(q)) {
    if (std::min(c.a.z(), c.b.z()) - c.radius < config.table_clearance_m) return false;
    const double reach = c.radius + config.arm_clearance_m;
    const Vector3d mid = 0.5 * (c.a + c.b);
    const double half_length = 0.5 * (c.b - c.a).norm();
    for (const model::BoxModel& model : boxes) {
      const OrientedBox box = BoxOf(model);
      // Far apart (the spheres around both further than reach): no search.
      if ((mid - box.centre).norm() - half_length - 0.5 * box.size.norm() >= reach) continue;
      if (SegmentBoxDistance(c.a, c.b, box) < reach) return false;
    }
  }
  return true;
}

std::array<OrientedBox, 3> HandBoxes(const Pose3& X_WE, double opening_m,
                                     const HandGeometry& hand) {
  const Eigen::Matrix3d& R = X_WE.linear();
  const double half = 0.5 * opening_m + 0.5 * hand.pad_size.x();
  const Vector3d thumb(-half, 0.0, hand.pad_centre_z_m), index(half, 0.0, hand.pad_centre_z_m);
  return {OrientedBox{X_WE * hand.palm_centre, R, hand.palm_size},
          OrientedBox{X_WE * thumb, R, hand.pad_size}, OrientedBox{X_WE * index, R, hand.pad_size}};
}

bool Overlap(const OrientedBox& a, const OrientedBox& b) {
  const Vector3d d = b.centre - a.centre;
  std::vector<Vector3d> axes;
  for (int i = 0; i < 3; ++i) axes.push_back(a.R.col(i));
  for (int i = 0; i < 3; ++i) axes.push_back(b.R.col(i));
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const Vector3d c = a.R.col(i).cross(b.R.col(j));
      if (c.norm() > 1e-9) axes.push_back(c.normalized());
    }
  }
  for (const Vector3d& n : axes) {
    double ra = 0, rb = 0;
    for (int k = 0; k < 3; ++k) {
      ra += 0.5 * a.size[k] * std::abs(n.dot(a.R.col(k)));
      rb += 0.5 * b.size[k] * std::abs(n.dot(b.R.col(k)));
    }
    if (std::abs(n.dot(d)) > ra + rb) return false;
  }
  return true;
}

std::optional<GraspPlan> PlanGrasp(const std::vector<model::BoxModel>& boxes, int target,
                                   const std::array<const robot::ArmKinematics*, 2>& arms,
                                   const GraspConfig& config, std::vector<GraspPlan>* feasible) {
  HGRASP_DEMAND(target >= 0 && target < static_cast<int>(boxes.size()));
  const model::BoxModel& box = boxes[target];
  const Eigen::Matrix3d& R_WO = box.X_WO.linear();
  const Vector3d centre = box.X_WO.translation();
  const double top_z = centre.z() + 0.5 * box.size_O.z();
  std::optional<GraspPlan> best;
  if (feasible != nullptr) feasible->clear();

  for (int axis = 0; axis < 2; ++axis) {  // the pair of faces along O's x, then O's y
    const double width = box.size_O[axis];
    const double opening = width + 2.0 * config.clearance_m;
    if (opening > config.hand.max_opening_m) continue;  // the aperture check
    // Contacts: the middles of the two faces, delta below the top.
    const Vector3d e = R_WO.col(axis);
    Vector3d mid = centre;
    mid.z() = top_z - config.delta_m;
    std::array<Vector3d, 2> c = {mid - 0.5 * width * e, mid + 0.5 * width * e};
    // The thumb on the face nearer the robot (W's origin, below the head, in the horizontal).
    if (c[0].head<2>().norm() > c[1].head<2>().norm()) std::swap(c[0], c[1]);
    // R1: x_E from thumb to index; R2 about x_E puts the palm above the top (z_E down), tilted.
    const Vector3d x = (c[1] - c[0]).normalized();
    Vector3d down = -Vector3d::UnitZ();
    down = (down - x * x.dot(down)).normalized();
    for (const double tilt_deg : config.tilts_deg) {
      const double tilt = DegToRad(tilt_deg);
      const Vector3d z = Eigen::AngleAxisd(tilt, x) * down;
      Pose3 X_WE = Pose3::Identity();
      X_WE.linear().col(0) = x;
      X_WE.linear().col(1) = z.cross(x);
      X_WE.linear().col(2) = z;
      X_WE.translation() = 0.5 * (c[0] + c[1]) - config.hand.contact_z_m * z;  // t_g
      Pose3 X_WE_pre = X_WE;
      X_WE_pre.translation() -= config.approach_m * z;
      Pose3 X_WE_via = X_WE_pre;
      X_WE_via.translation().z() += config.via_height_m;
      if (!HandClear(X_WE, opening, boxes, target, config) ||
          !HandClear(X_WE_pre, opening, boxes, target, config) ||
          !HandClear(X_WE_via, opening, boxes, target, config)) {
        continue;
      }
      for (int side = 0; side < 2; ++side) {
        const robot::ArmKinematics& arm = *arms[side];
        const std::vector<robot::ArmIkSolution> pre = arm.Inverse(X_WE_pre);
        const std::vector<robot::ArmIkSolution> via = arm.Inverse(X_WE_via);
        // The solution of `among` in the configuration of s, within the limits; null if none.
        auto same_configuration = [&](const std::vector<robot::ArmIkSolution>& among,
                                      const robot::ArmIkSolution& s) {
          const robot::ArmIkSolution* found = nullptr;
          for (const robot::ArmIkSolution& t : among) {
            if (t.shoulder == s.shoulder && t.elbow == s.elbow && t.wrist == s.wrist &&
                arm.WithinLimits(t.q)) {
              found = &t;
            }
          }
          return found;
        };
        for (const robot::ArmIkSolution& s : arm.Inverse(X_WE)) {
          if (!arm.WithinLimits(s.q)) continue;
          // The pre-grasp and the via pose in the same configuration (short moves).
          const robot::ArmIkSolution* p = same_configuration(pre, s);
          const robot::ArmIkSolution* v = same_configuration(via, s);
          if (p == nullptr || v == nullptr) continue;
          if (!PathClear(arm, v->q, p->q, boxes, config) ||
              !PathClear(arm, p->q, s.q, boxes, config)) {
            continue;
          }
          GraspPlan plan;
          plan.box = target;
          plan.side = side == 0 ? device::Side::kLeft : device::Side::kRight;
          plan.X_WE = X_WE;
          plan.X_WE_pre = X_WE_pre;
          plan.q = s.q;
          plan.q_pre = p->q;
          plan.X_WE_via = X_WE_via;
          plan.q_via = v->q;
          plan.contacts_W = c;
          plan.opening_m = opening;
          plan.tilt_rad = tilt;
          // Comfort (paper): the smallest angle between the forearm and the hand's approach.
          plan.comfort_rad = std::acos(std::clamp(arm.ForearmDirection(s.q).dot(z), -1.0, 1.0));
          if (feasible != nullptr) feasible->push_back(plan);
          if (!best || plan.comfort_rad < best->comfort_rad) best = plan;
        }
      }
    }
  }
  return best;
}

}  // namespace hgrasp::grasp
