#pragma once
// Which CAN ids may cross the bridge, per direction: the network must not be able to put arbitrary frames
// onto a bus, and a bus must not leak unrelated traffic onto the network.
#include <bitset>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

#include "lever/protocol/can_frame.hpp"

namespace lever::bridge {

class AllowList {
 public:
  // Hexadecimal ids and inclusive ranges, comma-separated: "0x100-0x1FF,0x700". Throws std::invalid_argument
  // naming the offending item.
  static AllowList parse(std::string_view text);
  // The lever protocol's ids for all pairs: commands, motion, force, heartbeats.
  static AllowList lever_protocol();

  bool allows(std::uint32_t id) const noexcept { return id <= protocol::kMaxStandardId && ids_.test(id); }
  std::size_t count() const noexcept { return ids_.count(); }
  std::string describe() const;  // back in range syntax

 private:
  std::bitset<protocol::kMaxStandardId + 1> ids_;
};

}  // namespace lever::bridge
