#include "sensorhand/opening_estimator.h"

#include <algorithm>
#include <cmath>

namespace hgrasp::drivers::sensorhand {
namespace {

// Below this grip force (N) a blocked close is the fingers meeting, not an object: one force
// count is 1.09 N, so this is "the force byte reads 0".
constexpr double kNoForceN = 0.5;
// Closing travel in a gap of samples above which the estimate is lost if they come back
// pressing (m).
constexpr double kUnseenM = 1e-4;

}  // namespace

OpeningEstimator::OpeningEstimator(const HandMotionModel& m, double t_s, double opening_m,
                                   double uncertainty_m)
    : m_(m),
      t_(t_s),
      y_(std::clamp(opening_m, 0.0, m.max_opening_m)),
      sigma_(std::max(0.0, uncertainty_m)),
      t_observed_(t_s) {}

double OpeningEstimator::TargetVelocity() const {
  if (stalled_) return 0.0;
  if (setting_.open != 0) {
    // At the end stop the fingers stay still whatever the speed.
    return y_ >= m_.max_opening_m ? 0.0 : m_.full_speed_m_s * SpeedFraction(setting_.open);
  }
  if (setting_.close == 0 || y_ <= 0.0) return 0.0;
  double v = -m_.full_speed_m_s * SpeedFraction(setting_.close);
  // The motor's torque-speed line: against an object it closes the slower the harder it
  // presses, and stalls at the stall force of its close byte.
  if (force_n_ > kNoForceN) {
    v *= stall_force_n_ > 0.0 ? std::max(0.0, 1.0 - force_n_ / stall_force_n_) : 0.0;
  }
  return v;
}

void OpeningEstimator::AdvanceTo(double t_s) {
  double dt = t_s - t_;
  if (!(dt > 0.0)) return;
  t_ = t_s;
  const double vt = TargetVelocity();
  const double y0 = y_;
  while (dt > 0.0) {
    // At an end stop and pushed into it: the fingers stay there.
    if ((y_ >= m_.max_opening_m && vt >= 0.0) || (y_ <= 0.0 && vt <= 0.0)) {
      v_ = 0.0;
      break;
    }
    double h = dt;
    if (v_ != vt) {
      // Accelerate towards the target speed (a trapezoid profile, as the motor's controller).
      const double ramp = std::abs(vt - v_) / m_.accel_m_s2;
      h = std::min(dt, ramp);
      const double dv = (vt > v_ ? 1.0 : -1.0) * m_.accel_m_s2 * h;
      y_ += v_ * h + 0.5 * dv * h;
      v_ = h >= ramp ? vt : v_ + dv;
    } else {
      y_ += v_ * h;
    }
    dt -= h;
    if (y_ >= m_.max_opening_m) {
      y_ = m_.max_opening_m;
      if (v_ > 0.0) v_ = 0.0;
    } else if (y_ <= 0.0) {
      y_ = 0.0;
      if (v_ < 0.0) v_ = 0.0;
    }
  }
  sigma_ += m_.speed_error * std::abs(y_ - y0);
  travel_since_observed_ += std::abs(y_ - y0);
}

void OpeningEstimator::Execute(double t_s, const SpeedSetting& s, double timing_uncertainty_s) {
  AdvanceTo(t_s);
  const double v_before = TargetVelocity();
  setting_ = s;
  stalled_ = false;
  // Only closing sets the stall force: stopped or opening, the gear holds what it pressed with.
  if (s.close != 0) stall_force_n_ = m_.full_force_n * SpeedFraction(s.close);
  sigma_ += std::abs(TargetVelocity() - v_before) * std::max(0.0, timing_uncertainty_s);
}

void OpeningEstimator::Observe(double t_s, double force_n, std::uint8_t state) {
  force_n = std::max(0.0, force_n);
  if (t_s > t_) {
    // Over the interval since the last sample the force went from the last value to this one:
    // the motor line runs on their mean (trapezoid rule), not on the older value alone, which
    // overrates the closing speed while the pads press into an object.
    force_n_ = 0.5 * (force_n_ + force_n);
    AdvanceTo(t_s);
  }
  if (t_s - t_observed_ > kBlindGapS) {
    sigma_ += travel_since_observed_;
    // Closing unseen and now pressing: the object stopped them at a point nobody saw (or, if
    // they pressed already, the force rose unseen, and the motor line ran on a stale force).
    if (setting_.close != 0 && force_n > kNoForceN && travel_since_observed_ > kUnseenM) {
      lost_ = true;
    }
  }
  travel_since_observed_ = 0.0;
  t_observed_ = std::max(t_observed_, t_s);
  force_n_ = force_n;
  switch (static_cast<MotionState>(state)) {
    case MotionState::kIdle:
      // Speeds 0 and the fingers still.
      if (setting_.stopped()) v_ = 0.0;
      break;
    case MotionState::kBlocked:
      if (setting_.open != 0) {
        FixAt(m_.max_opening_m);  // nothing but the end stop blocks opening
      } else if (setting_.close != 0) {
        if (force_n_ <= kNoForceN) {
          FixAt(0.0);  // the fingers meet
        } else {
          // Stalled on an object: still where the estimate has them, until the setting changes
          // (the measured force, a count below the stall, would not stop the motor line).
          v_ = 0.0;
          stalled_ = true;
        }
      }
      break;
    case MotionState::kOpening:
    case MotionState::kClosing:
      stalled_ = false;  // moving again (the object gave way)
      break;
    default:
      break;  // a value we do not know: no information
  }
}

void OpeningEstimator::FixAt(double opening_m) {
  last_correction_m_ = opening_m - y_;
  max_abs_correction_m_ = std::max(max_abs_correction_m_, std::abs(last_correction_m_));
  ++fixes_;
  y_ = opening_m;
  v_ = 0.0;
  sigma_ = 0.0;
  referenced_ = true;
  lost_ = false;
}

double OpeningEstimator::RestOpening() const {
  const double run_on = v_ * std::abs(v_) / (2.0 * m_.accel_m_s2);
  return std::clamp(y_ + run_on, 0.0, m_.max_opening_m);
}

}  // namespace hgrasp::drivers::sensorhand
