#include "sim/twin/twin.h"

#include <poll.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/error.h"
#include "common/paths.h"
#include "robot/arm_kinematics.h"
#include "robot/kinematic_tree.h"
#include "serial/command_log.h"

namespace hgrasp::sim {

namespace {

using json = nlohmann::json;

/// Biclops: 12000 counts per joint turn (BiclopsDefault.cfg; drivers/emulators/biclops_emulator.h).
constexpr double kHeadRadPerCount = 2.0 * kPi / 12000.0;

json PoseJson(const Pose3& X) {
  json R = json::array();
  for (int r = 0; r < 3; ++r) R.push_back({X.linear()(r, 0), X.linear()(r, 1), X.linear()(r, 2)});
  return {{"p", {X.translation().x(), X.translation().y(), X.translation().z()}}, {"R", R}};
}

// What an emulator ran, in its own terms (and the lines VAL refused, with their messages: a
// driver that lost a message would have taken the line as run), with the twin times.
void EmulatorLog(const drivers::DeviceEmulator& d, json* log, json* log_t, json* refused) {
  if (const auto* v = dynamic_cast<const drivers::Val2Emulator*>(&d)) {
    for (const auto& e : v->executed()) {
      log->push_back(e.line);
      log_t->push_back(e.t_s);
    }
    for (const auto& [line, error] : v->refused()) {
      refused->push_back({{"line", line}, {"error", error}});
    }
  } else if (const auto* h = dynamic_cast<const drivers::SensorHandEmulator*>(&d)) {
    for (const auto& e : h->log()) {
      log->push_back(drivers::HexBytes(drivers::sensorhand::Encode(e.command)));
      log_t->push_back(e.t_s);
    }
  } else if (const auto* b = dynamic_cast<const drivers::BiclopsEmulator*>(&d)) {
    for (const auto& e : b->executed()) {
      log->push_back({{"axis", e.axis}, {"opcode", e.opcode}, {"value", e.value}});
      log_t->push_back(e.t_s);
    }
  } else if (const auto* lb = dynamic_cast<const drivers::LaserBoardEmulator*>(&d)) {
    for (const auto& e : lb->log()) {
      log->push_back(drivers::HexBytes(drivers::laser_board::CommandPayload(e.command)) + "/" +
                     std::to_string(static_cast<int>(drivers::laser_board::CodeOf(e.command))));
      log_t->push_back(e.t_s);
    }
  }
}

}  // namespace

Twin::Twin(Scenario scenario, const TwinOptions& options, FrameSink sink)
    : scenario_(scenario), options_(options), sink_(std::move(sink)) {
  world_ = std::make_unique<World>(std::move(scenario), options.world);
  job_data_ = mj_makeData(world_->model());
  if (options.lockstep != nullptr) {
    // Rendered at once, in this thread, from a world of its own (the LEDs and the laser are
    // set on it per frame, as the render thread does).
    try {
      render_world_ = std::make_unique<World>(scenario_, options_.world);
      render_rig_ = std::make_unique<StereoRig>(render_world_.get());
    } catch (...) {
      mj_deleteData(job_data_);
      throw;
    }
  } else {
    render_thread_ = std::thread([this] { RenderLoop(); });
  }
  if (options.lockstep == nullptr) {
    std::unique_lock<std::mutex> lock(render_mu_);
    render_cv_.wait(lock, [this] { return render_ready_; });
    if (!render_error_.empty()) {
      lock.unlock();
      render_thread_.join();
      mj_deleteData(job_data_);
      throw std::runtime_error("the twin's renderer: " + render_error_);
    }
  }
  for (const SimObject& o : world_->objects()) {
    boxes_at_start_[o.spec.name] = world_->BodyPose(o.body);
  }
  const robot::KinematicTree tree =
      robot::KinematicTree::FromUrdfFile(ResolveDataPath("models/humanoid.urdf"));
  int index = 0;
  for (const TwinLineSpec& spec : kTwinLines) {
    const std::string key = spec.key;
    std::unique_ptr<drivers::DeviceEmulator> device;
    if (key == "arm_left" || key == "arm_right") {
      const device::Side side = key == "arm_left" ? device::Side::kLeft : device::Side::kRight;
      const std::string name(device::ToString(side));
      device = std::make_unique<drivers::Val2Emulator>(
          std::make_unique<TwinArmModel>(world_.get(), side),
          robot::ArmKinematics::FromTree(tree, name), tree.LinkPose(name + "_base", {}));
    } else if (key == "hand_left" || key == "hand_right") {
      const device::Side side = key == "hand_left" ? device::Side::kLeft : device::Side::kRight;
      auto model = std::make_unique<TwinHandModel>(world_.get(), side);
      hands_[static_cast<int>(side)] = model.get();
      device = std::make_unique<drivers::SensorHandEmulator>(std::move(model));
    } else if (key == "head") {
      drivers::BiclopsEmulatorConfig config = drivers::PoweredUpBiclopsEmulatorConfig(options.seed);
      // The head powers up where the world has it; its relative encoders read 0 there.
      config.start_counts = TwinHeadMirror::Counts(*world_, kHeadRadPerCount);
      auto chip = std::make_unique<drivers::BiclopsEmulator>(config);
      head_ = std::make_unique<TwinHeadMirror>(world_.get(), chip.get(), kHeadRadPerCount);
      device = std::move(chip);
    } else {
      drivers::LaserBoardEmulatorConfig config;
      config.leds_per_gripper = world_->LedCount("left");
      auto hardware = std::make_unique<TwinBoardHardware>(world_.get(), config.motor);
      board_ = hardware.get();
      device = std::make_unique<drivers::LaserBoardEmulator>(config, std::move(hardware));
    }
    std::optional<drivers::FaultPlan> faults = options.faults;
    if (faults) faults->seed += 7919u * static_cast<unsigned>(index);
    if (options.lockstep != nullptr) {
      lines_.push_back(std::make_unique<SerialLine>(key, std::move(device), spec.baud, faults,
                                                    *options.lockstep));
    } else {
      const std::string link = options.dir.empty() ? "" : options.dir + "/" + key;
      lines_.push_back(
          std::make_unique<SerialLine>(key, std::move(device), link, spec.baud, faults));
    }
    ++index;
  }
  next_frame_s_ = world_->time() + kFramePeriodS;
  for (int s = 0; s < 2; ++s) {
    for (int j = 0; j < 6; ++j) {
      const int joint = world_->Id(
          mjOBJ_JOINT, std::string(s == 0 ? "left" : "right") + "_j" + std::to_string(j + 1));
      arm_dofs_[s][j] = world_->model()->jnt_dofadr[joint];
    }
  }
  if (options.lockstep != nullptr) {
    // One time base: the clock reads the world's time (a world starts after its settling).
    t0_ = world_->time();
    SimClock& clock = *options.lockstep;
    const Clock::TimePoint world_now(Clock::FromSeconds(t0_));
    if (clock.Now() < world_now) clock.SleepUntil(world_now);
    tick_ = clock.At(clock.Now() + Clock::FromSeconds(world_->model()->opt.timestep),
                     [this] { Tick(); });
  }
}

Twin::~Twin() {
  if (options_.lockstep != nullptr) options_.lockstep->Cancel(tick_);
  {
    std::lock_guard<std::mutex> lock(render_mu_);
    render_stop_ = true;
  }
  render_cv_.notify_all();
  if (render_thread_.joinable()) render_thread_.join();
  mj_deleteData(job_data_);
}

void Twin::RenderLoop() {
  // The renderer's world: the same scenario, its state overwritten by each job's copy. Built in
  // this thread, which owns its EGL context.
  std::unique_ptr<World> world;
  std::unique_ptr<StereoRig> rig;
  try {
    world = std::make_unique<World>(scenario_, options_.world);
    rig = std::make_unique<StereoRig>(world.get());
  } catch (const std::exception& e) {
    std::lock_guard<std::mutex> lock(render_mu_);
    render_error_ = e.what();
    render_ready_ = true;
    render_cv_.notify_all();
    return;
  }
  {
    std::lock_guard<std::mutex> lock(render_mu_);
    render_ready_ = true;
  }
  render_cv_.notify_all();
  for (;;) {
    std::array<std::uint32_t, 2> leds{};
    bool laser = false;
    std::uint64_t frame = 0;
    std::int32_t count = 0;
    double t = 0.0;
    {
      std::unique_lock<std::mutex> lock(render_mu_);
      render_cv_.wait(lock, [this] { return job_pending_ || render_stop_; });
      if (render_stop_) return;
      leds = job_leds_;
      laser = job_laser_;
      frame = job_frame_;
      count = job_count_;
      t = job_t_;
      job_pending_ = false;
    }
    // job_data_ stays as it is until rendering_ is cleared (Expose writes it only then).
    Render(*world, *rig, job_data_, leds, laser, frame, count, t);
    std::lock_guard<std::mutex> lock(render_mu_);
    rendering_ = false;
  }
}

void Twin::Render(World& world, StereoRig& rig, const mjData* state,
                  const std::array<std::uint32_t, 2>& leds, bool laser, std::uint64_t frame,
                  std::int32_t encoder_count, double t) {
  mj_copyData(world.data(), world.model(), state);
  const int count = world.LedCount("left");
  for (int s = 0; s < 2; ++s) {
    for (int i = 0; i < count; ++i) {
      world.SetLed(s == 0 ? "left" : "right", i, (leds[s] >> i) & 1u);
    }
  }
  world.set_laser_on(laser);
  const auto t0 = std::chrono::steady_clock::now();
  StereoImages images = rig.Expose(frame);
  if (render_observer_) render_observer_(rig, encoder_count, laser);
  if (sink_) {
    for (int c = 0; c < 2; ++c) sink_(c, images.image[c], frame, t);
  }
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::lock_guard<std::mutex> lock(render_mu_);
  frames_.render_s += took;
  frames_.max_render_s = std::max(frames_.max_render_s, took);
  ++frames_.rendered;
}

bool Twin::Develop() {
  if (options_.lockstep == nullptr || !job_pending_) return false;
  job_pending_ = false;
  Render(*render_world_, *render_rig_, job_data_, job_leds_, job_laser_, job_frame_, job_count_,
         job_t_);
  for (auto it = exposures_.rbegin(); it != exposures_.rend(); ++it) {
    if (it->frame == job_frame_) {
      it->rendered = true;
      break;
    }
  }
  return true;
}

std::unique_ptr<drivers::ByteLink> Twin::HostLink(const std::string& key) {
  HGRASP_DEMAND_MSG(options_.lockstep != nullptr, "Twin::HostLink: the twin is not in lockstep");
  SerialLine* l = line(key);
  HGRASP_DEMAND_MSG(l != nullptr, "Twin::HostLink: no such line");
  return l->HostLink(*options_.lockstep);
}

void Twin::Tick() {
  // At clock time T: the world steps from T - dt to T, the lines are polled at T, and an
  // exposure due at T is taken (Turn's order: poll, expose, step), so the world's time is the
  // clock's after every tick.
  const double dt = world_->model()->opt.timestep;
  StepPhysics(dt);
  for (auto& l : lines_) l->Poll(world_->time());
  WatchHands();
  if (world_->time() + 0.5 * dt >= next_frame_s_) Expose(0.0);
  SimClock& clock = *options_.lockstep;
  tick_ = clock.At(clock.Now() + Clock::FromSeconds(dt), [this] { Tick(); });
}

SerialLine* Twin::line(const std::string& key) {
  for (auto& l : lines_) {
    if (l->key() == key) return l.get();
  }
  return nullptr;
}

std::vector<SerialLine*> Twin::lines() {
  std::vector<SerialLine*> v;
  for (auto& l : lines_) v.push_back(l.get());
  return v;
}

void Twin::StepPhysics(double dt) {
  head_->Apply();
  board_->Apply(dt);
  for (TwinHandModel* h : hands_) h->Apply(dt);
  world_->Step(dt);
  for (int s = 0; s < 2; ++s) {
    for (int dof : arm_dofs_[s]) {
      if (std::abs(world_->data()->qvel[dof]) > kArmMovingRad_s) {
        arm_last_moving_s_[s] = world_->time();
        break;
      }
    }
  }
}

void Twin::Expose(double late_s) {
  ++frame_;
  ++frames_.exposures;
  next_frame_s_ += kFramePeriodS;
  TwinExposure e;
  e.frame = frame_;
  e.t_s = world_->time();
  e.encoder_count = board_->Latch();
  e.laser_on = world_->laser_on();
  // The board takes the latch at once (VSYNC is a wire to it), before the image is out.
  line("laser_board")->Poll(world_->time());
  if (!cameras_stopped_ && options_.lockstep != nullptr) {
    // The state at the exposure, developed (rendered) when a camera takes it (Develop); a newer
    // exposure replaces one nobody took, which is then never rendered.
    mj_copyData(job_data_, world_->model(), world_->data());
    job_leds_ = {board_->LedMask(0), board_->LedMask(1)};
    job_laser_ = world_->laser_on();
    job_frame_ = frame_;
    job_count_ = e.encoder_count;
    job_t_ = e.t_s;
    job_pending_ = true;
    exposures_.push_back(e);
    return;
  }
  if (!cameras_stopped_) {
    std::lock_guard<std::mutex> lock(render_mu_);
    if (late_s > kFramePeriodS || rendering_) {
      ++frames_.overruns;  // the loop fell behind, or the last exposure is still rendering
    } else {
      mj_copyData(job_data_, world_->model(), world_->data());
      job_leds_ = {board_->LedMask(0), board_->LedMask(1)};
      job_laser_ = world_->laser_on();
      job_frame_ = frame_;
      job_count_ = e.encoder_count;
      job_t_ = e.t_s;
      job_pending_ = rendering_ = true;
      e.rendered = true;
      render_cv_.notify_all();
    }
  }
  exposures_.push_back(e);
}

void Twin::WatchHands() {
  for (int s = 0; s < 2; ++s) {
    const double v = hands_[s]->commanded_velocity();
    if (v < 0.0 && !(hand_velocity_[s] < 0.0)) {
      const std::string side = s == 0 ? "left" : "right";
      grips_.push_back(
          {side, world_->time(), world_->BodyPose(world_->Id(mjOBJ_BODY, side + "_gripper"))});
    }
    if (v != hand_velocity_[s]) {
      TwinHandEvent e;
      e.side = s == 0 ? "left" : "right";
      e.t_s = world_->time();
      e.velocity_m_s = v;
      e.opening_m = hands_[s]->opening_m();
      e.force_n = hands_[s]->grip_force_n();
      for (const SimObject& o : world_->objects()) {
        e.objects.emplace_back(o.spec.name, world_->BodyPose(o.body));
      }
      hand_events_.push_back(std::move(e));
      hand_velocity_[s] = v;
    }
  }
}

void Twin::Turn(double wall_s) {
  const double dt = world_->model()->opt.timestep;
  const double target = t0_ + options_.rate * wall_s;
  frames_.max_lag_s = std::max(frames_.max_lag_s, target - world_->time());
  while (world_->time() + 0.5 * dt <= target) {
    if (world_->time() + 0.5 * dt >= next_frame_s_) Expose(target - world_->time());
    StepPhysics(dt);
    for (auto& l : lines_) l->Poll(world_->time());
    WatchHands();
  }
  if (world_->time() + 0.5 * dt >= next_frame_s_) Expose(target - world_->time());
  for (auto& l : lines_) l->Poll(world_->time());
  WatchHands();
}

void Twin::Run(const std::function<bool()>& keep_going) {
  using Clock = std::chrono::steady_clock;
  const Clock::time_point wall0 = Clock::now();
  t0_ = world_->time();
  const double dt = world_->model()->opt.timestep;
  std::vector<pollfd> fds;
  while (keep_going()) {
    const double wall = std::chrono::duration<double>(Clock::now() - wall0).count();
    Turn(wall);
    // Sleep until the next physics step is due or a driver writes.
    const double next_wall = (world_->time() + dt - t0_) / options_.rate;
    const double now = std::chrono::duration<double>(Clock::now() - wall0).count();
    const int wait_ms = std::clamp(static_cast<int>((next_wall - now) * 1000.0), 0, 1);
    if (wait_ms == 0) continue;
    fds.clear();
    for (auto& l : lines_) {
      if (l->fd() >= 0) fds.push_back({l->fd(), POLLIN, 0});
    }
    ::poll(fds.data(), fds.size(), wait_ms);
  }
}

std::string Twin::Control(const std::string& command) {
  controls_.emplace_back(world_->time() - t0_, command);
  std::istringstream in(command);
  std::string verb, arg;
  in >> verb >> arg;
  if (verb == "stop" && arg == "cameras") {
    StopCameras(true);
    return "";
  }
  if (verb == "resume" && arg == "cameras") {
    StopCameras(false);
    return "";
  }
  std::string key = arg;
  if (key == "laser" || key == "leds") key = "laser_board";
  SerialLine* l = line(key);
  if (l == nullptr) {
    return "no such line '" + arg +
           "' (arm_left, arm_right, hand_left, hand_right, head, "
           "laser_board; or 'cameras')";
  }
  if (verb == "cut") {
    l->Cut(true);
  } else if (verb == "cut_tx") {
    l->CutFromDevice(true);
  } else if (verb == "mend") {
    l->Cut(false);
    l->CutFromDevice(false);
  } else if (verb == "vanish") {
    l->Vanish();
  } else if (verb == "reappear") {
    l->Reappear();
  } else {
    return "unknown command '" + verb + "' (cut, cut_tx, mend, vanish, reappear, stop, resume)";
  }
  return "";
}

std::string Twin::DevicesYaml(const std::string& left_pipeline, const std::string& right_pipeline,
                              const std::string& head_options) const {
  std::ostringstream y;
  y << "devices:\n";
  for (const auto& l : lines_) {
    if (l->key() == "laser_board") {
      for (const char* k : {"laser", "leds"}) {
        y << "  " << k << ": {driver: laser_board, port: " << l->port() << "}\n";
      }
      continue;
    }
    const char* driver = "";
    for (const TwinLineSpec& s : kTwinLines) {
      if (l->key() == s.key) driver = s.driver;
    }
    y << "  " << l->key() << ": {driver: " << driver << ", port: " << l->port();
    if (l->key() == "head" && !head_options.empty()) y << ", options: " << head_options;
    y << "}\n";
  }
  y << "  cameras:\n    driver: gstreamer\n    left: \"" << left_pipeline << "\"\n    right: \""
    << right_pipeline << "\"\n    options: {latch_pairing: offset}\n";
  return y.str();
}

TwinFrameCounts Twin::frame_counts() const {
  std::lock_guard<std::mutex> lock(render_mu_);
  return frames_;
}

json Twin::LinesReport(json* commands, json* times) const {
  json lines = json::object();
  for (const auto& l : lines_) {
    const drivers::FaultCounts f = l->fault_counts();
    json log = json::array(), log_t = json::array(), refused = json::array();
    EmulatorLog(l->device(), &log, &log_t, &refused);
    lines[l->key()] = {{"port", l->port()},
                       {"baud", l->baud()},
                       {"bytes_from_host", l->bytes_from_host()},
                       {"bytes_to_host", l->bytes_to_host()},
                       {"bytes_unsent", l->bytes_unsent()},
                       {"commands", log.size()},
                       {"faults",
                        {{"bytes", f.bytes},
                         {"corrupted", f.corrupted},
                         {"inserted", f.inserted},
                         {"dropped", f.dropped},
                         {"dropouts", f.dropouts}}}};
    if (!refused.empty()) lines[l->key()]["refused"] = std::move(refused);
    (*commands)[l->key()] = std::move(log);
    (*times)[l->key()] = std::move(log_t);
  }
  return lines;
}

json Twin::HandTruth() const {
  json grips = json::array();
  for (const TwinGrip& g : grips_) {
    json j = PoseJson(g.X_WE);
    j["side"] = g.side;
    j["t_s"] = g.t_s;
    grips.push_back(j);
  }
  json hand_events = json::array();
  for (const TwinHandEvent& e : hand_events_) {
    json objects = json::object();
    for (const auto& [name, X] : e.objects) objects[name] = PoseJson(X);
    hand_events.push_back({{"side", e.side},
                           {"t_s", e.t_s},
                           {"velocity_m_s", e.velocity_m_s},
                           {"opening_m", e.opening_m},
                           {"force_n", e.force_n},
                           {"objects", objects}});
  }
  return {{"grips", grips}, {"hand_events", hand_events}};
}

json Twin::Truth() const {
  json truth = HandTruth();
  json boxes = json::array();
  for (const SimObject& o : world_->objects()) {
    const Pose3 now = world_->BodyPose(o.body);
    const Pose3& start = boxes_at_start_.at(o.spec.name);
    boxes.push_back({{"name", o.spec.name},
                     {"start", PoseJson(start)},
                     {"now", PoseJson(now)},
                     {"rise_m", now.translation().z() - start.translation().z()}});
  }
  truth["boxes"] = boxes;
  truth["head_rad"] = {world_->JointPosition("head_pan"), world_->JointPosition("head_tilt"),
                       world_->JointPosition("head_verge_left")};
  truth["laser_count"] = board_->EncoderCount();
  truth["laser_on"] = world_->laser_on();
  auto arm = [&](int i, const char* gripper) -> json {
    return {{"last_moving_t_s", arm_last_moving_s_[i]},
            {"X_WE", PoseJson(world_->BodyPose(world_->Id(mjOBJ_BODY, gripper)))}};
  };
  truth["arms"] = {{"left", arm(0, "left_gripper")}, {"right", arm(1, "right_gripper")}};
  truth["leds"] = {{"left", board_->LedMask(0)}, {"right", board_->LedMask(1)}};
  auto hand = [&](int i) -> json {
    return {{"opening_m", hands_[i]->opening_m()}, {"force_n", hands_[i]->grip_force_n()}};
  };
  truth["hands"] = {{"left", hand(0)}, {"right", hand(1)}};
  return truth;
}

json Twin::Report() const {
  const TwinFrameCounts frames = frame_counts();
  json commands = json::object(), times = json::object();
  const json lines = LinesReport(&commands, &times);
  // Every exposure: [frame, twin time (s), encoder count latched, laser on, rendered].
  json exposures = json::array();
  for (const TwinExposure& e : exposures_) {
    exposures.push_back({e.frame, e.t_s, e.encoder_count, e.laser_on, e.rendered});
  }
  json controls = json::array();
  for (const auto& [t, c] : controls_) controls.push_back({{"t_s", t}, {"command", c}});
  return {{"scenario", scenario_.name},
          {"t0_s", t0_},
          {"controls", controls},
          {"exposures", exposures},
          {"rate", options_.rate},
          {"lockstep", options_.lockstep != nullptr},
          {"twin_s", world_->time() - t0_},
          {"frames",
           {{"exposures", frames.exposures},
            {"rendered", frames.rendered},
            {"overruns", frames.overruns},
            {"mean_render_ms", frames.rendered ? 1e3 * frames.render_s / frames.rendered : 0.0},
            {"max_render_ms", 1e3 * frames.max_render_s},
            {"max_lag_ms", 1e3 * frames.max_lag_s}}},
          {"lines", lines},
          {"truth", Truth()},
          {"commands", commands},
          {"command_times_s", times}};
}

}  // namespace hgrasp::sim
