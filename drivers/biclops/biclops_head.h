#pragma once
/// @file The Biclops pan/tilt/verge head behind device::Head, over the PMD motion chip's serial
/// protocol (drivers/biclops/PROTOCOL.md). One chip drives the three axes: pan (chip axis 0),
/// tilt (1) and verge (2), each a trapezoidal profile to a target at the axis speed limit.
///
/// No command is executed twice or altered: a Set* is sent only when the register differs from
/// the value sent, so after a lost or garbled reply the driver resynchronises and reads the
/// register back (GetPosition, GetVelocity, GetAcceleration, GetProfileMode) to learn whether it
/// took effect; an Update is sent only when the axis' active target changes, and after an
/// unclear reply the driver waits for the profile to end and reads where it ended
/// (GetCommandedPosition): at the new target the Update happened, at the old one it did not.
///
/// A freshly powered head must be homed (its encoders are relative): ConfigureAndHome configures
/// the chip as TRACLabs' libPMD does (PMDAxisControl::ConfigureHardware, SetFilter) and finds
/// each axis' home as its FindHome does with a home sensor and an index pulse per encoder cycle
/// (PROTOCOL.md, "Homing").

#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "biclops/pmd_codec.h"
#include "common/clock.h"
#include "common/stop_request.h"
#include "device/head.h"
#include "serial/byte_link.h"
#include "serial/command_log.h"

namespace hgrasp::drivers {

/// One Biclops axis (SI units).
struct BiclopsAxisOptions {
  /// Encoder counts per radian of joint motion; negative when the joint's positive sense
  /// (device/head.h) runs against the encoder's.
  double counts_per_rad = 12000.0 / (2.0 * 3.14159265358979323846);
  double min_rad = -1.0;  ///< joint range: targets outside it are rejected (kRejected)
  double max_rad = 1.0;
  double max_speed_rad_s = 1.0;   ///< > 0: the profile velocity of every move
  double max_accel_rad_s2 = 1.0;  ///< > 0: the profile acceleration

  // Homing (ConfigureAndHome). Defaults per axis: DefaultBiclopsOptions.
  /// > 0: speed of the homing sweeps (BiclopsDefault.cfg [homing profile] vel).
  double homing_speed_rad_s = 0.5;
  /// > 0: acceleration of the homing sweeps (BiclopsDefault.cfg [homing profile] acc).
  double homing_accel_rad_s2 = 0.5;
  /// > 0: joint angle between two encoder index pulses, one encoder cycle (BiclopsDefault.cfg:
  /// 2000 counts per encoder cycle).
  double index_spacing_rad = 2.0 * 3.14159265358979323846 / 6.0;
  /// > 0: the home sensor's expected width (BiclopsDefault.cfg homeSensorWidth); two edges
  /// closer than half of it are not taken for the sensor.
  double home_sensor_width_rad = 0.026;
  /// The home sensor's output is low on the sensor (BiclopsDefault.cfg homeSignalPolarity
  /// ActiveLow): the driver inverts the home input's signal sense so that it reads 1 there.
  bool home_active_low = true;
  /// Joint angle of the index pulse nearest the home sensor's centre, i.e. where the joint's 0
  /// lies relative to it with the opposite sign (BiclopsDefault.cfg homeOffset, 0 counts).
  double home_offset_rad = 0.0;

  // Servo filter and motor output, sent at configuration (PMD chip units, not SI: the chip
  // defines them; BiclopsDefault.cfg [run servo filter]).
  int filter_kp = 100;                  ///< proportional gain, 0..32767
  int filter_kd = 60;                   ///< derivative gain, 0..32767
  int filter_ki = 150;                  ///< integral gain, 0..32767
  int filter_kvff = 0;                  ///< velocity feed-forward, 0..32767
  int filter_kaff = 0;                  ///< acceleration feed-forward, 0..32767
  int filter_kout = 65535;              ///< output scale, 0..65535
  int filter_integration_limit = 2000;  ///< integrator limit, 0..2^31-1
  int filter_motor_limit = 32767;       ///< motor command limit, 0..32767
  int filter_motor_bias = 0;            ///< motor command bias, -32768..32767
  /// >= 0: the following error at which the chip flags a motion error (BiclopsDefault.cfg elim).
  double position_error_limit_rad = 10.0 * 3.14159265358979323846 / 180.0;
  /// Motor output mode (SetOutputMode): 1 PWM sign/magnitude (BiclopsDefault.cfg amptype
  /// PWMSignMag), 2 PWM 50/50, 0 DAC.
  int output_mode = 1;
  /// The amplifier's enable input is active low (BiclopsDefault.cfg ampPolarity ActiveLow): the
  /// driver drives it through the axis-out pin's signal sense, as libPMD's EnableAmp does.
  bool amp_active_low = true;
};

struct BiclopsOptions {
  /// Pan, tilt, verge (chip axes 0, 1, 2).
  std::array<BiclopsAxisOptions, 3> axes;
  /// Wait for a complete reply after sending a packet (9600 baud: 6 bytes take 6 ms).
  double reply_timeout_s = 0.1;
  /// During resynchronisation: the longest wait for an answer after each 0x00 byte (the
  /// driver waits four measured round trips, at least 3 ms, at most this).
  double resync_byte_timeout_s = 0.02;
  /// A call gives up with kTimeout once nothing at all has come from the chip for this long
  /// (a cut cable is reported within this time plus one wait). ConfigureAndHome gives up only
  /// once the chip has not answered one resynchronisation round after that either (the line
  /// probe: up to max_resends per homing), so a cut cable ends homing about 0.1 s later.
  double silence_timeout_s = 0.4;
  /// Re-sends of one command known not to have been executed (TRACLabs libPMD tries 4 times;
  /// the read-back lets us try more safely).
  int max_resends = 8;
  /// Margin on the longest move when waiting for a profile to end (after an unclear Update),
  /// and on each homing sweep's expected duration before it is called a timeout.
  double settle_margin_s = 1.0;
  /// Stop waits up to this for every axis to report itself at rest: an abrupt stop zeroes the
  /// profile, and the servo still brakes the axis from its speed. Still moving after it: kTimeout.
  double stop_settle_s = 0.5;
  /// Whether the composition root homes the head (ConfigureAndHome) when it opens the driver:
  /// a freshly powered head must be homed; one homed since its power came on need not be.
  bool home_at_start = true;
};

/// Biclops defaults: 12000 counts per joint turn (0.03 deg/count; TRACLabs BiclopsDefault.cfg:
/// 2000 counts per encoder cycle, 6 encoder cycles per axis turn), pan +-180 deg at 150 deg/s
/// (published) and 300 deg/s^2 (BiclopsDefault.cfg run profile), tilt +-60 deg (published) at
/// 150 deg/s (ours, as models/humanoid.xml) and 80 deg/s^2 (BiclopsDefault.cfg), verge -5..25 deg
/// at 100 deg/s (ours, as models/humanoid.xml) and 200 deg/s^2 (ours).
BiclopsOptions DefaultBiclopsOptions();

/// What the driver went through (for reports and tests).
struct BiclopsCounters {
  std::uint64_t exchanges = 0;      ///< packets sent expecting a reply
  std::uint64_t timeouts = 0;       ///< no complete reply in time
  std::uint64_t garbled = 0;        ///< replies with a bad sum or surplus bytes
  std::uint64_t error_replies = 0;  ///< replies with a non-zero chip status
  std::uint64_t resyncs = 0;        ///< NoOperation resynchronisations
  std::uint64_t readbacks = 0;      ///< registers read back after an unclear Set* reply
  std::uint64_t update_checks = 0;  ///< profile ends awaited after an unclear Update reply
  std::uint64_t resends = 0;        ///< commands re-sent, known not to have been executed
  std::uint64_t disconnects = 0;    ///< calls that met a vanished port
  /// Silences that reached silence_timeout_s during homing and were given a line probe.
  std::uint64_t line_probes = 0;
};

class BiclopsHead final : public device::Head {
 public:
  /// `link`: the serial line (9600 8N1), or a decorator over it. Throws InputError on bad
  /// options (field and value named).
  /// `clock`: every time the driver reads and every wait it times (a SimClock in simulated
  /// time; it must outlive the driver).
  explicit BiclopsHead(std::unique_ptr<ByteLink> link,
                       const BiclopsOptions& options = DefaultBiclopsOptions(),
                       Clock& clock = Clock::Wall());

  /// Whether any axis' profile is running (GetActivityStatus, in-motion bit) and the joint
  /// angles (GetActualPosition, read after the status: a head reported at rest is at the
  /// angles where it stopped). t_s: seconds since the driver was made (host clock).
  device::Status Read(device::HeadState* state) override;
  /// Starts every axis towards its target at the axis speed limit (returns once the chip has
  /// the moves; see Read for their progress). kRejected for a target outside the joint range.
  device::Status MoveTo(const device::HeadJoints& target) override;
  /// Stops every axis where it is: SetStopMode abrupt and an Update per axis (the PMD chip's
  /// stop; the Update is sent again only when GetStopMode shows the chip did not take it).
  device::Status Stop() override;

  /// Synchronises with the chip, checks its version (three axes at least), reads its cycle
  /// time and sets every axis' profile mode, velocity and acceleration where they differ.
  /// Called by MoveTo when needed.
  device::Status Initialize();
  /// Configures the chip and homes the three axes, as libBiclops' Initialize and HomeAxes do
  /// (PROTOCOL.md, "Homing"): per axis the motor output, signal sense, limit switch mode,
  /// servo filter and profile mode; then tilt, verge and pan in turn find the centre of their
  /// home sensor (both edges captured), the index pulse nearest it (captured in a sweep of one
  /// encoder cycle), zero their position there (plus home_offset_rad) and move to 0. Afterwards
  /// the joint angles read in the frame of device/head.h. Takes seconds (the sweeps run at the
  /// homing speeds). kRejected when the chip refuses a command or an axis finds no home sensor
  /// or index; kTimeout, kBadReply, kDisconnected as for every call; last_error() says which
  /// axis and step failed. Not called by the constructor; may be called again (re-homes).
  /// `stop` (may be null) is polled while the axes sweep: when requested, homing ends with
  /// kInterrupted (the axis is left moving; the caller stops the head).
  /// A silence of silence_timeout_s does not end homing by itself: the chip gets one
  /// resynchronisation round to answer (a line probe), and when it does (the silence was a
  /// dropout) the step goes on, its lost reply resolved as any other (nothing executed twice).
  device::Status ConfigureAndHome(const StopRequest* stop = nullptr);
  /// Whether ConfigureAndHome has completed since the driver was made (or the chip reset).
  bool homed() const;
  /// What the last failed ConfigureAndHome stopped at ("" after success).
  std::string last_error() const;
  /// Resets the chip (all registers and position counters to 0: the head loses its homing).
  /// Sent once: the driver confirms it by reading a velocity register back.
  device::Status ResetChip();

  /// GetVersion words (after Initialize).
  std::uint16_t version_chip() const { return version_chip_; }
  std::uint16_t version_software() const { return version_software_; }
  /// The chip's cycle time (after Initialize), s.
  double cycle_s() const { return cycle_s_; }
  /// The velocity and acceleration registers sent for `axis` (after Initialize).
  std::int32_t velocity_register(int axis) const { return velocity_reg_[Index(axis)]; }
  std::uint32_t acceleration_register(int axis) const { return accel_reg_[Index(axis)]; }
  /// `target` in encoder counts, as MoveTo sends it.
  std::array<std::int32_t, 3> ToCounts(const device::HeadJoints& target) const;
  BiclopsCounters counters() const;
  /// The state-changing commands (pmd::OpcodeInfo::changes_state: Set*, Update,
  /// AdjustActualPosition, Reset, GetCaptureValue) sent to the chip, in order, as sent; the
  /// chip's log (BiclopsEmulator::executed) gives each as {axis, opcode, pmd::CommandValue}.
  /// Confirmed when the driver knows a command took effect: a clean status-0 reply, or, after
  /// a lost or garbled reply, the register read back (WriteRegister, AdjustPosition, ResetChip)
  /// or the profile's end (the Updates); a command the chip refused, or that the read-back
  /// shows it never got, is not recorded. Unconfirmed: every send of a configuration Set*
  /// (Command) or of GetCaptureValue (Query) whose reply was lost or garbled, since those are
  /// sent again without asking whether the chip took them (they write the same value again:
  /// when only the reply was damaged, the chip executed the command twice in a row, which its
  /// log shows and this one shows as one unconfirmed entry and one confirmed); an Update to
  /// the target an axis already stands at whose reply was lost (the chip shows the same
  /// whether it ran or not); any command whose outcome a failure left unknown.
  const CommandLog<pmd::Command>& command_log() const { return command_log_; }

 private:
  /// What the driver knows of one chip register.
  struct Known {
    bool known = false;
    std::int64_t value = 0;
  };
  enum Register { kPosition = 0, kVelocity, kAcceleration, kProfileMode, kRegisters };

  static std::size_t Index(int axis) { return static_cast<std::size_t>(axis); }
  void BeginCall();
  double SilenceLeft() const;
  /// At the silence limit: a line probe when one is granted (homing), else silent_.
  void SilenceReached();
  /// One read from the link, keeping track of silence. kTimeout when nothing came.
  device::Status ReadLink(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n);
  /// Reads until the line is quiet for `quiet_s`, then drops everything received.
  device::Status Drain(double quiet_s);
  /// One packet out and its reply in: kOk with *reply (any chip status), kTimeout, kBadReply
  /// (garbled), kDisconnected.
  device::Status Exchange(const pmd::Command& command, int result_words, pmd::Reply* reply);
  /// 0x00 bytes until the chip answers, then a GetVersion that must come back clean.
  device::Status Resync();
  /// How long to wait for an answer to each 0x00 byte.
  double ZeroWait() const;
  device::Status SyncIfNeeded();
  /// A Get* (no side effects): retried until a clean status-0 reply.
  device::Status Query(int axis, std::uint8_t opcode, int result_words, pmd::Reply* reply);
  device::Status ReadRegister(int axis, Register r, std::int64_t* value);
  /// Sets a register unless it already holds `value`; never twice (see the file comment).
  device::Status WriteRegister(int axis, Register r, std::int64_t value);
  /// Waits until the axis' profile has ended and learns its active target.
  device::Status ResolveActive(int axis);
  /// Makes `target` the axis' active target with one Update (none when it already is).
  device::Status UpdateTo(int axis, std::int64_t target);
  /// After a failure that may leave the chip mid-packet or the mirrors stale.
  device::Status Fail(device::Status s);
  device::Status EnsureInitialized();
  /// An idempotent command (a configuration Set*): re-sent until the chip answers it OK.
  device::Status Command(const pmd::Command& command);
  device::Status ConfigureAxis(int axis);
  /// Sends one Update to `axis`; after an unclear reply `took` says whether the chip executed
  /// it (then it is not sent again), else it is re-sent (at most max_resends times). `took`
  /// clears its second argument when the chip would show the same had the Update never
  /// arrived (the Update is then recorded unconfirmed).
  device::Status UpdateOnce(int axis, const std::function<device::Status(bool*, bool*)>& took);
  /// An Update during homing: re-sent only when the chip shows it did not take it.
  /// `at_target`: the axis stands at `target` already.
  device::Status HomingUpdate(int axis, std::int32_t target, bool at_target);
  /// One homing sweep to `target` counts; with `capture` (kCaptureIndex or kCaptureHome, or -1
  /// for none) it stops smoothly at the first capture: *captured and *capture_counts.
  device::Status HomingMove(int axis, std::int32_t target, int capture, bool* captured,
                            std::int32_t* capture_counts);
  device::Status HomeAxis(int axis);
  /// Shifts the axis' position counter by `delta` counts (AdjustActualPosition), never twice.
  device::Status AdjustPosition(int axis, std::int32_t delta);
  /// The Update that executes a pending stop, never twice (a second would restart the profile).
  device::Status StopUpdate(int axis);
  device::Status Failed(int axis, const std::string& step, device::Status s);
  /// Records a state-changing command in command_log_: `executed` (confirmed), or sent and
  /// perhaps executed (unconfirmed). Other commands are not recorded.
  void Record(const pmd::Command& command, bool executed);

  std::unique_ptr<ByteLink> link_;
  BiclopsOptions options_;
  Clock* clock_;
  mutable std::mutex mu_;
  pmd::ReplyDecoder decoder_;
  Clock::TimePoint created_, call_start_, last_rx_;
  bool silent_ = false;
  double silence_limit_s_ = 0.4;   ///< silence_timeout_s, or the line probe's length
  bool probing_ = false;           ///< in a line probe: nothing heard since it began
  int line_probes_left_ = 0;       ///< line probes granted (during ConfigureAndHome)
  std::uint64_t line_probes_ = 0;  ///< line probes begun
  bool need_sync_ = true;
  bool initialized_ = false;
  std::array<std::array<Known, kRegisters>, 3> reg_{};  ///< buffered registers per axis
  std::array<Known, 3> active_target_{};                ///< the profile's target per axis
  std::array<bool, 3> at_rest_{};                       ///< seen at rest, and no Update sent since
  /// Where Read last found each axis at rest (rad), valid while at_rest_ holds and
  /// rest_known_ says Read saw it (homing and resyncs set at_rest_ without a position).
  std::array<double, 3> rest_q_{};
  std::array<bool, 3> rest_known_{};
  std::uint16_t version_chip_ = 0, version_software_ = 0;
  double cycle_s_ = 0.0;
  std::array<std::int32_t, 3> velocity_reg_{};
  std::array<std::uint32_t, 3> accel_reg_{};
  double longest_move_s_ = 0.0;
  double rtt_s_ = 0.0;       ///< mean time from a packet to its complete reply
  double zero_rtt_s_ = 0.0;  ///< mean time from a resync zero to the first byte of its answer
  BiclopsCounters counters_;
  bool homed_ = false;
  const StopRequest* stop_ = nullptr;  ///< during ConfigureAndHome
  std::string last_error_;
  CommandLog<pmd::Command> command_log_;
};

}  // namespace hgrasp::drivers
