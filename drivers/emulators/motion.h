#pragma once
/// @file One axis of a device model: trapezoidal velocity profile (acceleration, cruise,
/// deceleration) towards a target within position limits, advanced in time. The emulators'
/// motion is made of these.

namespace hgrasp::drivers {

struct AxisLimits {
  double min = -1e9, max = 1e9;  ///< position range (device units)
  double max_speed = 1.0;        ///< > 0, units/s
  double max_accel = 1.0;        ///< > 0, units/s^2
};

class TrapezoidAxis {
 public:
  explicit TrapezoidAxis(const AxisLimits& limits, double position = 0.0);

  /// Moves towards `target` (clamped into the limits) at most at `speed` (clamped to
  /// max_speed) with `accel` (clamped to max_accel); replaces any motion under way, from the
  /// current position and velocity.
  void MoveTo(double target, double speed, double accel);
  /// Moves at constant `velocity` (clamped) until a limit or Stop (velocity mode).
  void MoveAt(double velocity, double accel);
  /// Decelerates to rest at max_accel.
  void Stop();
  /// Advances the state by dt seconds (>= 0).
  void Advance(double dt);

  double position() const { return x_; }
  double velocity() const { return v_; }
  double target() const { return target_; }
  bool moving() const { return moving_; }
  const AxisLimits& limits() const { return limits_; }

 private:
  AxisLimits limits_;
  double x_ = 0.0, v_ = 0.0;
  double target_ = 0.0, speed_ = 0.0, accel_ = 1.0;
  bool velocity_mode_ = false, moving_ = false;
};

}  // namespace hgrasp::drivers
