#pragma once
/// @file The device end of a pseudo-terminal pair (openpty), for emulators and tests: the
/// emulator reads and writes the master; a driver opens the slave as its serial port. An
/// optional symlink gives the port a stable path that survives Reopen(), as udev's
/// /dev/serial/by-id/ links do for a re-plugged adapter.

#include <string>

namespace hgrasp::drivers {

class Pty {
 public:
  /// Opens a pair in raw mode. With a non-empty `link_path`, (re)creates that symlink to the
  /// slave. Throws std::runtime_error when the system refuses.
  explicit Pty(std::string link_path = "");
  ~Pty();
  Pty(const Pty&) = delete;
  Pty& operator=(const Pty&) = delete;

  /// The master side (the device's wires), or -1 while closed.
  int master_fd() const { return master_; }
  /// The path a driver opens: the link when there is one, else the slave (/dev/pts/N).
  const std::string& port() const { return link_path_.empty() ? slave_path_ : link_path_; }
  const std::string& slave_path() const { return slave_path_; }

  /// The port vanishes: both sides close (a reader of the slave gets EIO / POLLHUP) and the link
  /// is removed.
  void Close();
  /// A new pair, the link pointed at its slave (the port comes back under the same link path).
  void Reopen();
  bool open() const { return master_ >= 0; }

  /// Whether a pty's link may be put at `path`: nothing is there, or a symlink to a
  /// pseudo-terminal (/dev/pts/N: a link an emulator made). A file, a folder or any other link
  /// is never replaced; `why` says what is there.
  static bool ReplaceableLink(const std::string& path, std::string* why);

 private:
  std::string link_path_, slave_path_;
  int master_ = -1, slave_ = -1;
};

}  // namespace hgrasp::drivers
