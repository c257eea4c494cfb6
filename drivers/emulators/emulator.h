#pragma once
/// @file Device emulators: a device's protocol and a model of its motion, served byte for byte
/// on a pseudo-terminal so the real drivers can be tested without the hardware.
///
/// A DeviceEmulator is pure protocol + model, with no I/O and no clock of its own: the host
/// hands it received bytes and the time, and sends what it answers. EmulatorHost runs one on a
/// Pty in a thread of its own.

#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "serial/pty.h"

namespace hgrasp::drivers {

class DeviceEmulator {
 public:
  virtual ~DeviceEmulator() = default;
  /// Bytes from the host, received at `t_s` (s since the host started); append the device's
  /// answers to *out. Called with any split of the stream (one byte, a frame and a half, ...).
  virtual void Receive(std::span<const std::uint8_t> in, double t_s,
                       std::vector<std::uint8_t>* out) = 0;
  /// Advances the device model to `t_s`; may append bytes the device sends on its own (data
  /// streams) to *out. Called every tick, after every byte that has arrived by then has been
  /// handed to Receive (so Receive advances the model to its `t_s` itself where it needs to).
  virtual void Advance(double t_s, std::vector<std::uint8_t>* out) = 0;
};

/// Serves a DeviceEmulator on a pty until destroyed.
class EmulatorHost {
 public:
  /// `link_path`: optional stable symlink to the pty (see Pty). `tick_s`: how often Advance runs.
  explicit EmulatorHost(std::unique_ptr<DeviceEmulator> device, std::string link_path = "",
                        double tick_s = 0.002);
  ~EmulatorHost();
  EmulatorHost(const EmulatorHost&) = delete;
  EmulatorHost& operator=(const EmulatorHost&) = delete;

  /// The path a driver opens.
  std::string port() const;

  /// The port vanishes (the pty closes, the link goes away) until Reappear().
  void Vanish();
  /// The port comes back (a new pty behind the same link path).
  void Reappear();

  /// Runs `f(device)` while the host's thread is held off: to inspect or script the model.
  template <class F>
  auto With(F&& f) {
    std::lock_guard<std::mutex> lock(mu_);
    return f(*device_);
  }

  /// Seconds since the host started (the clock the emulator sees).
  double Now() const;

  /// How well the host's thread kept its ticks. A real device acts on a byte as it arrives; this
  /// one acts when its thread next runs, so a host thread held off the CPU for 30 ms lets the
  /// device run on 30 ms past a stop. Counted, not hidden: a test that times the device bounds
  /// its error by what the host reports here.
  struct Timing {
    std::uint64_t ticks = 0;     ///< passes of the host's loop
    std::uint64_t overruns = 0;  ///< passes that came more than kOverrunS after their due time
    double worst_late_s = 0.0;   ///< the latest pass after its due time (s)
  };
  /// Ticks later than this past their due time count as overruns (s).
  static constexpr double kOverrunS = 0.003;
  Timing timing() const;

 private:
  void Run();

  std::unique_ptr<DeviceEmulator> device_;
  double tick_s_;
  mutable std::mutex mu_;
  Pty pty_;
  bool stop_ = false;
  Timing timing_;
  std::chrono::steady_clock::time_point start_;
  std::thread thread_;
};

}  // namespace hgrasp::drivers
