#include "serial/faulty_link.h"

namespace hgrasp::drivers {

FaultyLink::FaultyLink(std::unique_ptr<ByteLink> inner, const FaultPlan& plan,
                       const Clock& clock)
    : inner_(std::move(inner)), clock_(&clock), faults_(plan, clock) {}

LineFaults::LineFaults(const FaultPlan& plan, const Clock& clock)
    : plan_(plan), clock_(&clock), rng_(plan.seed) {
  const Clock::TimePoint now = clock_->Now();
  dropout_end_ = now;
  next_dropout_ = now;
  if (plan_.dropouts_per_s > 0.0) {
    std::exponential_distribution<double> gap(plan_.dropouts_per_s);
    next_dropout_ = now + Clock::FromSeconds(gap(rng_));
  }
}

void LineFaults::Cut(bool cut) {
  std::lock_guard<std::mutex> lock(mu_);
  cut_ = cut;
}

void LineFaults::CutFromDevice(bool cut) {
  std::lock_guard<std::mutex> lock(mu_);
  cut_from_device_ = cut;
}

FaultCounts LineFaults::counts() const {
  std::lock_guard<std::mutex> lock(mu_);
  return counts_;
}

bool LineFaults::InDropout(Clock::TimePoint now) {
  if (plan_.dropouts_per_s <= 0.0) return false;
  while (now >= next_dropout_) {
    dropout_end_ = next_dropout_ + Clock::FromSeconds(plan_.dropout_s);
    ++counts_.dropouts;
    std::exponential_distribution<double> gap(plan_.dropouts_per_s);
    next_dropout_ = dropout_end_ + Clock::FromSeconds(plan_.min_dropout_gap_s + gap(rng_));
  }
  return now < dropout_end_;
}

bool LineFaults::cut() const {
  std::lock_guard<std::mutex> lock(mu_);
  return cut_;
}

void LineFaults::Pass(std::span<const std::uint8_t> in, bool from_device,
                      std::vector<std::uint8_t>* out) {
  std::lock_guard<std::mutex> lock(mu_);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> other(1, 255), any(0, 255);
  const bool lost = cut_ || (from_device && cut_from_device_) || InDropout(clock_->Now());
  for (std::uint8_t b : in) {
    ++counts_.bytes;
    if (lost) {
      ++counts_.dropped;
      continue;
    }
    if (plan_.corrupt_probability > 0.0 && u(rng_) < plan_.corrupt_probability) {
      b = static_cast<std::uint8_t>(b ^ other(rng_));
      ++counts_.corrupted;
    }
    out->push_back(b);
    if (plan_.garbage_probability > 0.0 && u(rng_) < plan_.garbage_probability) {
      out->push_back(static_cast<std::uint8_t>(any(rng_)));
      ++counts_.inserted;
    }
  }
}

device::Status FaultyLink::Write(std::span<const std::uint8_t> bytes) {
  std::vector<std::uint8_t> out;
  out.reserve(bytes.size() + 4);
  faults_.Pass(bytes, /*from_device=*/false, &out);
  if (out.empty()) return device::Status::kOk;  // lost on the wire: the sender cannot tell
  return inner_->Write(out);
}

device::Status FaultyLink::Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) {
  *n = 0;
  const Clock::TimePoint deadline = clock_->Now() + Clock::FromSeconds(std::max(timeout_s, 0.0));
  for (;;) {
    const double left = Clock::ToSeconds(deadline - clock_->Now());
    // Read at most half the buffer: inserted garbage may double what comes out.
    std::vector<std::uint8_t> raw(std::max<std::size_t>(1, buf.size() / 2));
    std::size_t got = 0;
    const device::Status s = inner_->Read(raw, std::max(left, 0.0), &got);
    if (s != device::Status::kOk) return s;
    std::vector<std::uint8_t> out;
    faults_.Pass(std::span<const std::uint8_t>(raw.data(), got), /*from_device=*/true, &out);
    if (!out.empty()) {
      // Inserted bytes beyond the caller's buffer are dropped too (an overrun).
      *n = std::min(out.size(), buf.size());
      std::copy(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(*n), buf.begin());
      return device::Status::kOk;
    }
    if (clock_->Now() >= deadline) return device::Status::kTimeout;
  }
}

}  // namespace hgrasp::drivers
