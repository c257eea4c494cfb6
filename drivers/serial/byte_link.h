#pragma once
/// @file A byte stream to a device: a serial port (SerialPort), or a decorator over one
/// (FaultyLink). Drivers speak their protocols over this interface only.

#include <cstddef>
#include <cstdint>
#include <span>

#include "device/status.h"

namespace hgrasp::drivers {

class ByteLink {
 public:
  virtual ~ByteLink() = default;

  /// Sends every byte (blocking until the kernel has taken them). kDisconnected when the port is
  /// gone; the link tries to reopen it on later calls.
  virtual device::Status Write(std::span<const std::uint8_t> bytes) = 0;

  /// Reads what has arrived, up to buf.size() bytes, waiting at most `timeout_s` for the first
  /// byte; *n is the number read. kTimeout when nothing arrived in time, kDisconnected when the
  /// port is gone.
  virtual device::Status Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) = 0;

  /// Throws away bytes received and not yet read (before a resynchronisation).
  virtual void Discard() = 0;
};

/// Writes a string's bytes (text protocols).
device::Status WriteText(ByteLink& link, std::string_view text);

}  // namespace hgrasp::drivers
