#include "emulators/motion.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::drivers {

TrapezoidAxis::TrapezoidAxis(const AxisLimits& limits, double position)
    : limits_(limits), x_(std::clamp(position, limits.min, limits.max)), target_(x_) {}

void TrapezoidAxis::MoveTo(double target, double speed, double accel) {
  target_ = std::clamp(target, limits_.min, limits_.max);
  speed_ = std::clamp(std::abs(speed), 0.0, limits_.max_speed);
  accel_ = std::clamp(std::abs(accel), 1e-12, limits_.max_accel);
  velocity_mode_ = false;
  moving_ = speed_ > 0.0 && (target_ != x_ || v_ != 0.0);
}

void TrapezoidAxis::MoveAt(double velocity, double accel) {
  speed_ = std::clamp(velocity, -limits_.max_speed, limits_.max_speed);
  accel_ = std::clamp(std::abs(accel), 1e-12, limits_.max_accel);
  velocity_mode_ = true;
  moving_ = speed_ != 0.0 || v_ != 0.0;
}

void TrapezoidAxis::Stop() {
  velocity_mode_ = true;
  speed_ = 0.0;
  accel_ = limits_.max_accel;
  moving_ = v_ != 0.0;
}

void TrapezoidAxis::Advance(double dt) {
  // Sub-steps of at most 1 ms keep the profile's corners sharp for any caller's dt.
  while (dt > 0.0 && moving_) {
    const double h = std::min(dt, 1e-3);
    dt -= h;
    double v_want;
    if (velocity_mode_) {
      v_want = speed_;
    } else {
      const double d = target_ - x_;
      // The fastest speed from which the axis, losing accel * h per step, still stops within
      // |d|: v (v / (a h) + 1) h / 2 <= |d|.
      const double ah = accel_ * h;
      const double v_stop = 0.5 * (-ah + std::sqrt(ah * ah + 8.0 * accel_ * std::abs(d)));
      v_want = std::copysign(std::min(speed_, v_stop), d);
    }
    const double dv = std::clamp(v_want - v_, -accel_ * h, accel_ * h);
    v_ += dv;
    x_ += v_ * h;
    if (!velocity_mode_) {
      // Arrive exactly: within one step's travel at creeping speed.
      if (std::abs(target_ - x_) <= std::max(accel_ * h * h, 1e-12) &&
          std::abs(v_) <= accel_ * h + 1e-12) {
        x_ = target_;
        v_ = 0.0;
        moving_ = false;
      }
    } else if (speed_ == 0.0 && v_ == 0.0) {
      moving_ = false;
    }
    if (x_ <= limits_.min || x_ >= limits_.max) {
      x_ = std::clamp(x_, limits_.min, limits_.max);
      v_ = 0.0;
      if (velocity_mode_ || x_ == target_) moving_ = false;
    }
  }
}

}  // namespace hgrasp::drivers
