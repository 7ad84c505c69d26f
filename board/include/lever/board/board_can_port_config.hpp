#pragma once
// Which CAN interface and lever pair the board's CAN port (board_can_port.hpp) serves, and how it retries a
// link that went down or away.
#include <cstdint>
#include <string>
#include <vector>

namespace lever::board {

struct BoardCanPortConfig {
  std::string interface = "can0";
  std::uint8_t pair = 0;  // the lever pair (0..15) whose frames the port receives
  // While the interface is down or gone, receive() asks the kernel about it again after link_retry_ms,
  // doubling up to link_retry_max_ms, and back to link_retry_ms once it is up.
  std::uint32_t link_retry_ms = 50;
  std::uint32_t link_retry_max_ms = 1000;

  // Every problem, each naming its field ("pair: ..."); empty when the config can be opened.
  std::vector<std::string> validate() const;
};

}  // namespace lever::board
