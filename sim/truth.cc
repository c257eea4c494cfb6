#include "sim/truth.h"

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

}  // namespace hgrasp::sim
