#include "sim/world.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "common/error.h"
#include "common/paths.h"
#include "robot/kinematic_tree.h"

namespace hgrasp::sim {
namespace {

std::string ReadFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "", path, "a readable MJCF model file");
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// Loads MJCF text through MuJoCo's virtual file system (no temporary files).
mjModel* LoadFromString(const std::string& xml, const std::string& name) {
  // On the heap: MuJoCo 2.2's mjVFS holds the names of mjMAXVFS files inline, 2 MB, a quarter of
  // a thread's default stack.
  auto vfs = std::make_unique<mjVFS>();
  mj_defaultVFS(vfs.get());
  if (mj_makeEmptyFileVFS(vfs.get(), name.c_str(), static_cast<int>(xml.size())) != 0) {
    throw std::runtime_error("MuJoCo VFS: cannot hold " + name);
  }
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), name.c_str())], xml.data(), xml.size());
  char error[1024] = "";
  mjModel* m = mj_loadXML(name.c_str(), vfs.get(), error, sizeof error);
  mj_deleteVFS(vfs.get());
  if (m == nullptr) throw std::runtime_error("MuJoCo rejected the model " + name + ": " + error);
  return m;
}

std::string Num(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

// The scenario's objects (and wall) as MJCF, to go inside <worldbody>.
std::string ObjectsXml(const Scenario& sc) {
  std::ostringstream x;
  for (const ObjectSpec& o : sc.objects) {
    const Eigen::Vector3d h = 0.5 * o.size_O;
    const std::string name = "obj_" + o.name;
    // Start 0.1 mm above the table so the first contact is gentle.
    x << "<body name=\"" << name << "\" pos=\"" << Num(o.position_W.x()) << " "
      << Num(o.position_W.y()) << " " << Num(h.z() + 1e-4) << "\" quat=\""
      << Num(std::cos(0.5 * o.yaw)) << " 0 0 " << Num(std::sin(0.5 * o.yaw)) << "\">"
      << "<freejoint name=\"" << name
      << "\"/>"
      // Explicit inertia of a uniform box: the model may not infer inertia from geoms.
      << "<inertial pos=\"0 0 0\" mass=\"" << Num(o.mass) << "\" diaginertia=\""
      << Num(o.mass / 3.0 * (h.y() * h.y() + h.z() * h.z())) << " "
      << Num(o.mass / 3.0 * (h.x() * h.x() + h.z() * h.z())) << " "
      << Num(o.mass / 3.0 * (h.x() * h.x() + h.y() * h.y())) << "\"/>"
      << "<geom name=\"" << name << "\" type=\"box\" size=\"" << Num(h.x()) << " " << Num(h.y())
      << " " << Num(h.z()) << "\" rgba=\"" << Num(o.color_rgb.x()) << " " << Num(o.color_rgb.y())
      << " " << Num(o.color_rgb.z())
      << " 1\" contype=\"1\" conaffinity=\"1\" friction=\"1 0.005 0.0001\""
      << (o.specular ? " material=\"specular_" + o.name + "\"" : std::string()) << "/>"
      << "</body>\n";
  }
  // Chessboards on stands: a white plate, its face at B z = 0, and black squares 0.04 mm proud
  // of it (under a micrometre of depth resolution there: no fighting over the face).
  for (std::size_t i = 0; i < sc.boards.size(); ++i) {
    const BoardSpec& b = sc.boards[i];
    const Pose3 X_WB = b.X_WB();
    const Eigen::Quaterniond q(X_WB.linear());
    const Eigen::Vector2d half = b.HalfExtent();
    const std::string name = "board_" + std::to_string(i);
    x << "<body name=\"" << name << "\" pos=\"" << Num(X_WB.translation().x()) << " "
      << Num(X_WB.translation().y()) << " " << Num(X_WB.translation().z()) << "\" quat=\""
      << Num(q.w()) << " " << Num(q.x()) << " " << Num(q.y()) << " " << Num(q.z()) << "\">"
      << "<geom name=\"" << name << "\" type=\"box\" pos=\"0 0 -0.0025\" size=\""
      << Num(half.x()) << " " << Num(half.y()) << " 0.0025\" material=\"board_white\"/>";
    const double s = b.square_m;
    for (int a = 0; a <= b.cols; ++a) {
      for (int c = 0; c <= b.rows; ++c) {
        if ((a + c) % 2 != 0) continue;  // square (0, 0), at the plate's -x, -y corner, is black
        x << "<geom type=\"box\" pos=\"" << Num((a - 0.5 * b.cols) * s) << " "
          << Num((c - 0.5 * b.rows) * s) << " 0.00002\" size=\"" << Num(0.5 * s) << " "
          << Num(0.5 * s) << " 0.00002\" material=\"board_black\" contype=\"0\" "
          << "conaffinity=\"0\"/>";
      }
    }
    x << "</body>\n";
  }
  if (sc.wall_x) {
    x << "<geom name=\"wall\" type=\"box\" pos=\"" << Num(*sc.wall_x + 0.01)
      << " 0 0.5\" size=\"0.01 1.0 0.5\" rgba=\"0.85 0.85 0.82 1\" contype=\"1\""
         " conaffinity=\"1\"/>\n";
  }
  return x.str();
}

std::string MaterialsXml(const Scenario& sc) {
  std::ostringstream x;
  if (!sc.boards.empty()) {
    // Matte print: a highlight on the board would wash out its corners.
    x << "<material name=\"board_white\" rgba=\"0.92 0.92 0.92 1\" specular=\"0\" "
         "shininess=\"0\"/>\n"
      << "<material name=\"board_black\" rgba=\"0.04 0.04 0.04 1\" specular=\"0\" "
         "shininess=\"0\"/>\n";
  }
  for (const ObjectSpec& o : sc.objects) {
    if (!o.specular) continue;
    x << "<material name=\"specular_" << o.name << "\" rgba=\"" << Num(o.color_rgb.x()) << " "
      << Num(o.color_rgb.y()) << " " << Num(o.color_rgb.z())
      << " 1\" specular=\"1\" shininess=\"1\"/>\n";
  }
  return x.str();
}

// Inserts `text` before the last occurrence of `tag` in `xml`.
void InsertBefore(std::string* xml, const std::string& tag, const std::string& text,
                  const std::string& path) {
  const size_t at = xml->rfind(tag);
  if (at == std::string::npos) throw InputError(path, tag, "", "an MJCF file with " + tag);
  xml->insert(at, text);
}

// Smooth 0..1 position profile with zero speed at both ends; peak slope 1.5.
double Smoothstep(double s) { return s * s * (3.0 - 2.0 * s); }

// Time a constant-speed move (the laser motor) takes to reach full speed and to stop.
constexpr double kRampS = 0.04;

// 0..1 position of a constant-speed move of `duration` s at time t: speed ramps up linearly
// over kRampS, cruises, ramps down over kRampS (a DC motor's finite acceleration).
double Trapezoid(double t, double duration) {
  if (duration <= 0) return 1.0;  // already there
  if (duration <= 2 * kRampS) return Smoothstep(std::clamp(t / duration, 0.0, 1.0));
  const double v = 1.0 / (duration - kRampS);  // cruise speed, so that the ramps fit
  if (t <= 0) return 0.0;
  if (t < kRampS) return 0.5 * v * t * t / kRampS;
  if (t < duration - kRampS) return v * (t - 0.5 * kRampS);
  if (t < duration) return 1.0 - 0.5 * v * (duration - t) * (duration - t) / kRampS;
  return 1.0;
}

}  // namespace

World::World(Scenario scenario, const WorldOptions& options)
    : scenario_(std::move(scenario)),
      errors_(DrawRobotErrors(scenario_.robot_errors, scenario_.seed)) {
  const std::string& model_path = options.model_path;
  const std::string path = ResolveDataPath(model_path);
  std::string xml = ReadFile(path);

  // The robot alone first: its keyframe "home" (the composed model has more qpos than the key).
  mjModel* robot = LoadFromString(xml, "humanoid.xml");
  mjData* robot_data = mj_makeData(robot);
  const int home = mj_name2id(robot, mjOBJ_KEY, "home");
  if (home < 0) {
    mj_deleteData(robot_data);
    mj_deleteModel(robot);
    throw InputError(path, "keyframe", "", "a keyframe named 'home'");
  }
  mj_resetDataKeyframe(robot, robot_data, home);
  std::map<std::string, double> home_q, home_ctrl;
  for (int j = 0; j < robot->njnt; ++j) {
    if (robot->jnt_type[j] == mjJNT_HINGE || robot->jnt_type[j] == mjJNT_SLIDE) {
      home_q[mj_id2name(robot, mjOBJ_JOINT, j)] = robot_data->qpos[robot->jnt_qposadr[j]];
    }
  }
  for (int a = 0; a < robot->nu; ++a)
    home_ctrl[mj_id2name(robot, mjOBJ_ACTUATOR, a)] = robot_data->ctrl[a];
  mj_deleteData(robot_data);
  mj_deleteModel(robot);

  // The keyframes are the robot's alone (their qpos lacks the objects): applied above by name.
  if (const size_t k0 = xml.find("<keyframe>"), k1 = xml.find("</keyframe>");
      k0 != std::string::npos && k1 != std::string::npos) {
    xml.erase(k0, k1 + std::string("</keyframe>").size() - k0);
  }
  InsertBefore(&xml, "</worldbody>", ObjectsXml(scenario_) + options.extra_worldbody_xml, path);
  InsertBefore(&xml, "</mujoco>", "<asset>\n" + MaterialsXml(scenario_) + "</asset>\n", path);
  model_ = LoadFromString(xml, "scene.xml");
  model_->vis.headlight.ambient[0] = model_->vis.headlight.ambient[1] =
      model_->vis.headlight.ambient[2] = static_cast<float>(scenario_.ambient);
  nominal_model_ = mj_copyModel(nullptr, model_);
  // The true robot: each link where robot_errors put it in its parent.
  for (const auto& [body, offset] : errors_.body_offsets) {
    mjtNum* pos = model_->body_pos + 3 * Id(mjOBJ_BODY, body);
    for (int i = 0; i < 3; ++i) pos[i] += offset[i];
  }
  const Pose3 head_mount = options.head_mount_error * errors_.head_mount;
  if (!head_mount.isApprox(Pose3::Identity(), 0.0)) {
    // X_PT = X_PM * X_MT: the head's body frame in its parent (the torso), displaced.
    const int head = Id(mjOBJ_BODY, "head_pan_link");
    mjtNum* pos = model_->body_pos + 3 * head;
    mjtNum* quat = model_->body_quat + 4 * head;
    Pose3 X_PM = Pose3::Identity();
    X_PM.translation() = Eigen::Vector3d(pos[0], pos[1], pos[2]);
    X_PM.linear() = Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]).toRotationMatrix();
    const Pose3 X_PT = X_PM * head_mount;
    const Eigen::Quaterniond q(X_PT.linear());
    for (int i = 0; i < 3; ++i) pos[i] = X_PT.translation()[i];
    quat[0] = q.w(), quat[1] = q.x(), quat[2] = q.y(), quat[3] = q.z();
  }
  // The true cameras: each one's focal length scaled, its field of view narrowed by as much.
  for (int c = 0; c < 2; ++c) {
    const double scale = errors_.camera_focal_scale[c];
    if (scale == 1.0) continue;
    const int id = Id(mjOBJ_CAMERA, c == 0 ? "camera_left" : "camera_right");
    const double half_fovy = DegToRad(0.5 * model_->cam_fovy[id]);
    model_->cam_fovy[id] = RadToDeg(2.0 * std::atan(std::tan(half_fovy) / scale));
  }
  data_ = mj_makeData(model_);

  for (const auto& [name, q] : home_q) data_->qpos[model_->jnt_qposadr[Id(mjOBJ_JOINT, name)]] = q;
  for (const auto& [name, u] : home_ctrl) data_->ctrl[Id(mjOBJ_ACTUATOR, name)] = u;
  for (const ObjectSpec& o : scenario_.objects) {
    SimObject so;
    so.spec = o;
    so.body = Id(mjOBJ_BODY, "obj_" + o.name);
    so.geom = Id(mjOBJ_GEOM, "obj_" + o.name);
    objects_.push_back(so);
  }

  // Speed limits come from the URDF: one robot model for sim, drivers and pipeline.
  const auto tree = robot::KinematicTree::FromUrdfFile(
      ResolveDataPath(std::filesystem::path(model_path).replace_extension(".urdf").string()));
  speed_limit_.assign(model_->nu, 0.0);
  motion_.assign(model_->nu, Motion{});
  joint_error_.assign(model_->nu, JointError{});
  dir_.assign(model_->nu, 0);
  for (const auto& [name, e] : errors_.joints) joint_error_[Id(mjOBJ_ACTUATOR, name)] = e;
  // At home each joint stands at the whole encoder count nearest the keyframe's angle (the
  // controllers servo to counts): its encoder reads the count, the link stands off it by the
  // zero error.
  for (int a = 0; a < model_->nu; ++a) {
    const JointError& e = joint_error_[a];
    if (e.resolution_rad <= 0) continue;
    const double count =
        e.resolution_rad * std::round((data_->ctrl[a] - e.zero_rad) / e.resolution_rad);
    data_->ctrl[a] = LinkAngle(a, count);
    data_->qpos[model_->jnt_qposadr[model_->actuator_trnid[2 * a]]] = data_->ctrl[a];
  }
  for (int a = 0; a < model_->nu; ++a) {
    const int joint = model_->actuator_trnid[2 * a];
    speed_limit_[a] = tree.Limits(mj_id2name(model_, mjOBJ_JOINT, joint)).velocity;
  }
  for (int j = 0; j < model_->njnt; ++j) {
    if (model_->jnt_type[j] == mjJNT_FREE) continue;
    robot_dofs_.push_back(model_->jnt_dofadr[j]);
  }
  led_on_material_ = Id(mjOBJ_MATERIAL, "led_on");
  led_off_material_ = Id(mjOBJ_MATERIAL, "led_off");

  mj_forward(model_, data_);
  Step(options.settle_s);
}

World::~World() {
  mj_deleteData(data_);
  mj_deleteModel(model_);
  mj_deleteModel(nominal_model_);
}

double World::LinkAngle(int a, double encoder) const {
  const JointError& e = joint_error_[a];
  return encoder + e.zero_rad - 0.5 * dir_[a] * e.backlash_rad;
}

double World::EncoderSetpoint(int a) const {
  const JointError& e = joint_error_[a];
  return data_->ctrl[a] - e.zero_rad + 0.5 * dir_[a] * e.backlash_rad;
}

double World::EncoderReading(int a) const {
  const JointError& e = joint_error_[a];
  const int joint = model_->actuator_trnid[2 * a];
  const double raw =
      data_->qpos[model_->jnt_qposadr[joint]] - e.zero_rad + 0.5 * dir_[a] * e.backlash_rad;
  return e.resolution_rad > 0 ? e.resolution_rad * std::round(raw / e.resolution_rad) : raw;
}

int World::Id(mjtObj type, const std::string& name) const {
  const int id = mj_name2id(model_, type, name.c_str());
  if (id < 0)
    throw std::runtime_error("model has no " + std::string(mju_type2Str(type)) + " '" + name + "'");
  return id;
}

double World::JointPosition(const std::string& joint) const {
  return data_->qpos[model_->jnt_qposadr[Id(mjOBJ_JOINT, joint)]];
}

void World::StartMotion(const std::vector<int>& actuators, const std::vector<double>& goal,
                        const std::vector<double>& speed_limit, bool constant_speed) {
  HGRASP_DEMAND(actuators.size() == goal.size() && goal.size() == speed_limit.size());
  double duration = 0.0, latency = 0.0;
  std::vector<double> link_goal(goal.size());
  for (size_t i = 0; i < actuators.size(); ++i) {
    const int a = actuators[i];
    HGRASP_DEMAND(speed_limit[i] > 0);
    // The controller servos its motor to a whole encoder count: at rest the encoder reads the
    // goal, and the link stands where its zero and the backlash put it.
    const double res = joint_error_[a].resolution_rad;
    const double count_goal = res > 0 ? res * std::round(goal[i] / res) : goal[i];
    // The gear's backlash is taken up in the direction the motor now turns.
    const double delta = count_goal - EncoderSetpoint(a);
    if (std::abs(delta) > 1e-12) dir_[a] = delta > 0 ? 1 : -1;
    link_goal[i] = LinkAngle(a, count_goal);
    latency = std::max(latency, joint_error_[a].latency_s);
    const double distance = std::abs(link_goal[i] - data_->ctrl[a]);
    // The cubic profile peaks at 1.5 times the mean speed.
    duration = std::max(duration, (constant_speed ? 1.0 : 1.5) * distance / speed_limit[i]);
  }
  if (constant_speed && duration > 0) duration += kRampS;  // cruise at speed_limit
  for (size_t i = 0; i < actuators.size(); ++i) {
    Motion& m = motion_[actuators[i]];
    m.start = data_->ctrl[actuators[i]];
    m.goal = link_goal[i];
    m.t0 = data_->time + latency;
    m.duration = duration;
    m.active = true;
    m.constant_speed = constant_speed;
  }
}

bool World::Moving(const std::vector<int>& actuators) const {
  return std::any_of(actuators.begin(), actuators.end(), [&](int a) { return motion_[a].active; });
}

void World::StopMotion(const std::vector<int>& actuators) {
  for (int a : actuators) motion_[a].active = false;
}

void World::ApplyControllers() {
  const double t = data_->time;
  for (int a = 0; a < model_->nu; ++a) {
    Motion& m = motion_[a];
    if (!m.active) continue;
    const double s = m.duration > 0 ? std::clamp((t - m.t0) / m.duration, 0.0, 1.0) : 1.0;
    const double profile = m.constant_speed ? Trapezoid(t - m.t0, m.duration) : Smoothstep(s);
    data_->ctrl[a] = m.start + (m.goal - m.start) * profile;
    if (s >= 1.0) m.active = false;
  }
  // Gravity and Coriolis feed-forward, as the arm and head controllers provide.
  for (int dof : robot_dofs_) data_->qfrc_applied[dof] = data_->qfrc_bias[dof];
}

void World::Step(double duration_s) {
  const int steps = static_cast<int>(std::lround(duration_s / model_->opt.timestep));
  for (int i = 0; i < steps; ++i) {
    if ((data_->time >= hide_from_s_ && data_->time < hide_until_s_) != leds_hidden_) ApplyLeds();
    ApplyControllers();
    mj_step(model_, data_);
    // MuJoCo answers a diverging simulation by resetting it to the model's zero pose and
    // carrying on: never let that pass silently.
    for (const mjtWarning w : {mjWARN_BADQPOS, mjWARN_BADQVEL, mjWARN_BADQACC, mjWARN_BADCTRL}) {
      if (data_->warning[w].number > 0) {
        throw std::runtime_error(
            "the simulation became unstable at t = " + std::to_string(data_->time) +
            " s (MuJoCo warning " + std::to_string(static_cast<int>(w)) + ", index " +
            std::to_string(data_->warning[w].lastinfo) + ")");
      }
    }
  }
}

Pose3 PoseFromMujoco(const mjtNum* pos, const mjtNum* mat) {
  Pose3 X = Pose3::Identity();
  X.translation() = Eigen::Vector3d(pos[0], pos[1], pos[2]);
  X.linear() = Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>>(mat);
  return X;
}

Pose3 World::SitePose(int site) const {
  return PoseFromMujoco(data_->site_xpos + 3 * site, data_->site_xmat + 9 * site);
}

Pose3 World::BodyPose(int body) const {
  return PoseFromMujoco(data_->xpos + 3 * body, data_->xmat + 9 * body);
}

bool World::PathClear(const Eigen::Vector3d& from_W, const Eigen::Vector3d& to_W,
                      double ignore_near_to_m) const {
  const Eigen::Vector3d v = to_W - from_W;
  const double length = v.norm();
  const Eigen::Vector3d unit = v / length;
  const double kLift = 1e-3;  // leave the surface the path starts on
  const Eigen::Vector3d start = from_W + kLift * unit;
  int geom = -1;
  const double hit = mj_ray(model_, data_, start.data(), unit.data(), nullptr, 1, -1, &geom);
  return hit < 0 || hit >= length - kLift - ignore_near_to_m;
}

int World::LedCount(const std::string& side) const {
  int n = 0;
  while (mj_name2id(model_, mjOBJ_GEOM, (side + "_led" + std::to_string(n)).c_str()) >= 0) ++n;
  return n;
}

void World::SetLed(const std::string& side, int index, bool on) {
  led_switched_on_[Id(mjOBJ_GEOM, side + "_led" + std::to_string(index))] = on;
  ApplyLeds();
}

void World::HideLeds(double from_s, double until_s) {
  hide_from_s_ = from_s;
  hide_until_s_ = until_s;
  ApplyLeds();
}

void World::ApplyLeds() {
  leds_hidden_ = data_->time >= hide_from_s_ && data_->time < hide_until_s_;
  for (const auto& [geom, on] : led_switched_on_) {
    const int material = on && !leds_hidden_ ? led_on_material_ : led_off_material_;
    if (model_->geom_matid[geom] != material) {
      model_->geom_matid[geom] = material;
      ++appearance_version_;
    }
  }
}

}  // namespace hgrasp::sim
