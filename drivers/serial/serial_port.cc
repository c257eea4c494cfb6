#include "serial/serial_port.h"

#include <fcntl.h>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <utility>

namespace hgrasp::drivers {
namespace {

using device::Status;

struct BaudEntry {
  int baud;
  speed_t code;
};

constexpr BaudEntry kBauds[] = {
    {50, B50},           {75, B75},           {110, B110},         {134, B134},
    {150, B150},         {200, B200},         {300, B300},         {600, B600},
    {1200, B1200},       {1800, B1800},       {2400, B2400},       {4800, B4800},
    {9600, B9600},       {19200, B19200},     {38400, B38400},     {57600, B57600},
    {115200, B115200},   {230400, B230400},   {460800, B460800},   {500000, B500000},
    {576000, B576000},   {921600, B921600},   {1000000, B1000000}, {1152000, B1152000},
    {1500000, B1500000}, {2000000, B2000000}, {2500000, B2500000}, {3000000, B3000000},
    {3500000, B3500000}, {4000000, B4000000}};

bool BaudCode(int baud, speed_t* code) {
  for (const BaudEntry& e : kBauds) {
    if (e.baud == baud) {
      *code = e.code;
      return true;
    }
  }
  return false;
}

}  // namespace

bool IsStandardBaud(int baud) {
  speed_t code;
  return BaudCode(baud, &code);
}

std::string Describe(const SerialConfig& c) {
  const char parity = c.parity == Parity::kNone ? 'N' : c.parity == Parity::kEven ? 'E' : 'O';
  return std::to_string(c.baud) + " " + std::to_string(c.data_bits) + parity +
         std::to_string(c.stop_bits);
}

std::unique_ptr<SerialPort> SerialPort::Open(const SerialConfig& config, std::string* error) {
  std::string ignored;
  if (error == nullptr) error = &ignored;
  speed_t code;
  if (!BaudCode(config.baud, &code)) {
    *error = config.port + ": baud " + std::to_string(config.baud) + " is not a standard rate";
    return nullptr;
  }
  if (config.data_bits < 5 || config.data_bits > 8 || config.stop_bits < 1 ||
      config.stop_bits > 2) {
    *error = config.port + ": framing " + Describe(config) + " is not possible";
    return nullptr;
  }
  std::unique_ptr<SerialPort> port(new SerialPort(config));
  if (!port->OpenFd(error)) return nullptr;
  return port;
}

SerialPort::~SerialPort() { Hangup(); }

bool SerialPort::OpenFd(std::string* error) {
  const int fd = ::open(config_.port.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *error = config_.port + ": " + std::strerror(errno);
    return false;
  }
  termios tio{};
  if (::tcgetattr(fd, &tio) != 0) {
    *error = config_.port + ": not a serial port (" + std::strerror(errno) + ")";
    ::close(fd);
    return false;
  }
  ::cfmakeraw(&tio);
  speed_t code = B9600;
  BaudCode(config_.baud, &code);
  ::cfsetispeed(&tio, code);
  ::cfsetospeed(&tio, code);
  tio.c_cflag &= ~(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
  static constexpr tcflag_t kSize[] = {CS5, CS6, CS7, CS8};
  tio.c_cflag |= kSize[config_.data_bits - 5] | CLOCAL | CREAD;
  if (config_.parity != Parity::kNone) tio.c_cflag |= PARENB;
  if (config_.parity == Parity::kOdd) tio.c_cflag |= PARODD;
  if (config_.stop_bits == 2) tio.c_cflag |= CSTOPB;
  tio.c_iflag &= ~(IXON | IXOFF | IXANY);
  tio.c_cc[VMIN] = 0;
  tio.c_cc[VTIME] = 0;
  if (::tcsetattr(fd, TCSANOW, &tio) != 0) {
    *error = config_.port + ": cannot set " + Describe(config_) + " (" + std::strerror(errno) + ")";
    ::close(fd);
    return false;
  }
  ::tcflush(fd, TCIOFLUSH);
  fd_ = fd;
  return true;
}

void SerialPort::Hangup() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool SerialPort::EnsureOpen() {
  if (fd_ >= 0) return true;
  const auto now = std::chrono::steady_clock::now();
  if (now - last_attempt_ < kReopenInterval) return false;
  last_attempt_ = now;
  std::string error;
  if (!OpenFd(&error)) return false;
  ++reconnects_;
  return true;
}

device::Status SerialPort::Write(std::span<const std::uint8_t> bytes) {
  if (!EnsureOpen()) return Status::kDisconnected;
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n > 0) {
      done += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK)) {
      pollfd p{fd_, POLLOUT, 0};
      if (::poll(&p, 1, 1000) <= 0 || (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0) {
        Hangup();
        return Status::kDisconnected;
      }
      continue;
    }
    Hangup();
    return Status::kDisconnected;
  }
  return Status::kOk;
}

device::Status SerialPort::Read(std::span<std::uint8_t> buf, double timeout_s, std::size_t* n) {
  *n = 0;
  if (!EnsureOpen()) {
    // The port is gone: wait out the timeout in small steps, in case it comes back.
    const auto deadline =
        std::chrono::steady_clock::now() + std::chrono::duration<double>(std::max(timeout_s, 0.0));
    while (std::chrono::steady_clock::now() < deadline) {
      ::usleep(static_cast<useconds_t>(kReopenInterval.count() * 1000));
      if (EnsureOpen()) break;
    }
    if (fd_ < 0) return Status::kDisconnected;
  }
  const auto deadline =
      std::chrono::steady_clock::now() + std::chrono::duration<double>(std::max(timeout_s, 0.0));
  for (;;) {
    const double left =
        std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, std::max(0, static_cast<int>(std::ceil(left * 1000.0))));
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) {
      Hangup();
      return Status::kDisconnected;
    }
    if (r == 0) return Status::kTimeout;
    if ((p.revents & POLLIN) != 0) {
      const ssize_t got = ::read(fd_, buf.data(), buf.size());
      if (got > 0) {
        *n = static_cast<std::size_t>(got);
        return Status::kOk;
      }
      if (got < 0 && (errno == EAGAIN || errno == EINTR)) continue;
    }
    // End of file, a read error (EIO on a hung-up pty or an unplugged adapter), or POLLHUP /
    // POLLERR without data: the port is gone.
    Hangup();
    return Status::kDisconnected;
  }
}

void SerialPort::Discard() {
  if (fd_ >= 0) ::tcflush(fd_, TCIFLUSH);
}

}  // namespace hgrasp::drivers
