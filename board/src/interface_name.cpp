#include "lever/board/interface_name.hpp"

#include <net/if.h>

#include <cstdio>

namespace lever::board {

static_assert(kMaxInterfaceNameBytes + 1 == IFNAMSIZ);

namespace {

// The kernel's own ctype table (lib/ctype.c) marks these as space; 0xA0 is a byte of many UTF-8 letters.
bool kernel_space(unsigned char c) noexcept { return c == ' ' || (c >= '\t' && c <= '\r') || c == 0xA0; }

std::string shown_byte(unsigned char c) {
  if (c >= 0x21 && c < 0x7F) return std::string("'") + static_cast<char>(c) + "'";
  char buffer[8];
  std::snprintf(buffer, sizeof buffer, "\\x%02X", c);
  return buffer;
}

}  // namespace

std::optional<std::string> interface_name_problem(std::string_view name) {
  if (name.empty()) return "empty (an interface name such as can0)";
  if (name.size() > kMaxInterfaceNameBytes)
    return std::to_string(name.size()) + " bytes, more than the kernel's " + std::to_string(kMaxInterfaceNameBytes);
  if (name == "." || name == "..") return "'.' and '..' are not interface names";
  for (const char ch : name) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\0') return std::string("contains a NUL byte");
    if (c == '/' || c == ':' || kernel_space(c))
      return "contains " + shown_byte(c) + ", which the kernel refuses in an interface name";
    if (c == '%') return std::string("contains '%', which the kernel expands when it names an interface");
  }
  return std::nullopt;
}

}  // namespace lever::board
