#include "emulators/emulator.h"

#include <poll.h>
#include <unistd.h>

#include <cerrno>

namespace hgrasp::drivers {

EmulatorHost::EmulatorHost(std::unique_ptr<DeviceEmulator> device, std::string link_path,
                           double tick_s)
    : device_(std::move(device)),
      tick_s_(tick_s),
      pty_(std::move(link_path)),
      start_(std::chrono::steady_clock::now()) {
  thread_ = std::thread([this] { Run(); });
}

EmulatorHost::~EmulatorHost() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  thread_.join();
}

std::string EmulatorHost::port() const {
  std::lock_guard<std::mutex> lock(mu_);
  return pty_.port();
}

void EmulatorHost::Vanish() {
  std::lock_guard<std::mutex> lock(mu_);
  pty_.Close();
}

void EmulatorHost::Reappear() {
  std::lock_guard<std::mutex> lock(mu_);
  pty_.Reopen();
}

double EmulatorHost::Now() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

EmulatorHost::Timing EmulatorHost::timing() const {
  std::lock_guard<std::mutex> lock(mu_);
  return timing_;
}

namespace {

// Writes all of `bytes` to the (non-blocking) master; what the pty cannot take within a short
// while is lost, as on a serial line nobody listens to.
void WriteAll(int fd, const std::vector<std::uint8_t>& bytes) {
  std::size_t done = 0;
  int stalls = 0;
  while (done < bytes.size() && stalls < 50) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EAGAIN) {
      pollfd p{fd, POLLOUT, 0};
      ::poll(&p, 1, 2);
      ++stalls;
      continue;
    }
    return;
  }
}

}  // namespace

void EmulatorHost::Run() {
  std::vector<std::uint8_t> out;
  std::uint8_t buf[512];
  const int tick_ms = std::max(1, static_cast<int>(tick_s_ * 1000.0 + 0.5));
  // A pass is due a tick after the one before began (sooner if bytes arrive): a pass that
  // starts later than that, because this thread was off the CPU or the pass before took long
  // (or a test held the device), is late by the difference.
  double due = Now() + tick_ms * 1e-3;
  auto account = [&](double t) {  // under mu_
    ++timing_.ticks;
    const double late = t - due;
    if (late > kOverrunS) ++timing_.overruns;
    timing_.worst_late_s = std::max(timing_.worst_late_s, late);
    due = t + tick_ms * 1e-3;
  };
  for (;;) {
    int fd;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (stop_) return;
      fd = pty_.master_fd();
    }
    if (fd < 0) {
      // The port has vanished: the device keeps running without a link.
      {
        std::lock_guard<std::mutex> lock(mu_);
        out.clear();
        const double t = Now();
        account(t);
        device_->Advance(t, &out);
      }
      ::usleep(static_cast<useconds_t>(tick_ms * 1000));
      continue;
    }
    pollfd p{fd, POLLIN, 0};
    ::poll(&p, 1, tick_ms);
    const double woke = Now();
    std::lock_guard<std::mutex> lock(mu_);
    if (stop_) return;
    if (pty_.master_fd() != fd) continue;  // vanished or reopened meanwhile
    out.clear();
    const double t = Now();
    // When bytes woke poll they may have waited since before: the lateness is a lower bound.
    account(woke);
    // Everything that has arrived goes to the device before it may send anything of its own,
    // whatever poll said and however late this thread runs: a frame the device sends reflects
    // every command that reached it before, as on a device with a timer of its own. (Advancing
    // first sent samples made after a command had arrived that did not show it, and a driver
    // that counts such samples to call a command lost sent it twice: SensorHand under load.)
    for (;;) {
      const ssize_t n = ::read(fd, buf, sizeof(buf));  // the master is non-blocking
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      device_->Receive(std::span<const std::uint8_t>(buf, static_cast<std::size_t>(n)), t, &out);
    }
    device_->Advance(t, &out);
    if (!out.empty()) WriteAll(fd, out);
  }
}

}  // namespace hgrasp::drivers
