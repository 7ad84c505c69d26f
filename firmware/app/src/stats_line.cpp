#include "lever/app/stats_line.hpp"

namespace lever::app {

std::string state_name(protocol::LeverState s) {
  switch (s) {
    case protocol::LeverState::init:
      return "init";
    case protocol::LeverState::disarmed:
      return "disarmed";
    case protocol::LeverState::armed:
      return "armed";
    case protocol::LeverState::fault:
      return "fault";
    case protocol::LeverState::homing:
      return "homing";
  }
  return "unknown";
}

}  // namespace lever::app
