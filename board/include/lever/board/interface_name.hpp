#pragma once
// A network interface's name as the kernel takes it (net/core/dev.c, dev_valid_name()), checked before any
// socket is opened, so a name no interface can have is refused as bad input, not reported as "no such device".
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace lever::board {

inline constexpr std::size_t kMaxInterfaceNameBytes = 15;  // IFNAMSIZ less its terminator

// Empty when the kernel could have an interface of this name: 1 to 15 bytes, not "." or "..", no '/', ':'
// or white space (the kernel's isspace: space, \t \n \v \f \r and the byte 0xA0), no NUL; and no '%', which
// the kernel expands as a pattern when it names an interface, so no interface has one. Any other byte is
// allowed, as the kernel allows it. Otherwise the problem, naming the offending character.
std::optional<std::string> interface_name_problem(std::string_view name);

}  // namespace lever::board
