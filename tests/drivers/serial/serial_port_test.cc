#include "serial/serial_port.h"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <termios.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include "serial/pty.h"

namespace hgrasp::drivers {
namespace {

using device::Status;

TEST(SerialPort, RejectsBadSettingsAndMissingPorts) {
  std::string error;
  EXPECT_FALSE(SerialPort::Open({"/dev/null", 9601}, &error));
  EXPECT_NE(error.find("9601"), std::string::npos) << error;
  EXPECT_FALSE(SerialPort::Open({"/nonexistent/ttyS9", 9600}, &error));
  EXPECT_NE(error.find("/nonexistent/ttyS9"), std::string::npos) << error;
  EXPECT_NE(error.find("No such file"), std::string::npos) << error;
  EXPECT_FALSE(SerialPort::Open({"/dev/null", 9600}, &error));  // not a tty
  EXPECT_NE(error.find("not a serial port"), std::string::npos) << error;
  EXPECT_FALSE(SerialPort::Open({"/dev/null", 9600, 9}, &error));
  EXPECT_TRUE(IsStandardBaud(19200));
  EXPECT_FALSE(IsStandardBaud(12345));
  EXPECT_EQ(Describe({"x", 19200, 7, Parity::kEven, 2}), "19200 7E2");
}

TEST(SerialPort, ConfiguresRawFramingAndTimesOut) {
  Pty pty;
  std::string error;
  auto port = SerialPort::Open({pty.port(), 19200, 7, Parity::kEven, 2}, &error);
  ASSERT_TRUE(port) << error;
  // The slave's termios carries what was asked.
  termios tio{};
  const int fd = ::open(pty.slave_path().c_str(), O_RDWR | O_NOCTTY);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::tcgetattr(fd, &tio), 0);
  ::close(fd);
  EXPECT_EQ(::cfgetospeed(&tio), B19200);
  // Linux's pty keeps CS8 and no parity whatever is asked (there are no wires to frame), but
  // it keeps the rest.
  EXPECT_TRUE(tio.c_cflag & CSTOPB);
  EXPECT_TRUE(tio.c_cflag & CLOCAL);
  EXPECT_FALSE(tio.c_lflag & (ICANON | ECHO));

  std::uint8_t buf[16];
  std::size_t n = 7;
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_EQ(port->Read(buf, 0.1, &n), Status::kTimeout);
  const double waited =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  EXPECT_EQ(n, 0u);
  // The whole timeout waited (load cannot shorten a wait); how much longer is the machine's
  // load (label realtime): 10 timeouts is a hang guard, not a latency bound.
  EXPECT_GE(waited, 0.095);
  EXPECT_LT(waited, 1.0);

  // Bytes both ways, binary-clean (no CR/LF translation, no flow-control characters eaten).
  const std::uint8_t out[] = {0x00, 0x0D, 0x0A, 0x11, 0x13, 0x03, 0xFF};
  ASSERT_EQ(port->Write(out), Status::kOk);
  std::uint8_t got[16];
  std::size_t total = 0;
  while (total < sizeof(out)) {
    const ssize_t k = ::read(pty.master_fd(), got + total, sizeof(got) - total);
    if (k > 0) total += static_cast<std::size_t>(k);
  }
  EXPECT_EQ(std::vector<std::uint8_t>(got, got + total),
            std::vector<std::uint8_t>(out, out + sizeof(out)));
  ASSERT_EQ(::write(pty.master_fd(), out, sizeof(out)), static_cast<ssize_t>(sizeof(out)));
  total = 0;
  while (total < sizeof(out)) {
    ASSERT_EQ(port->Read(std::span<std::uint8_t>(buf + total, sizeof(buf) - total), 1.0, &n),
              Status::kOk);
    total += n;
  }
  EXPECT_EQ(std::vector<std::uint8_t>(buf, buf + total),
            std::vector<std::uint8_t>(out, out + sizeof(out)));

  // Discard drops what has arrived.
  ASSERT_EQ(::write(pty.master_fd(), out, sizeof(out)), static_cast<ssize_t>(sizeof(out)));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  port->Discard();
  EXPECT_EQ(port->Read(buf, 0.05, &n), Status::kTimeout);
}

}  // namespace
}  // namespace hgrasp::drivers
