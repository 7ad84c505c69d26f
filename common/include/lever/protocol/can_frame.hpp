#pragma once
// A classic CAN 2.0A frame as the lever protocol sees it: 11-bit id, up to 8 data bytes.
#include <array>
#include <cstdint>

namespace lever::protocol {

struct CanFrame {
  std::uint32_t id = 0;  // 11-bit standard identifier
  std::uint8_t dlc = 0;  // 0..8
  std::array<std::uint8_t, 8> data{};
};

constexpr std::uint32_t kMaxStandardId = 0x7FF;

}  // namespace lever::protocol
