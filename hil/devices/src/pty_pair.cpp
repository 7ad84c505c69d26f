#include "pty_pair.hpp"

#include <fcntl.h>
#include <termios.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>

namespace lever::hil::devices {

namespace {

board::Error os_error(const std::string& what) {
  const int err = errno;
  return board::Error{"pty: " + what + ": " + std::strerror(err), err};
}

// No echo, no line editing, no CR/LF translation: the bytes of a frame pass as they are.
bool make_raw(int fd) {
  termios settings{};
  if (::tcgetattr(fd, &settings) != 0) return false;
  ::cfmakeraw(&settings);
  return ::tcsetattr(fd, TCSANOW, &settings) == 0;
}

}  // namespace

board::Result<PtyPair> PtyPair::open() {
  PtyPair pair;
  pair.master_.reset(::posix_openpt(O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!pair.master_) return os_error("posix_openpt");
  if (::grantpt(pair.master_.get()) != 0) return os_error("grantpt");
  if (::unlockpt(pair.master_.get()) != 0) return os_error("unlockpt");
  char name[128];
  if (::ptsname_r(pair.master_.get(), name, sizeof name) != 0) return os_error("ptsname");
  pair.slave_path_ = name;
  pair.slave_held_open_.reset(::open(name, O_RDWR | O_NOCTTY | O_CLOEXEC));
  if (!pair.slave_held_open_) return os_error("open " + pair.slave_path_);
  if (!make_raw(pair.slave_held_open_.get())) return os_error("raw mode on " + pair.slave_path_);
  if (!make_raw(pair.master_.get())) return os_error("raw mode on the master");
  return pair;
}

}  // namespace lever::hil::devices
