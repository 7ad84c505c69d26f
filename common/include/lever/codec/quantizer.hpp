#pragma once
// What a value becomes on the wire. The sender feeds its reference model the value the receiver will decode,
// not the value it measured, so fixed-point rounding cannot make the two models drift apart.
#include <cmath>
#include <concepts>
#include <cstdint>
#include <limits>

namespace lever::codec {

template <typename Q, typename T>
concept Quantizer = requires(const Q q, T value, typename Q::wire_type wire, bool& saturated) {
  { q.encode(value, saturated) } -> std::same_as<typename Q::wire_type>;
  { q.decode(wire) } -> std::same_as<T>;
};

// Lossless: the wire carries the scalar itself (the codec tool, tests, in-process links).
template <typename T>
struct IdentityQuantizer {
  using wire_type = T;
  constexpr wire_type encode(T value, bool& /*saturated*/) const noexcept { return value; }
  constexpr T decode(wire_type wire) const noexcept { return wire; }
};

// value = wire * resolution, rounded to nearest (half away from zero), saturating at [lo, hi].
// Saturation is reported, never wrapped: a wrapped force would flip sign on the operator's hand.
template <typename T, std::signed_integral Int = std::int32_t>
struct FixedPointQuantizer {
  using wire_type = Int;
  T resolution = T(1);
  Int lo = std::numeric_limits<Int>::min();
  Int hi = std::numeric_limits<Int>::max();

  constexpr wire_type encode(T value, bool& saturated) const noexcept {
    const T scaled = value / resolution;
    if (!(scaled == scaled)) {  // NaN: no honest code exists
      saturated = true;
      return Int(0);
    }
    if (scaled >= static_cast<T>(hi)) {
      saturated = saturated || scaled > static_cast<T>(hi) + T(0.5);
      return hi;
    }
    if (scaled <= static_cast<T>(lo)) {
      saturated = saturated || scaled < static_cast<T>(lo) - T(0.5);
      return lo;
    }
    return static_cast<Int>(scaled >= T(0) ? scaled + T(0.5) : scaled - T(0.5));
  }
  constexpr T decode(wire_type wire) const noexcept { return static_cast<T>(wire) * resolution; }
};

}  // namespace lever::codec
