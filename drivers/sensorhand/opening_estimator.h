#pragma once
/// @file Dead reckoning of a SensorHand Speed's opening from what a stock hand gives
/// (drivers/sensorhand/PROTOCOL.md, "What the driver infers"): the speed settings it executed
/// and when, the grip force and the state byte of its data stream, and the ends of its range.
/// A stock hand reports no finger position, so the opening is the integral of the commanded
/// speed over time, through the fingers' acceleration and the motor's torque-speed line against
/// an object, set to the limit whenever the stream shows the fingers blocked at an end stop.
///
/// A plain model without I/O or clock of its own: the driver feeds it times (s) on its steady
/// clock. It is a value type, so the driver can keep a copy from before a command and replay
/// the samples once it knows when the command took effect.

#include <algorithm>
#include <cstdint>

#include "sensorhand/sensorhand_codec.h"

namespace hgrasp::drivers::sensorhand {

/// The hand's motion as the estimator models it (PROTOCOL.md, "Speeds, forces and the hand's
/// mechanics"): the same figures the driver's options give.
struct HandMotionModel {
  double max_opening_m = 0.10;   ///< the open end stop (m)
  double full_speed_m_s = 0.30;  ///< pad-distance rate at speed byte 0x85 (m/s)
  double full_force_n = 100.0;   ///< stall force at close speed 0x85 (N)
  double accel_m_s2 = 10.0;      ///< finger acceleration and deceleration (m/s^2)
  /// Relative error of the speed scale (a share, 0.02 = 2%): the uncertainty grows by this
  /// share of every metre travelled.
  double speed_error = 0.02;
};

/// The opening estimate and how far it may be off.
class OpeningEstimator {
 public:
  /// Opening 0 at time 0 under the default model.
  OpeningEstimator() = default;
  /// Starts at `opening_m` at time `t_s`, fingers still, speed 0, with the given uncertainty.
  OpeningEstimator(const HandMotionModel& m, double t_s, double opening_m, double uncertainty_m);

  /// Integrates the motion up to `t_s` (earlier times are ignored) under the speed setting in
  /// force and the grip force last observed.
  void AdvanceTo(double t_s);
  /// The hand took the speed setting `s` at `t_s`, known to within +-timing_uncertainty_s: the
  /// uncertainty grows by the change of speed times that.
  void Execute(double t_s, const SpeedSetting& s, double timing_uncertainty_s);
  /// Widens the uncertainty by `m` metres (m >= 0).
  void AddUncertainty(double m) { sigma_ += std::max(0.0, m); }
  /// The estimate is lost (the driver could not learn a setting): lost() until the next fix,
  /// and the uncertainty widened by `m` metres.
  void MarkLost(double m) {
    lost_ = true;
    AddUncertainty(m);
  }
  /// A stream sample of `t_s`: its grip force (N) and state byte (MotionState values; others
  /// are ignored). The travel since the last sample counts fully into the uncertainty when
  /// samples were missing (more than kBlindGapS between two): an object may have stopped the
  /// fingers anywhere along it unseen; if they were closing in it and come back pressing, the
  /// estimate is lost(). Idle: the fingers are still. Blocked under an open speed: at the open end
  /// stop (max_opening_m). Blocked under a close speed with no force: the fingers meet (0).
  /// Blocked under a close speed with a force: stalled on an object, still where they are.
  void Observe(double t_s, double force_n, std::uint8_t state);

  /// A gap between samples longer than this (s, three stream periods) is travel unobserved.
  static constexpr double kBlindGapS = 3 * kDumpPeriodS;

  double time_s() const { return t_; }
  double opening_m() const { return y_; }
  double velocity_m_s() const { return v_; }
  /// A bound on |estimate - true opening| (m) under the model's errors.
  double uncertainty_m() const { return sigma_; }
  /// Where the fingers come to rest if the speed goes to 0 now (m), clamped to the range.
  double RestOpening() const;
  /// The speed setting the estimate runs under.
  const SpeedSetting& setting() const { return setting_; }
  /// Whether an end stop has fixed the estimate since construction.
  bool referenced() const { return referenced_; }
  /// Whether the estimate is lost: the fingers were closing while samples were missing and
  /// came back pressing an object, so they stopped somewhere unseen; or the driver could not
  /// learn a setting (MarkLost). An end stop clears it.
  bool lost() const { return lost_; }
  /// How often an end stop fixed the estimate, and the last correction (m, true - estimate).
  int fixes() const { return fixes_; }
  double last_correction_m() const { return last_correction_m_; }
  double max_abs_correction_m() const { return max_abs_correction_m_; }

 private:
  double TargetVelocity() const;
  void FixAt(double opening_m);

  HandMotionModel m_;
  double t_ = 0.0, y_ = 0.0, v_ = 0.0, sigma_ = 0.0;
  double force_n_ = 0.0;        ///< the grip force last observed
  double t_observed_ = 0.0;     ///< time of the last sample
  double travel_since_observed_ = 0.0;  ///< |travel| since the last sample (m)
  double stall_force_n_ = 0.0;  ///< set by the last close speed: the motor stalls there
  SpeedSetting setting_;
  bool stalled_ = false;  ///< blocked on an object under the setting: still until it changes
  bool referenced_ = false;
  bool lost_ = false;
  int fixes_ = 0;
  double last_correction_m_ = 0.0, max_abs_correction_m_ = 0.0;
};

}  // namespace hgrasp::drivers::sensorhand
