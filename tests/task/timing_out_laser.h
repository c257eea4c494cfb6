#pragma once
// A laser board that stops answering: it passes `answers` motor commands and reads to the
// device it wraps, then times out on every one (as a real board whose link went silent would);
// SetLaser always reaches the laser, and every state it was set to is recorded, so a test can see
// what the caller left it in.

#include <memory>
#include <utility>
#include <vector>

#include "device/stripe_laser.h"

namespace hgrasp::testing {

class TimingOutLaser : public device::StripeLaser {
 public:
  TimingOutLaser(std::unique_ptr<device::StripeLaser> inner, int answers)
      : inner_(std::move(inner)), answers_(answers) {}

  device::Status Read(device::StripeLaserState* state) override {
    return Answer() ? inner_->Read(state) : device::Status::kTimeout;
  }
  device::Status SetLaser(bool on) override {
    set_.push_back(on);
    return inner_->SetLaser(on);
  }
  device::Status MoveTo(std::int32_t count, double speed_counts_s) override {
    return Answer() ? inner_->MoveTo(count, speed_counts_s) : device::Status::kTimeout;
  }
  device::Status Stop() override {
    ++stops_;
    return Answer() ? inner_->Stop() : device::Status::kTimeout;
  }

  /// Every SetLaser argument, in order.
  const std::vector<bool>& set() const { return set_; }
  /// Stop calls.
  int stops() const { return stops_; }

 private:
  bool Answer() { return answers_-- > 0; }

  std::unique_ptr<device::StripeLaser> inner_;
  int answers_;
  std::vector<bool> set_;
  int stops_ = 0;
};

}  // namespace hgrasp::testing
