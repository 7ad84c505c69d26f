#pragma once
// A sysfs attribute takes one value per write, from offset 0. These write it with a single pwrite and no
// allocation, so that the control loop and a signal handler can use them alike.
#include <unistd.h>

#include <charconv>
#include <cstdint>
#include <cstring>

namespace lever::board {

// Async-signal-safe: only pwrite.
inline bool write_text(int fd, const char* text) noexcept {
  const std::size_t length = std::strlen(text);
  char buffer[32];
  if (length + 1 > sizeof buffer) return false;
  std::memcpy(buffer, text, length);
  buffer[length] = '\n';
  return ::pwrite(fd, buffer, length + 1, 0) == static_cast<ssize_t>(length + 1);
}

// Async-signal-safe: std::to_chars touches no locale, no heap and no errno; then one pwrite.
inline bool write_decimal(int fd, std::uint64_t value) noexcept {
  char buffer[24];
  auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer - 1, value);
  if (ec != std::errc{}) return false;
  *end++ = '\n';
  const auto length = static_cast<std::size_t>(end - buffer);
  return ::pwrite(fd, buffer, length, 0) == static_cast<ssize_t>(length);
}

}  // namespace lever::board
