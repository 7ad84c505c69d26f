#pragma once
// Register words as libmodbus delivers them (host-order 16-bit values) into the amplifier's raw number.
// Pure, so every type and word order is tested without a device.
#include <cstdint>
#include <optional>
#include <span>

#include "lever/board/modbus_gauge_config.hpp"

namespace lever::board {

// The raw value in `words` (register_count(type) of them, lowest address first). Empty when there are too
// few words, or for a float32 that is NaN or infinite: an amplifier signalling overload or a broken bridge
// that way must show up as a failed reading, never as a force.
std::optional<double> decode_registers(std::span<const std::uint16_t> words, RegisterType type,
                                       WordOrder order) noexcept;

}  // namespace lever::board
