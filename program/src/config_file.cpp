#include "lever/program/config_file.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "lever/program/text.hpp"

namespace lever::program {

const char* file_kind(unsigned mode) noexcept {
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISLNK(mode)) return "a symbolic link";
  if (S_ISCHR(mode) || S_ISBLK(mode)) return "a device";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISSOCK(mode)) return "a socket";
  return "a special file";
}

ConfigText read_config_file(const std::string& path, std::size_t max_bytes) {
  ConfigText out;
  const std::string shown = printable(path, 400);
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    out.error = fmt::format("{}: cannot read: {}", shown, std::strerror(errno));
    return out;
  }
  struct Closer {
    int fd;
    ~Closer() { ::close(fd); }
  } closer{fd};
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    out.error = fmt::format("{}: cannot read: {}", shown, std::strerror(errno));
    return out;
  }
  if (!S_ISREG(st.st_mode)) {
    out.error = fmt::format("{}: {}, not a configuration file", shown, file_kind(st.st_mode));
    return out;
  }
  if (static_cast<unsigned long long>(st.st_size) > max_bytes) {
    out.error = fmt::format("{}: {} bytes; a configuration file is at most {}", shown,
                            static_cast<long long>(st.st_size), max_bytes);
    return out;
  }
  // One byte more than allowed: a file that grew after fstat is refused too, not cut.
  out.text.resize(max_bytes + 1);
  std::size_t length = 0;
  while (length < out.text.size()) {
    const ssize_t got = ::read(fd, out.text.data() + length, out.text.size() - length);
    if (got == 0) break;
    if (got < 0) {
      if (errno == EINTR) continue;
      out.error = fmt::format("{}: cannot read: {}", shown, std::strerror(errno));
      out.text.clear();
      return out;
    }
    length += static_cast<std::size_t>(got);
  }
  if (length > max_bytes) {
    out.error = fmt::format("{}: more than {} bytes; a configuration file is at most that", shown, max_bytes);
    out.text.clear();
    return out;
  }
  out.text.resize(length);
  return out;
}

}  // namespace lever::program
