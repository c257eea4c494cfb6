#pragma once
/// @file The device end of one of the twin's serial lines: a pty (with a stable link) whose
/// bytes go to and come from a byte-exact emulator at the line's baud rate, optionally through
/// the faults of a noisy line (drivers/serial/faulty_link.h), and that can be cut or made to
/// vanish. Unlike drivers::EmulatorHost it has no thread and no clock of its own: the twin
/// polls it with the twin's time.

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "emulators/emulator.h"
#include "serial/faulty_link.h"
#include "serial/pty.h"

namespace hgrasp::sim {

class SerialLine {
 public:
  /// `key`: the device (arm_left, ..., laser_board). `link_path`: the pty's stable symlink.
  /// `baud`: 8N1 bytes take 10 / baud s each, both ways. `faults`: none when nullopt.
  SerialLine(std::string key, std::unique_ptr<drivers::DeviceEmulator> device,
             std::string link_path, int baud, std::optional<drivers::FaultPlan> faults);

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
  std::string port() const { return pty_.port(); }
  int fd() const { return pty_.master_fd(); }
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
  std::unique_ptr<drivers::DeviceEmulator> device_;
  drivers::Pty pty_;
  int baud_;
  double byte_s_;
  std::optional<drivers::LineFaults> faults_;
  bool cut_ = false, cut_from_device_ = false;
  std::deque<std::pair<double, std::uint8_t>> rx_, tx_;  ///< (due time, byte)
  double rx_free_s_ = 0.0, tx_free_s_ = 0.0;            ///< when the wire is next free
  std::uint64_t bytes_from_host_ = 0, bytes_to_host_ = 0, bytes_unsent_ = 0;
};

}  // namespace hgrasp::sim
