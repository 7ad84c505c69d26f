#pragma once
// User text echoed into a one-line message: never a control byte, never a whole file of it.
#include <string>
#include <string_view>

namespace lever::program {

inline constexpr std::size_t kEchoLimit = 60;

// Control bytes (and DEL) as \xNN; cut after `limit` bytes with "..." so a 100 kB field stays one short line.
std::string printable(std::string_view text, std::size_t limit = kEchoLimit);

}  // namespace lever::program
