#pragma once
/// @file A POSIX serial port (termios): raw mode, configurable baud and framing, read timeouts,
/// and reconnection when the port vanishes (a USB adapter unplugged, an emulator restarted) and
/// comes back under the same path.
///
/// Why termios and not Boost.Asio or LibSerial: the drivers need one blocking read with a
/// timeout and one write, on one thread per device; poll(2) + read(2) give exactly that in a
/// page of code, with no dependency and with full control over what happens when the port
/// disappears (EIO / POLLHUP), which is the part the fault handling depends on.

#include <chrono>
#include <memory>
#include <string>

#include "serial/byte_link.h"

namespace hgrasp::drivers {

enum class Parity { kNone, kEven, kOdd };

/// How to open a port. The defaults are the robot's most common framing, 9600 8N1.
struct SerialConfig {
  std::string port;   ///< device path, e.g. /dev/ttyUSB0 or an emulator's pty link
  int baud = 9600;    ///< one of StandardBauds()
  int data_bits = 8;  ///< 5-8
  Parity parity = Parity::kNone;
  int stop_bits = 1;  ///< 1 or 2
};

/// The baud rates termios supports (50 ... 4000000).
bool IsStandardBaud(int baud);

/// "9600 8N1".
std::string Describe(const SerialConfig& config);

class SerialPort final : public ByteLink {
 public:
  /// Opens and configures the port. Returns nullptr and sets *error (the path and the system's
  /// reason) when it cannot be opened or configured.
  static std::unique_ptr<SerialPort> Open(const SerialConfig& config, std::string* error);
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  device::Status Write(std::span<const std::uint8_t> bytes) override;
  device::Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) override;
  void Discard() override;

  /// Whether the port is open now (false between a hang-up and a successful reopen).
  bool connected() const { return fd_ >= 0; }
  const SerialConfig& config() const { return config_; }
  /// How many times the port was reopened after vanishing.
  int reconnects() const { return reconnects_; }

 private:
  explicit SerialPort(SerialConfig config) : config_(std::move(config)) {}
  bool OpenFd(std::string* error);
  void Hangup();
  /// Reopens a vanished port, at most every kReopenInterval; true when open.
  bool EnsureOpen();

  static constexpr std::chrono::milliseconds kReopenInterval{20};
  SerialConfig config_;
  int fd_ = -1;
  int reconnects_ = 0;
  std::chrono::steady_clock::time_point last_attempt_{};
};

}  // namespace hgrasp::drivers
