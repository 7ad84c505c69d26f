#include "lever/app/motor_state.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "lever/platform/unique_fd.hpp"

namespace lever::app {

std::string write_motor_state(const std::string& path, const FwConfig& config) {
  const std::string text = "# lever-fw: the motor this lever opened, for lever-fw --motor-off (docs/board-motor.md)\n" +
                           motor_keys_toml(config);
  const std::string temporary = path + ".new";
  const auto failed = [&](const char* what) {
    const std::string why = std::strerror(errno);
    ::unlink(temporary.c_str());
    return std::string("cannot ") + what + " " + path + ": " + why;
  };
  {
    platform::UniqueFd fd(::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NOFOLLOW, 0644));
    if (!fd) return failed("write");
    std::size_t written = 0;
    while (written < text.size()) {
      const ssize_t n = ::write(fd.get(), text.data() + written, text.size() - written);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) return failed("write");
      written += static_cast<std::size_t>(n);
    }
    if (::fsync(fd.get()) != 0) return failed("write");
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) return failed("write");
  return {};
}

}  // namespace lever::app
