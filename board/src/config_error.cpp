#include "lever/board/config_error.hpp"

#include <cerrno>

namespace lever::board {

Error config_error(std::string_view what, const std::vector<std::string>& problems) {
  std::string message(what);
  message += ':';
  for (std::size_t i = 0; i < problems.size(); ++i) message += (i == 0 ? " " : "; ") + problems[i];
  return Error{message, EINVAL};
}

}  // namespace lever::board
