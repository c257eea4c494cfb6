#pragma once
/// @file The twin behind the real wires (`hgrasp twin`): the MuJoCo world run in wall-clock time
/// (or slower, `rate`), every serial device of the robot served on its real protocol by the
/// byte-exact emulators of drivers/emulators/ with the world behind their device models, and
/// the two cameras exposed every 40 ms of twin time and handed to a FrameSink (the app streams
/// them through GStreamer). One thread runs the physics steps, the serial lines between them and
/// the exposures at their times; a second one renders: at an exposure the world's state is
/// copied and rendered from the copy (in a world of its own, with its own EGL context) while the
/// loop goes on serving the lines, so that a slow render never delays a device's reply.
///
/// At each exposure the laser board latches the encoder (its frame counter counts exposures:
/// exposure k is board frame k, the number the frame carries), then both images are rendered.
/// An exposure that comes while the last one is still being rendered, or that the loop reaches
/// more than one frame period late, is latched but not rendered: an overrun, counted and
/// reported.
///
/// In lockstep (TwinOptions::lockstep, a SimClock) the same twin runs in simulated time in the
/// caller's process and thread: each physics step is an event of that clock (one every
/// timestep, the lines polled after it as Turn does), the lines have no pty (SerialLine::HostLink
/// gives the drivers their ends), and each exposure keeps its moment's state to be rendered when
/// a camera takes it (Develop). A driver waiting in a read runs the twin up to its answer; nothing
/// depends on the wall clock, so one scenario and seed give one run.

#include <array>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "common/clock.h"
#include "serial/faulty_link.h"
#include "sim/scenario.h"
#include "sim/stereo_rig.h"
#include "sim/twin/serial_line.h"
#include "sim/twin/twin_models.h"
#include "sim/world.h"

namespace hgrasp::sim {

/// Where an exposure goes: camera 0 left, 1 right; the board's frame number; its twin time.
using FrameSink =
    std::function<void(int camera, const cv::Mat& bgr, std::uint64_t frame, double exposure_s)>;

struct TwinOptions {
  std::string dir;    ///< the ports folder: DIR/arm_left, ..., DIR/laser_board (pty links)
  double rate = 1.0;  ///< twin seconds per wall second, (0, 1]
  /// Faults on every serial line (each line's seed varied from it); none when unset.
  std::optional<drivers::FaultPlan> faults;
  /// Seed of the Biclops' power-up state (its chips read 0 wherever the head stands).
  std::uint64_t seed = 1;
  WorldOptions world;
  /// Lockstep: the twin runs as events of this clock (which must outlive it), its lines in
  /// process; `dir` and `rate` are unused. The clock is set to the world's time when it is
  /// behind (a world starts after its settling), so drivers and twin share one time base.
  /// Null: wall-clock time (Run), lines on ptys.
  SimClock* lockstep = nullptr;
};

/// The serial devices the twin serves, with their default bauds (drivers/config kDrivers).
struct TwinLineSpec {
  const char* key;     ///< the link's name in the ports folder
  const char* driver;  ///< the real driver that speaks to it
  int baud;
};
inline constexpr std::array<TwinLineSpec, 6> kTwinLines = {{
    {"arm_left", "val2", 9600},
    {"arm_right", "val2", 9600},
    {"hand_left", "sensorhand", 19200},
    {"hand_right", "sensorhand", 19200},
    {"head", "biclops", 9600},
    {"laser_board", "laser_board", 115200},
}};

/// Counts of the camera clock.
struct TwinFrameCounts {
  std::uint64_t exposures = 0;  ///< VSYNC pulses (latched)
  std::uint64_t rendered = 0;   ///< exposures rendered and handed on
  std::uint64_t overruns = 0;   ///< exposures not rendered in time (skipped)
  double render_s = 0.0;        ///< wall time spent rendering
  double max_render_s = 0.0;
  double max_lag_s = 0.0;  ///< the furthest the world fell behind the twin clock (s, twin)
};

/// One exposure (for the latch test and the report).
struct TwinExposure {
  std::uint64_t frame = 0;
  double t_s = 0.0;
  std::int32_t encoder_count = 0;  ///< what the board latched
  bool laser_on = false;
  bool rendered = false;
};

/// The true gripper when a hand began to close (the end of the servo).
struct TwinGrip {
  std::string side;
  double t_s = 0.0;
  Pose3 X_WE;
};

/// A hand's motor changing speed (a start, a stop, a reversal): when, at what opening and grip
/// force, and where every object stood then. The truth's account of a grasp: a box knocked
/// over by the fingers shows between the close's start and its stop.
struct TwinHandEvent {
  std::string side;
  double t_s = 0.0;
  double velocity_m_s = 0.0;  ///< the new commanded pad speed (< 0 closing)
  double opening_m = 0.0;
  double force_n = 0.0;
  std::vector<std::pair<std::string, Pose3>> objects;
};

class Twin {
 public:
  /// Builds the world and the emulators, opens the ptys (links in options.dir). Throws
  /// InputError / std::runtime_error as World and Pty do.
  Twin(Scenario scenario, const TwinOptions& options, FrameSink sink);
  ~Twin();

  /// Runs until `keep_going` returns false (asked between loop turns, about every ms). Not in
  /// lockstep, where the clock's waits run the twin.
  void Run(const std::function<bool()>& keep_going);
  /// In lockstep: the host's end of line `key` (SerialLine::HostLink on the twin's clock).
  std::unique_ptr<drivers::ByteLink> HostLink(const std::string& key);
  /// In lockstep: renders the newest exposure not yet rendered into the sink (the state, LEDs
  /// and laser of its moment, kept at the exposure); false when there is none. An exposure is
  /// rendered only when a camera takes it: one that a newer exposure replaced first never is
  /// (frame_counts(): exposures, rendered).
  bool Develop();
  /// One loop turn at wall time `wall_s` since Run began (for tests that drive it themselves).
  void Turn(double wall_s);

  /// Twin time now (the world's).
  double time() const { return world_->time(); }
  /// Twin time when it began serving (Run's start, or the lockstep twin's construction): the
  /// origin of --at times and of twin.json's control times.
  double start_time() const { return t0_; }
  World& world() { return *world_; }
  SerialLine* line(const std::string& key);
  std::vector<SerialLine*> lines();

  /// Called after each exposure is rendered, with the rig that rendered it (its
  /// last_crossings() are that exposure's stripe), the encoder count the board latched at the
  /// exposure and whether the laser was on: the ground truth of what the cameras saw, for a
  /// report (`hgrasp run --lockstep` scores its scan with it). In lockstep on the thread that
  /// develops the frame (the clock's); otherwise on the render thread. Set it before the
  /// cameras run.
  using RenderObserver =
      std::function<void(StereoRig& rig, std::int32_t encoder_count, bool laser_on)>;
  void set_render_observer(RenderObserver observer) { render_observer_ = std::move(observer); }

  /// The cameras stop delivering frames (exposures still latch) / start again.
  void StopCameras(bool stop) { cameras_stopped_ = stop; }

  /// Runs one control command: "cut KEY", "cut_tx KEY", "mend KEY", "vanish KEY",
  /// "reappear KEY", "stop cameras", "resume cameras". Returns an error message, "" if done.
  std::string Control(const std::string& command);

  TwinFrameCounts frame_counts() const;
  const std::vector<TwinExposure>& exposures() const { return exposures_; }
  const std::vector<TwinGrip>& grips() const { return grips_; }

  /// The `devices` block that names every real driver on the twin's ports; the cameras'
  /// pipelines given by the caller.
  std::string DevicesYaml(const std::string& left_pipeline, const std::string& right_pipeline,
                          const std::string& head_options) const;
  /// Counts, truth (boxes now and at start, grips) and each emulator's command log.
  nlohmann::json Report() const;

 private:
  /// Report's "lines" (each line's counts and faults); each emulator's log into commands, its
  /// twin times into times, keyed by line.
  nlohmann::json LinesReport(nlohmann::json* commands, nlohmann::json* times) const;
  /// Report's "truth": grips, hand events, boxes, head, laser, arms, LEDs and hands now.
  nlohmann::json Truth() const;
  nlohmann::json HandTruth() const;  ///< the grips and hand events of Truth
  void StepPhysics(double dt);
  void Expose(double late_s);
  void WatchHands();
  // Lockstep: one physics step and the lines after it (Turn's loop body), then the next tick.
  void Tick();
  // Renders the state `state` with the LEDs and the laser given into the sink, in `world` (the
  // renderer's own) through `rig`; adds to frames_ (under render_mu_).
  void Render(World& world, StereoRig& rig, const mjData* state,
              const std::array<std::uint32_t, 2>& leds, bool laser, std::uint64_t frame,
              std::int32_t encoder_count, double t);

  Scenario scenario_;
  TwinOptions options_;
  FrameSink sink_;
  RenderObserver render_observer_;
  std::unique_ptr<World> world_;
  // The render thread and its job: the world's state at the exposure (a copy), the LEDs and
  // the laser switch, the frame. Guarded by render_mu_.
  void RenderLoop();
  std::thread render_thread_;
  mutable std::mutex render_mu_;
  std::condition_variable render_cv_;
  mjData* job_data_ = nullptr;
  std::array<std::uint32_t, 2> job_leds_{};
  bool job_laser_ = false;
  std::uint64_t job_frame_ = 0;
  std::int32_t job_count_ = 0;
  double job_t_ = 0.0;
  bool job_pending_ = false, rendering_ = false, render_ready_ = false, render_stop_ = false;
  std::string render_error_;
  // Lockstep: the renderer's world and rig (in this thread), and the next tick.
  std::unique_ptr<World> render_world_;
  std::unique_ptr<StereoRig> render_rig_;
  SimClock::EventId tick_ = 0;
  std::vector<std::unique_ptr<SerialLine>> lines_;
  // The models behind the emulators (owned by them).
  std::array<TwinHandModel*, 2> hands_{};
  TwinBoardHardware* board_ = nullptr;
  std::unique_ptr<TwinHeadMirror> head_;
  double t0_ = 0.0;  ///< twin time when Run began
  double next_frame_s_ = 0.0;
  std::uint64_t frame_ = 0;
  bool cameras_stopped_ = false;
  TwinFrameCounts frames_;
  std::vector<TwinExposure> exposures_;
  std::vector<TwinGrip> grips_;
  std::vector<TwinHandEvent> hand_events_;
  std::array<double, 2> hand_velocity_{};
  std::vector<std::pair<double, std::string>> controls_;  ///< (twin time, command) run
  /// Per arm: its joints' dofs, and the last twin time any of them turned faster than
  /// kArmMovingRad_s (the arm truly moving).
  std::array<std::array<int, 6>, 2> arm_dofs_{};
  std::array<double, 2> arm_last_moving_s_{};
  static constexpr double kArmMovingRad_s = 0.01;
  std::map<std::string, Pose3> boxes_at_start_;
};

}  // namespace hgrasp::sim
