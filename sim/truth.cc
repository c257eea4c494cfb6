#include "sim/truth.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::sim {

nlohmann::json PoseJson(const Pose3& X) {
  nlohmann::json R = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) R.push_back({X.linear()(i, 0), X.linear()(i, 1), X.linear()(i, 2)});
  const auto& p = X.translation();
  return {{"p", {p.x(), p.y(), p.z()}}, {"R", R}};
}

nlohmann::json TruthJson(const World& world, const StereoRig& rig,
                         const std::vector<std::int32_t>& encoder_counts) {
  nlohmann::json t;
  t["time_s"] = world.time();
  nlohmann::json objects = nlohmann::json::array();
  for (const SimObject& o : world.objects()) {
    const Pose3 X_WO = world.BodyPose(o.body);
    nlohmann::json j = PoseJson(X_WO);
    objects.push_back(
        {{"name", o.spec.name},
         {"center_W", j["p"]},
         {"R_WO", j["R"]},
         {"size", {o.spec.size_O.x(), o.spec.size_O.y(), o.spec.size_O.z()}},
         {"color_rgb", {o.spec.color_rgb.x(), o.spec.color_rgb.y(), o.spec.color_rgb.z()}},
         {"specular", o.spec.specular}});
  }
  t["objects"] = objects;
  t["head"] = {{"pan", world.JointPosition("head_pan")},
               {"tilt", world.JointPosition("head_tilt")},
               {"verge", world.JointPosition("head_verge_left")}};
  nlohmann::json cams;
  for (int c : {kLeft, kRight}) {
    const int id = rig.camera_id(c);
    const PinholeCamera k = PinholeCamera::FromFovy(StereoRig::kWidth, StereoRig::kHeight,
                                                    DegToRad(world.model()->cam_fovy[id]));
    cams[c == kLeft ? "left" : "right"] = {
        {"X_WC", PoseJson(Renderer::OpticalFramePose(world.data(), id))},
        {"intrinsics",
         {{"width", k.width},
          {"height", k.height},
          {"fx", k.fx},
          {"fy", k.fy},
          {"cx", k.cx},
          {"cy", k.cy}}}};
  }
  t["cameras"] = cams;
  nlohmann::json planes = nlohmann::json::array();
  for (std::int32_t count : encoder_counts) {
    const Plane p = rig.LaserPlaneAt(count * kLaserRadPerCount);
    planes.push_back({{"count", count}, {"n_W", {p.n.x(), p.n.y(), p.n.z()}}, {"d", p.d}});
  }
  const Eigen::Vector3d s = rig.LaserSource();
  t["laser"] = {
      {"counts_per_rev", kLaserCountsPerRev},
      {"encoder_count_now",
       static_cast<std::int32_t>(std::lround(world.JointPosition("laser") / kLaserRadPerCount))},
      {"source_W", {s.x(), s.y(), s.z()}},
      {"planes", planes}};
  return t;
}

double DistanceToBoxSurface(const Pose3& X_WO, const Eigen::Vector3d& size_O,
                            const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p_O = X_WO.inverse() * p_W;
  // q: how far outside each pair of faces (negative: inside the slab).
  const Eigen::Vector3d q = p_O.cwiseAbs() - 0.5 * size_O;
  if ((q.array() > 0.0).any()) return q.cwiseMax(0.0).norm();
  return -q.maxCoeff();
}

double DistanceToTrueSurface(const World& world, const Eigen::Vector3d& p_W) {
  // The table: 4 cm thick below z = 0 (models/humanoid.xml, geom "table").
  constexpr double kTableThickness = 0.04;
  Pose3 X_W_table = Pose3::Identity();
  X_W_table.translation() << 0.5 * (kTableMinX + kTableMaxX), 0.5 * (kTableMinY + kTableMaxY),
      -0.5 * kTableThickness;
  double d = DistanceToBoxSurface(
      X_W_table, Eigen::Vector3d(kTableMaxX - kTableMinX, kTableMaxY - kTableMinY, kTableThickness),
      p_W);
  if (const auto& wall_x = world.scenario().wall_x) {
    // Must match the wall geom of World (sim/world.cc, ObjectsXml): 2 cm thick, 2 m wide, 1 m
    // high, its near face the plane x = wall_x.
    Pose3 X_W_wall = Pose3::Identity();
    X_W_wall.translation() << *wall_x + 0.01, 0.0, 0.5;
    d = std::min(d, DistanceToBoxSurface(X_W_wall, Eigen::Vector3d(0.02, 2.0, 1.0), p_W));
  }
  for (const SimObject& o : world.objects())
    d = std::min(d, DistanceToBoxSurface(world.BodyPose(o.body), o.spec.size_O, p_W));
  return d;
}

LaserPlaneError CompareLaserPlanes(const StereoRig& rig,
                                   const std::function<Plane(std::int32_t)>& planes_W,
                                   std::int32_t lo, std::int32_t hi) {
  const Eigen::Vector3d probes[] = {{0.30, 0.0, 0.05},
                                    {0.20, -0.15, 0.0},
                                    {0.20, 0.15, 0.0},
                                    {0.40, -0.15, 0.15},
                                    {0.40, 0.15, 0.15}};
  LaserPlaneError e;
  for (std::int32_t count = lo; count <= hi; count += 10) {
    const Plane truth = rig.LaserPlaneAt(count * kLaserRadPerCount);
    const Plane mine = planes_W(count);
    e.worst_deg =
        std::max(e.worst_deg, RadToDeg(std::acos(std::min(1.0, std::abs(truth.n.dot(mine.n))))));
    for (const Eigen::Vector3d& q : probes) {
      const Eigen::Vector3d on_truth = q - truth.SignedDistance(q) * truth.n;
      e.worst_mm = std::max(e.worst_mm, 1e3 * std::abs(mine.SignedDistance(on_truth)));
    }
  }
  return e;
}

}  // namespace hgrasp::sim
