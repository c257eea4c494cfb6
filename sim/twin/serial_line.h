#pragma once
/// @file The device end of one of the twin's serial lines: a pty (with a stable link) whose
/// bytes go to and come from a byte-exact emulator at the line's baud rate, optionally through
/// the faults of a noisy line (drivers/serial/faulty_link.h), and that can be cut or made to
/// vanish. Unlike drivers::EmulatorHost it has no thread and no clock of its own: the twin
/// polls it with the twin's time. In lockstep (the twin on a SimClock) there is no pty: the host
/// end is a ByteLink in the same process (HostLink), whose reads wait in simulated time while
/// the twin's ticks carry the bytes.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/clock.h"
#include "emulators/emulator.h"
#include "serial/byte_link.h"
#include "serial/faulty_link.h"
#include "serial/pty.h"

namespace hgrasp::sim {

class SerialLine {
 public:
  /// `key`: the device (arm_left, ..., laser_board). `link_path`: the pty's stable symlink.
  /// `baud`: 8N1 bytes take 10 / baud s each, both ways. `faults`: none when nullopt.
  SerialLine(std::string key, std::unique_ptr<drivers::DeviceEmulator> device,
             std::string link_path, int baud, std::optional<drivers::FaultPlan> faults);
  /// In process (lockstep): no pty; the host talks through HostLink. The faults' dropouts
  /// follow `clock` (the lockstep twin's; it must outlive the line).
  SerialLine(std::string key, std::unique_ptr<drivers::DeviceEmulator> device, int baud,
             std::optional<drivers::FaultPlan> faults, const Clock& clock);
  ~SerialLine();

  /// In process only: the host's end of the wires, a ByteLink whose Read waits on `clock` (the
  /// twin's ticks, events of the same clock, deliver the bytes; bytes written are taken at the
  /// next tick). Each call gives a new link to the same wires; the links must go before the
  /// line does. A vanished line's links answer kDisconnected until it reappears.
  std::unique_ptr<drivers::ByteLink> HostLink(SimClock& clock);
  bool in_process() const { return pty_ == nullptr; }

  /// At twin time t_s: takes what the host wrote (each byte arriving one byte time after the
  /// one before it, and no earlier than it was written), hands the bytes that have arrived to
  /// the emulator, advances it, and sends what it answered as fast as the baud rate lets.
  void Poll(double t_s);
  /// The earliest twin time something is due (a byte to hand over or to send); +inf if none.
  double NextDue() const;

  /// Both wires cut (nothing passes either way), or mended.
  void Cut(bool cut);
  /// The device's transmit wire cut (the host hears nothing; the device still hears the host).
  void CutFromDevice(bool cut);
  /// The port vanishes (the pty closes: a driver reading it gets EIO) / comes back.
  void Vanish();
  void Reappear();

  const std::string& key() const { return key_; }
  /// The pty's path; "" in process.
  std::string port() const { return pty_ ? pty_->port() : std::string(); }
  /// The pty's master; -1 in process or while vanished.
  int fd() const { return pty_ ? pty_->master_fd() : -1; }
  int baud() const { return baud_; }
  drivers::DeviceEmulator& device() { return *device_; }
  const drivers::DeviceEmulator& device() const { return *device_; }
  /// Fault counts (zeros without faults).
  drivers::FaultCounts fault_counts() const;
  std::uint64_t bytes_from_host() const { return bytes_from_host_; }
  std::uint64_t bytes_to_host() const { return bytes_to_host_; }
  /// Bytes the pty could not take (nobody reading the port).
  std::uint64_t bytes_unsent() const { return bytes_unsent_; }

 private:
  std::string key_;
  class InProcessLink;
  std::unique_ptr<drivers::DeviceEmulator> device_;
  std::unique_ptr<drivers::Pty> pty_;  ///< null in process
  // In process: what the host wrote (taken at the next Poll), what reached the host (read by
  // HostLink), and whether the port has vanished.
  std::deque<std::uint8_t> host_in_, host_out_;
  bool vanished_ = false;
  int baud_;
  double byte_s_;
  std::optional<drivers::LineFaults> faults_;
  bool cut_ = false, cut_from_device_ = false;
  std::deque<std::pair<double, std::uint8_t>> rx_, tx_;  ///< (due time, byte)
  double rx_free_s_ = 0.0, tx_free_s_ = 0.0;             ///< when the wire is next free
  std::uint64_t bytes_from_host_ = 0, bytes_to_host_ = 0, bytes_unsent_ = 0;
};

}  // namespace hgrasp::sim
