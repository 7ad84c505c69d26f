#include "lever/board/modbus_register_decode.hpp"

#include <bit>
#include <cmath>

namespace lever::board {

std::optional<double> decode_registers(std::span<const std::uint16_t> words, RegisterType type,
                                       WordOrder order) noexcept {
  if (words.size() < static_cast<std::size_t>(register_count(type))) return std::nullopt;
  if (type == RegisterType::int16) return static_cast<double>(static_cast<std::int16_t>(words[0]));
  if (type == RegisterType::uint16) return static_cast<double>(words[0]);

  const std::uint32_t high = order == WordOrder::high_first ? words[0] : words[1];
  const std::uint32_t low = order == WordOrder::high_first ? words[1] : words[0];
  const std::uint32_t bits = (high << 16) | low;
  switch (type) {
    case RegisterType::int32:
      return static_cast<double>(static_cast<std::int32_t>(bits));
    case RegisterType::uint32:
      return static_cast<double>(bits);
    case RegisterType::float32: {
      const float value = std::bit_cast<float>(bits);
      if (!std::isfinite(value)) return std::nullopt;
      return static_cast<double>(value);
    }
    default:
      return std::nullopt;
  }
}

}  // namespace lever::board
