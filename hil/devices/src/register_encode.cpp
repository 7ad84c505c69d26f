#include "lever/hil/devices/register_encode.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

namespace lever::hil::devices {

namespace {

// Rounded to nearest and held inside [lo, hi] before the conversion, which would be undefined out of range.
template <typename Int>
Int to_integer(double raw) noexcept {
  if (std::isnan(raw)) return 0;
  constexpr double lo = static_cast<double>(std::numeric_limits<Int>::min());
  constexpr double hi = static_cast<double>(std::numeric_limits<Int>::max());
  return static_cast<Int>(std::clamp(std::round(raw), lo, hi));
}

float to_float(double raw) noexcept {
  if (!std::isfinite(raw)) return static_cast<float>(raw);
  constexpr double limit = static_cast<double>(std::numeric_limits<float>::max());
  return static_cast<float>(std::clamp(raw, -limit, limit));
}

}  // namespace

double raw_for_newtons(double newtons, const board::GaugeRegisterMap& map) noexcept {
  return (newtons - map.offset) / map.scale;
}

RegisterWords encode_registers(double raw, board::RegisterType type, board::WordOrder order) noexcept {
  using board::RegisterType;
  std::uint32_t bits = 0;
  switch (type) {
    case RegisterType::int16:
      return {{static_cast<std::uint16_t>(to_integer<std::int16_t>(raw)), 0}, 1};
    case RegisterType::uint16:
      return {{to_integer<std::uint16_t>(raw), 0}, 1};
    case RegisterType::int32:
      bits = static_cast<std::uint32_t>(to_integer<std::int32_t>(raw));
      break;
    case RegisterType::uint32:
      bits = to_integer<std::uint32_t>(raw);
      break;
    case RegisterType::float32:
      bits = std::bit_cast<std::uint32_t>(to_float(raw));
      break;
  }
  const auto high = static_cast<std::uint16_t>(bits >> 16);
  const auto low = static_cast<std::uint16_t>(bits & 0xFFFFu);
  if (order == board::WordOrder::high_first) return {{high, low}, 2};
  return {{low, high}, 2};
}

}  // namespace lever::hil::devices
