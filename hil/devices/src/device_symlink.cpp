#include "device_symlink.hpp"

#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace lever::hil::devices {

namespace {

board::Error os_error(const std::string& what) {
  const int err = errno;
  return board::Error{what + ": " + std::strerror(err), err};
}

}  // namespace

board::Result<DeviceSymlink> DeviceSymlink::create(const std::string& path, const std::string& target) {
  struct stat found {};
  if (::lstat(path.c_str(), &found) == 0) {
    if (!S_ISLNK(found.st_mode)) {
      return board::Error{"gauge server: rtu.device " + path +
                              " exists and is not a symlink; refusing to replace it (remove it, or configure "
                              "another path)",
                          EEXIST};
    }
  } else if (errno != ENOENT) {
    return os_error("gauge server: rtu.device " + path);
  }
  const std::string temporary = path + ".hil-" + std::to_string(::getpid());
  ::unlink(temporary.c_str());  // left by a run of the same pid that died here; it is ours either way
  if (::symlink(target.c_str(), temporary.c_str()) != 0) {
    return os_error("gauge server: cannot create the symlink " + temporary + " -> " + target);
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    board::Error error = os_error("gauge server: cannot move the symlink to rtu.device " + path);
    ::unlink(temporary.c_str());
    return error;
  }
  return DeviceSymlink(path, target);
}

DeviceSymlink::DeviceSymlink(std::string path, std::string target) noexcept
    : path_(std::move(path)), target_(std::move(target)) {}

DeviceSymlink::DeviceSymlink(DeviceSymlink&& other) noexcept
    : path_(std::exchange(other.path_, {})), target_(std::exchange(other.target_, {})) {}

DeviceSymlink& DeviceSymlink::operator=(DeviceSymlink&& other) noexcept {
  if (this != &other) {
    remove();
    path_ = std::exchange(other.path_, {});
    target_ = std::exchange(other.target_, {});
  }
  return *this;
}

DeviceSymlink::~DeviceSymlink() { remove(); }

void DeviceSymlink::remove() noexcept {
  if (path_.empty()) return;
  char buffer[4096];
  const ssize_t length = ::readlink(path_.c_str(), buffer, sizeof buffer);
  if (length >= 0 && std::string(buffer, static_cast<std::size_t>(length)) == target_) ::unlink(path_.c_str());
  path_.clear();
}

}  // namespace lever::hil::devices
