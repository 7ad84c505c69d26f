#pragma once
// The error a backend's open() returns for a config its validate() refused: every problem in one line,
// "WHAT: problem; problem", EINVAL.
#include <string>
#include <string_view>
#include <vector>

#include "lever/board/result.hpp"

namespace lever::board {

Error config_error(std::string_view what, const std::vector<std::string>& problems);

}  // namespace lever::board
