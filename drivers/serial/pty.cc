#include "serial/pty.h"

#include <fcntl.h>
#include <pty.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace hgrasp::drivers {

Pty::Pty(std::string link_path) : link_path_(std::move(link_path)) { Reopen(); }

Pty::~Pty() { Close(); }

void Pty::Reopen() {
  Close();
  termios tio{};
  ::cfmakeraw(&tio);
  char name[256] = {0};
  if (::openpty(&master_, &slave_, name, &tio, nullptr) != 0) {
    throw std::runtime_error(std::string("openpty: ") + std::strerror(errno));
  }
  slave_path_ = name;
  ::fcntl(master_, F_SETFL, ::fcntl(master_, F_GETFL) | O_NONBLOCK);
  ::fcntl(master_, F_SETFD, FD_CLOEXEC);
  ::fcntl(slave_, F_SETFD, FD_CLOEXEC);
  if (!link_path_.empty()) {
    const std::string tmp = link_path_ + ".new";
    ::unlink(tmp.c_str());
    if (::symlink(slave_path_.c_str(), tmp.c_str()) != 0 ||
        ::rename(tmp.c_str(), link_path_.c_str()) != 0) {
      const std::string why = std::strerror(errno);
      Close();
      throw std::runtime_error("pty link " + link_path_ + ": " + why);
    }
  }
}

void Pty::Close() {
  if (!link_path_.empty() && master_ >= 0) ::unlink(link_path_.c_str());
  // The emulator's own slave descriptor goes first, so that when the master closes the kernel
  // hangs up every other opener of the slave (the driver reads EIO / POLLHUP).
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
  slave_ = master_ = -1;
}

}  // namespace hgrasp::drivers
