#include "sim/truth.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

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

namespace {

// A box-shaped geom: its centre pose in W and full edge lengths (m).
struct TrueBox {
  Pose3 X_WB = Pose3::Identity();
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  double Distance(const Eigen::Vector3d& p_W) const {
    return DistanceToBoxSurface(X_WB, size, p_W);
  }
};

// The table: 4 cm thick below z = 0 (models/humanoid.xml, geom "table").
TrueBox TableBox() {
  constexpr double kTableThickness = 0.04;
  TrueBox b;
  b.X_WB.translation() << 0.5 * (kTableMinX + kTableMaxX), 0.5 * (kTableMinY + kTableMaxY),
      -0.5 * kTableThickness;
  b.size << kTableMaxX - kTableMinX, kTableMaxY - kTableMinY, kTableThickness;
  return b;
}

// Must match the wall geom of World (sim/world.cc, ObjectsXml): 2 cm thick, 2 m wide, 1 m high,
// its near face the plane x = wall_x.
TrueBox WallBox(double wall_x) {
  TrueBox b;
  b.X_WB.translation() << wall_x + 0.01, 0.0, 0.5;
  b.size << 0.02, 2.0, 1.0;
  return b;
}

}  // namespace

double DistanceToTrueSurface(const World& world, const Eigen::Vector3d& p_W) {
  double d = TableBox().Distance(p_W);
  if (const auto& wall_x = world.scenario().wall_x) d = std::min(d, WallBox(*wall_x).Distance(p_W));
  for (const SimObject& o : world.objects())
    d = std::min(d, DistanceToBoxSurface(world.BodyPose(o.body), o.spec.size_O, p_W));
  return d;
}

int NearestBoxFace(const Pose3& X_WO, const Eigen::Vector3d& size_O, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p_O = X_WO.inverse() * p_W;
  // The signed distance beyond each face's plane (negative inside). The faces nearest to a point
  // are those it lies beyond (all equally near: the distance to each face rectangle is the norm
  // of the amounts beyond) or, inside the box, the one with the least negative value: the largest
  // value picks one of them either way.
  int best = 0;
  double best_q = -std::numeric_limits<double>::infinity();
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const double q = (face % 2 == 0 ? p_O[axis] : -p_O[axis]) - 0.5 * size_O[axis];
    if (q > best_q) {
      best_q = q;
      best = face;
    }
  }
  return best;
}

std::vector<int> TrueFaceLabels(const World& world, StereoRig* rig, int camera,
                                const std::vector<Eigen::Vector3d>& p_W, double tol_m) {
  const CameraView& view = rig->View(camera);
  const Pose3 X_CW = view.X_WC.inverse();
  const cv::Mat& label = view.images.label;

  // What each geom id is: an object's index, or one of these.
  constexpr int kOther = -1, kTable = -2, kWall = -3;
  const mjModel* m = world.model();
  std::vector<int> kind(m->ngeom, kOther);
  kind[world.Id(mjOBJ_GEOM, "table")] = kTable;
  const std::optional<double> wall_x = world.scenario().wall_x;
  if (wall_x) kind[world.Id(mjOBJ_GEOM, "wall")] = kWall;
  const std::vector<SimObject>& objects = world.objects();
  std::vector<Pose3> X_WO(objects.size());
  for (std::size_t i = 0; i < objects.size(); ++i) {
    kind[objects[i].geom] = static_cast<int>(i);
    X_WO[i] = world.BodyPose(objects[i].body);
  }
  const Eigen::Vector3d p_WC = view.X_WC.translation();  // the optical centre
  const TrueBox table = TableBox();
  const TrueBox wall = wall_x ? WallBox(*wall_x) : TrueBox();

  std::vector<int> codes(p_W.size(), kTruthNone);
  for (std::size_t i = 0; i < p_W.size(); ++i) {
    const std::optional<Eigen::Vector2d> uv = view.camera.Project(X_CW * p_W[i]);
    if (!uv) continue;
    // The pixel (column c, row r) has its centre at (u, v) = (c, r) (common/pinhole_camera.h).
    const long c = std::lround(uv->x()), r = std::lround(uv->y());
    if (c < 0 || r < 0 || c >= label.cols || r >= label.rows) continue;
    const int geom = label.at<int>(static_cast<int>(r), static_cast<int>(c));
    if (geom < 0 || geom >= m->ngeom) continue;
    const int k = kind[geom];
    if (k == kTable) {
      if (table.Distance(p_W[i]) <= tol_m) codes[i] = kTruthTable;
    } else if (k == kWall) {
      if (wall.Distance(p_W[i]) <= tol_m) codes[i] = kTruthWall;
    } else if (k >= 0) {
      const Eigen::Vector3d& size = objects[k].spec.size_O;
      if (DistanceToBoxSurface(X_WO[k], size, p_W[i]) > tol_m) continue;
      const int face = NearestBoxFace(X_WO[k], size, p_W[i]);
      // The label image shows the box's front wherever its back faces project: a point near a
      // face turned away from the camera is not what the camera sees there.
      const Eigen::Vector3d n_W = (face % 2 == 0 ? 1.0 : -1.0) * X_WO[k].linear().col(face / 2);
      if (n_W.dot(p_WC - p_W[i]) > 0.0) codes[i] = TruthFaceCode(k, face);
    }
  }
  return codes;
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

Pose3 TrueFromBelievedWorld(const World& world, const Pose3& X_WCL_believed) {
  const Pose3 X_WCL =
      Renderer::OpticalFramePose(world.data(), world.Id(mjOBJ_CAMERA, "camera_left"));
  return X_WCL * X_WCL_believed.inverse();
}

PoseError GripperPoseError(const World& world, device::Side side, const Pose3& X_WCL_believed,
                           const Pose3& X_WE_believed) {
  const std::string body = std::string(device::ToString(side)) + "_gripper";
  const Pose3 X_WE = world.BodyPose(world.Id(mjOBJ_BODY, body));
  const Pose3 X_WT = TrueFromBelievedWorld(world, X_WCL_believed) * X_WE_believed;
  PoseError e;
  e.translation_m = (X_WE.translation() - X_WT.translation()).norm();
  e.rotation_rad = Eigen::AngleAxisd(X_WE.linear().transpose() * X_WT.linear()).angle();
  return e;
}

}  // namespace hgrasp::sim
