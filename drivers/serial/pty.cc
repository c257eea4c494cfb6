#include "serial/pty.h"

#include <fcntl.h>
#include <pty.h>
#include <sys/stat.h>
#include <termios.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

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
    std::string why;
    if (!ReplaceableLink(link_path_, &why)) {
      Close();
      throw std::runtime_error("pty link " + link_path_ + ": " + why);
    }
    // A fresh link beside it under a name nobody has (symlink never replaces anything), renamed
    // over the old link in one step.
    std::string tmp;
    for (int i = 0;; ++i) {
      tmp = link_path_ + ".hgrasp-" + std::to_string(::getpid()) + "-" + std::to_string(i);
      if (::symlink(slave_path_.c_str(), tmp.c_str()) == 0) break;
      if (errno != EEXIST || i == 100) {
        why = std::strerror(errno);
        Close();
        throw std::runtime_error("pty link " + link_path_ + ": " + why);
      }
    }
    if (::rename(tmp.c_str(), link_path_.c_str()) != 0) {
      why = std::strerror(errno);
      ::unlink(tmp.c_str());
      Close();
      throw std::runtime_error("pty link " + link_path_ + ": " + why);
    }
  }
}

bool Pty::ReplaceableLink(const std::string& path, std::string* why) {
  struct stat st{};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return true;  // nothing there
    *why = std::strerror(errno);
    return false;
  }
  if (!S_ISLNK(st.st_mode)) {
    *why = S_ISDIR(st.st_mode) ? "a folder is there (only a pty's link is ever replaced)"
                               : "a file is there (only a pty's link is ever replaced)";
    return false;
  }
  char target[4096];
  const ssize_t n = ::readlink(path.c_str(), target, sizeof target - 1);
  if (n < 0) {
    *why = std::strerror(errno);
    return false;
  }
  const std::string to(target, static_cast<std::size_t>(n));
  if (to.rfind("/dev/pts/", 0) != 0) {
    *why = "a link to " + to + " is there, not to a pseudo-terminal (only a pty's link is ever "
           "replaced)";
    return false;
  }
  return true;
}

void Pty::Close() {
  // The link goes only while it is still this pty's: never a file or link someone put there.
  if (!link_path_.empty() && master_ >= 0) {
    char target[4096];
    const ssize_t n = ::readlink(link_path_.c_str(), target, sizeof target - 1);
    if (n > 0 && std::string(target, static_cast<std::size_t>(n)) == slave_path_) {
      ::unlink(link_path_.c_str());
    }
  }
  // The emulator's own slave descriptor goes first, so that when the master closes the kernel
  // hangs up every other opener of the slave (the driver reads EIO / POLLHUP).
  if (slave_ >= 0) ::close(slave_);
  if (master_ >= 0) ::close(master_);
  slave_ = master_ = -1;
}

}  // namespace hgrasp::drivers
