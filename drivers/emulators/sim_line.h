#pragma once
/// @file One serial line in simulated time: a DeviceEmulator at the far end of an 8N1 wire
/// (10 bits a byte, each way), optionally through a noisy line's faults (FaultPlan: corruption,
/// garbage, dropouts, a cut either way or both), and a port that can vanish. The driver's end
/// is a ByteLink (Open()). No pty and no thread: bytes reach the device one byte time after the
/// one before, the device's ticks and its answers travelling back are events of a SimClock, run
/// while the driver waits in a Read. The same driver code as on the real wire, the same
/// emulator as behind a pty (EmulatorHost), so a protocol test replays exactly from its seed
/// and does not depend on the machine's load.
///
/// Time: the emulator sees seconds since the line was made. Faults are drawn at the times the
/// bytes pass (a dropout silences both ways for its length).

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "common/clock.h"
#include "emulators/emulator.h"
#include "serial/byte_link.h"
#include "serial/faulty_link.h"

namespace hgrasp::drivers {

class SimLine {
 public:
  /// `baud`: bytes take 10 / baud s each way. `faults`: none when nullopt. `tick_s`: how often
  /// the device's Advance runs between bytes (EmulatorHost's default).
  SimLine(SimClock& clock, std::unique_ptr<DeviceEmulator> device, int baud,
          std::optional<FaultPlan> faults = std::nullopt, double tick_s = 0.002);
  ~SimLine();
  SimLine(const SimLine&) = delete;
  SimLine& operator=(const SimLine&) = delete;

  /// The driver's end of the line (this line must outlive it). Reading it runs the clock.
  std::unique_ptr<ByteLink> Open();

  /// Runs `f(device)`: to inspect or script the model (nothing runs meanwhile).
  template <class F>
  auto With(F&& f) {
    return f(*device_);
  }
  DeviceEmulator& device() { return *device_; }

  /// Seconds since the line was made (the time the emulator sees).
  double Now() const;
  SimClock& clock() { return clock_; }

  /// The port vanishes (the driver's reads and writes fail kDisconnected; bytes on the wire are
  /// lost) until Reappear(). The device keeps running.
  void Vanish();
  void Reappear();
  /// Both wires cut, or mended.
  void Cut(bool cut) { faults_.Cut(cut); }
  /// The device's transmit wire cut (the driver hears nothing; the device still hears it).
  void CutFromDevice(bool cut) { faults_.CutFromDevice(cut); }
  FaultCounts counts() const { return faults_.counts(); }

  std::uint64_t bytes_from_host() const { return bytes_from_host_; }
  std::uint64_t bytes_to_host() const { return bytes_to_host_; }

 private:
  class HostEnd;
  // The host's bytes onto the wire towards the device.
  device::Status HostWrite(std::span<const std::uint8_t> bytes);
  device::Status HostRead(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n);
  // The device's answers onto the wire towards the host, each at its byte time.
  void Transmit(const std::vector<std::uint8_t>& out);
  void Tick();

  SimClock& clock_;
  std::unique_ptr<DeviceEmulator> device_;
  Clock::Duration byte_time_, tick_;
  LineFaults faults_;
  Clock::TimePoint start_;
  Clock::TimePoint to_device_free_{0}, to_host_free_{0};  // when each wire is next free
  std::deque<std::uint8_t> host_rx_;                        // arrived, not yet read
  bool vanished_ = false;
  std::uint64_t epoch_ = 0;  // bumped by Vanish: bytes on the wire before it are lost
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
  std::uint64_t bytes_from_host_ = 0, bytes_to_host_ = 0;
};

}  // namespace hgrasp::drivers
