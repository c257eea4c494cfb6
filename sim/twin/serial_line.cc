#include "sim/twin/serial_line.h"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <limits>

#include "common/error.h"

namespace hgrasp::sim {

using device::Status;

class SerialLine::InProcessLink final : public drivers::ByteLink {
 public:
  InProcessLink(SerialLine* line, SimClock& clock) : line_(line), clock_(clock) {}
  Status Write(std::span<const std::uint8_t> bytes) override {
    if (line_->vanished_) return Status::kDisconnected;
    line_->host_in_.insert(line_->host_in_.end(), bytes.begin(), bytes.end());
    return Status::kOk;
  }
  Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override {
    *n = 0;
    const Clock::TimePoint deadline = clock_.Now() + Clock::FromSeconds(std::max(0.0, timeout_s));
    clock_.RunUntil(deadline, [this] { return !line_->host_out_.empty() || line_->vanished_; });
    if (line_->vanished_) return Status::kDisconnected;
    if (line_->host_out_.empty()) return Status::kTimeout;
    while (*n < buf.size() && !line_->host_out_.empty()) {
      buf[(*n)++] = line_->host_out_.front();
      line_->host_out_.pop_front();
    }
    return Status::kOk;
  }
  void Discard() override { line_->host_out_.clear(); }

 private:
  SerialLine* line_;
  SimClock& clock_;
};

SerialLine::SerialLine(std::string key, std::unique_ptr<drivers::DeviceEmulator> device,
                       std::string link_path, int baud, std::optional<drivers::FaultPlan> faults)
    : key_(std::move(key)),
      device_(std::move(device)),
      pty_(std::make_unique<drivers::Pty>(std::move(link_path))),
      baud_(baud),
      byte_s_(10.0 / baud) {
  if (faults) faults_.emplace(*faults);
}

SerialLine::SerialLine(std::string key, std::unique_ptr<drivers::DeviceEmulator> device, int baud,
                       std::optional<drivers::FaultPlan> faults, const Clock& clock)
    : key_(std::move(key)), device_(std::move(device)), baud_(baud), byte_s_(10.0 / baud) {
  if (faults) faults_.emplace(*faults, clock);
}

SerialLine::~SerialLine() = default;

std::unique_ptr<drivers::ByteLink> SerialLine::HostLink(SimClock& clock) {
  HGRASP_DEMAND_MSG(in_process(), "SerialLine::HostLink: the line is on a pty");
  return std::make_unique<InProcessLink>(this, clock);
}

void SerialLine::Cut(bool cut) {
  cut_ = cut;
  if (faults_) faults_->Cut(cut);
}

void SerialLine::CutFromDevice(bool cut) {
  cut_from_device_ = cut;
  if (faults_) faults_->CutFromDevice(cut);
}

void SerialLine::Vanish() {
  if (pty_) pty_->Close();
  vanished_ = true;
  host_in_.clear();
  host_out_.clear();
  rx_.clear();
  tx_.clear();
}

void SerialLine::Reappear() {
  if (pty_) pty_->Reopen();
  vanished_ = false;
}

drivers::FaultCounts SerialLine::fault_counts() const {
  return faults_ ? faults_->counts() : drivers::FaultCounts{};
}

double SerialLine::NextDue() const {
  double t = std::numeric_limits<double>::infinity();
  if (!rx_.empty()) t = std::min(t, rx_.front().first);
  if (!tx_.empty()) t = std::min(t, tx_.front().first);
  return t;
}

void SerialLine::Poll(double t_s) {
  const int master = fd();
  std::vector<std::uint8_t> in, passed;
  if (in_process()) {
    in.assign(host_in_.begin(), host_in_.end());
    host_in_.clear();
  } else if (master >= 0) {
    std::uint8_t buf[512];
    for (;;) {
      const ssize_t n = ::read(master, buf, sizeof buf);  // the master is non-blocking
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      in.insert(in.end(), buf, buf + n);
    }
  }
  if (!in.empty()) {
    bytes_from_host_ += in.size();
    if (faults_) {
      faults_->Pass(in, /*from_device=*/false, &passed);
    } else if (!cut_) {
      passed = std::move(in);
    }
    for (std::uint8_t b : passed) {
      rx_free_s_ = std::max(rx_free_s_, t_s) + byte_s_;
      rx_.emplace_back(rx_free_s_, b);
    }
  }
  // What has arrived by now goes to the device before it may send anything of its own (as
  // EmulatorHost does, for the same reason).
  std::vector<std::uint8_t> out, chunk;
  while (!rx_.empty() && rx_.front().first <= t_s) {
    chunk.clear();
    const double t_arrived = rx_.front().first;
    while (!rx_.empty() && rx_.front().first <= t_s && chunk.size() < 64) {
      chunk.push_back(rx_.front().second);
      rx_.pop_front();
    }
    device_->Receive(chunk, std::max(t_arrived, 0.0), &out);
  }
  device_->Advance(t_s, &out);
  for (std::uint8_t b : out) {
    tx_free_s_ = std::max(tx_free_s_, t_s) + byte_s_;
    tx_.emplace_back(tx_free_s_, b);
  }
  // Send what the wire has carried by now.
  std::vector<std::uint8_t> due, sent;
  while (!tx_.empty() && tx_.front().first <= t_s) {
    due.push_back(tx_.front().second);
    tx_.pop_front();
  }
  if (due.empty()) return;
  if (faults_) {
    faults_->Pass(due, /*from_device=*/true, &sent);
  } else if (!cut_ && !cut_from_device_) {
    sent = std::move(due);
  }
  if (sent.empty()) return;
  if (in_process()) {
    if (vanished_) return;
    host_out_.insert(host_out_.end(), sent.begin(), sent.end());
    bytes_to_host_ += sent.size();
    return;
  }
  if (master < 0) return;
  std::size_t done = 0;
  while (done < sent.size()) {
    const ssize_t n = ::write(master, sent.data() + done, sent.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    break;  // the pty is full: nobody is reading the port
  }
  bytes_to_host_ += done;
  bytes_unsent_ += sent.size() - done;
}

}  // namespace hgrasp::sim
