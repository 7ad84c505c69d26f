#pragma once
// The serial device path a board's config names (rtu.device), made to point at a simulated device's pty: the
// program under test opens the path it was configured with, unchanged.
#include <string>

#include "lever/board/result.hpp"

namespace lever::hil::devices {

class DeviceSymlink {
 public:
  // Makes `path` a symlink to `target`. An existing symlink is replaced (a HIL that died left it, or another
  // run points it elsewhere); anything else at `path` is refused, since it may be a real device or a file
  // somebody needs. The replacement is a rename, so a client reconnecting meanwhile never finds the path gone.
  static board::Result<DeviceSymlink> create(const std::string& path, const std::string& target);

  DeviceSymlink(DeviceSymlink&& other) noexcept;
  DeviceSymlink& operator=(DeviceSymlink&& other) noexcept;
  DeviceSymlink(const DeviceSymlink&) = delete;
  DeviceSymlink& operator=(const DeviceSymlink&) = delete;
  // Removes the link, but only while it still points at our target: a later server may have taken the path.
  ~DeviceSymlink();

 private:
  DeviceSymlink(std::string path, std::string target) noexcept;
  void remove() noexcept;
  std::string path_;
  std::string target_;
};

}  // namespace lever::hil::devices
