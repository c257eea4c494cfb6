#include "emulators/sim_line.h"

#include <algorithm>

namespace hgrasp::drivers {

using device::Status;

class SimLine::HostEnd final : public ByteLink {
 public:
  explicit HostEnd(SimLine* line) : line_(line) {}
  Status Write(std::span<const std::uint8_t> bytes) override { return line_->HostWrite(bytes); }
  Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override {
    return line_->HostRead(buf, timeout_s, n);
  }
  void Discard() override { line_->host_rx_.clear(); }

 private:
  SimLine* line_;
};

SimLine::SimLine(SimClock& clock, std::unique_ptr<DeviceEmulator> device, int baud,
                 std::optional<FaultPlan> faults, double tick_s)
    : clock_(clock),
      device_(std::move(device)),
      byte_time_(Clock::FromSeconds(10.0 / baud)),
      tick_(Clock::FromSeconds(tick_s)),
      faults_(faults.value_or(FaultPlan{}), clock),
      start_(clock.Now()) {
  std::weak_ptr<bool> alive = alive_;
  clock_.At(start_ + tick_, [this, alive] {
    if (!alive.expired()) Tick();
  });
}

SimLine::~SimLine() { alive_.reset(); }

std::unique_ptr<ByteLink> SimLine::Open() { return std::make_unique<HostEnd>(this); }

double SimLine::Now() const { return Clock::ToSeconds(clock_.Now() - start_); }

void SimLine::Vanish() {
  vanished_ = true;
  ++epoch_;
  host_rx_.clear();
}

void SimLine::Reappear() { vanished_ = false; }

void SimLine::Tick() {
  std::vector<std::uint8_t> out;
  device_->Advance(Now(), &out);
  Transmit(out);
  std::weak_ptr<bool> alive = alive_;
  clock_.At(clock_.Now() + tick_, [this, alive] {
    if (!alive.expired()) Tick();
  });
}

Status SimLine::HostWrite(std::span<const std::uint8_t> bytes) {
  if (vanished_) return Status::kDisconnected;
  bytes_from_host_ += bytes.size();
  std::vector<std::uint8_t> passed;
  faults_.Pass(bytes, /*from_device=*/false, &passed);
  std::weak_ptr<bool> alive = alive_;
  const std::uint64_t epoch = epoch_;
  for (std::uint8_t b : passed) {
    to_device_free_ = std::max(to_device_free_, clock_.Now()) + byte_time_;
    // The device acts on each byte as its stop bit arrives, then on what it has to say.
    clock_.At(to_device_free_, [this, alive, epoch, b] {
      if (alive.expired() || epoch != epoch_) return;
      std::vector<std::uint8_t> out;
      const std::uint8_t one[1] = {b};
      device_->Receive(one, Now(), &out);
      device_->Advance(Now(), &out);
      Transmit(out);
    });
  }
  return Status::kOk;
}

void SimLine::Transmit(const std::vector<std::uint8_t>& out) {
  std::weak_ptr<bool> alive = alive_;
  const std::uint64_t epoch = epoch_;
  for (std::uint8_t b : out) {
    to_host_free_ = std::max(to_host_free_, clock_.Now()) + byte_time_;
    clock_.At(to_host_free_, [this, alive, epoch, b] {
      if (alive.expired() || epoch != epoch_ || vanished_) return;
      std::vector<std::uint8_t> passed;
      const std::uint8_t one[1] = {b};
      faults_.Pass(one, /*from_device=*/true, &passed);
      bytes_to_host_ += passed.size();
      host_rx_.insert(host_rx_.end(), passed.begin(), passed.end());
    });
  }
}

Status SimLine::HostRead(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) {
  *n = 0;
  if (vanished_) return Status::kDisconnected;
  const Clock::TimePoint deadline = clock_.Now() + Clock::FromSeconds(std::max(0.0, timeout_s));
  clock_.RunUntil(deadline, [this] { return !host_rx_.empty() || vanished_; });
  if (vanished_) return Status::kDisconnected;
  if (host_rx_.empty()) return Status::kTimeout;
  while (*n < buf.size() && !host_rx_.empty()) {
    buf[(*n)++] = host_rx_.front();
    host_rx_.pop_front();
  }
  return Status::kOk;
}

}  // namespace hgrasp::drivers
