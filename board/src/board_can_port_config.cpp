#include "lever/board/board_can_port_config.hpp"

#include "lever/board/interface_name.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::board {

std::vector<std::string> BoardCanPortConfig::validate() const {
  std::vector<std::string> problems;
  if (const auto problem = interface_name_problem(interface))
    problems.emplace_back("interface: \"" + interface + "\": " + *problem);
  if (pair >= protocol::kPairCount) {
    problems.emplace_back("pair: " + std::to_string(pair) + " is not a lever pair (0.." +
                          std::to_string(protocol::kPairCount - 1) + ")");
  }
  if (link_retry_ms == 0) problems.emplace_back("link_retry_ms: 0 (the port would ask the kernel on every call)");
  if (link_retry_max_ms < link_retry_ms) {
    problems.emplace_back("link_retry_max_ms: " + std::to_string(link_retry_max_ms) + " is below link_retry_ms (" +
                          std::to_string(link_retry_ms) + ")");
  }
  return problems;
}

}  // namespace lever::board
