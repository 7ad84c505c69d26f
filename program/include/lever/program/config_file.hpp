#pragma once
// A configuration file read whole, safely whatever the path names: only a regular file of bounded size is read.
// A directory reads as an empty file to toml++ (a wrong path would pass for an empty configuration), a FIFO
// blocks the reader until some writer comes, a device never ends; each is refused with one line naming it.
#include <cstddef>
#include <string>

namespace lever::program {

inline constexpr std::size_t kMaxConfigBytes = std::size_t{1} << 20;  // a configuration is a page of text

struct ConfigText {
  std::string text;
  std::string error;  // "PATH: a FIFO, not a configuration file"; empty on success
};

// Opened non-blocking (a FIFO swapped in after a check cannot block the open either), then judged by fstat on
// the open file, so what is read is what was checked.
ConfigText read_config_file(const std::string& path, std::size_t max_bytes = kMaxConfigBytes);

// "a directory", "a FIFO", "a device", ... for a stat mode that is not a regular file.
const char* file_kind(unsigned mode) noexcept;

}  // namespace lever::program
