// encode_registers() against the board layer's decode_registers(): for every type and word order, the value decoded
// from the registers is the raw value asked for, rounded and clamped as the type requires.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <span>
#include <vector>

#include "lever/board/modbus_register_decode.hpp"
#include "lever/hil/devices/register_encode.hpp"

using lever::board::RegisterType;
using lever::board::WordOrder;
using lever::hil::devices::encode_registers;
using lever::hil::devices::raw_for_newtons;

namespace {

std::optional<double> round_trip(double raw, RegisterType type, WordOrder order) {
  const auto encoded = encode_registers(raw, type, order);
  REQUIRE(encoded.count == lever::board::register_count(type));
  return lever::board::decode_registers(
      std::span<const std::uint16_t>(encoded.words.data(), static_cast<std::size_t>(encoded.count)), type, order);
}

template <typename Int>
void check_integer_type(RegisterType type, WordOrder order) {
  constexpr double lo = static_cast<double>(std::numeric_limits<Int>::min());
  constexpr double hi = static_cast<double>(std::numeric_limits<Int>::max());
  // Values whose words differ, so a swapped order would decode to something else.
  const std::vector<double> exact{0, 1, 7, 1234, 54321, 74565, -1234, -123456789, 4000000000.0, lo, hi, lo + 1, hi - 1};
  for (const double raw : exact) {
    CAPTURE(raw);
    const double expected = std::clamp(raw, lo, hi);
    CHECK(round_trip(raw, type, order) == expected);
  }
  CHECK(round_trip(12.4, type, order) == 12.0);
  CHECK(round_trip(12.6, type, order) == 13.0);
  CHECK(round_trip(hi + 1e6, type, order) == hi);
  CHECK(round_trip(lo - 1e6, type, order) == lo);
  CHECK(round_trip(std::numeric_limits<double>::infinity(), type, order) == hi);
  CHECK(round_trip(-std::numeric_limits<double>::infinity(), type, order) == lo);
  CHECK(round_trip(std::nan(""), type, order) == 0.0);
}

}  // namespace

TEST_CASE("integer types: decoded as encoded, rounded to nearest, clamped to the type's range") {
  for (const WordOrder order : {WordOrder::high_first, WordOrder::low_first}) {
    CAPTURE(static_cast<int>(order));
    check_integer_type<std::int16_t>(RegisterType::int16, order);
    check_integer_type<std::uint16_t>(RegisterType::uint16, order);
    check_integer_type<std::int32_t>(RegisterType::int32, order);
    check_integer_type<std::uint32_t>(RegisterType::uint32, order);
  }
}

TEST_CASE("float32: decoded as the nearest float; NaN and infinity stay failed readings") {
  for (const WordOrder order : {WordOrder::high_first, WordOrder::low_first}) {
    CAPTURE(static_cast<int>(order));
    for (const double raw : {0.0, 3.14159274, -12.5, 1e-3, 123456.789, -9.80665e-3, 1e30}) {
      CAPTURE(raw);
      CHECK(round_trip(raw, RegisterType::float32, order) == static_cast<double>(static_cast<float>(raw)));
    }
    constexpr double fmax = static_cast<double>(std::numeric_limits<float>::max());
    CHECK(round_trip(1e300, RegisterType::float32, order) == fmax);
    CHECK(round_trip(-1e300, RegisterType::float32, order) == -fmax);
    CHECK_FALSE(round_trip(std::nan(""), RegisterType::float32, order).has_value());
    CHECK_FALSE(round_trip(std::numeric_limits<double>::infinity(), RegisterType::float32, order).has_value());
  }
}

TEST_CASE("the word order puts the high word where the decoder looks for it") {
  const auto high = encode_registers(0x12345678, RegisterType::uint32, WordOrder::high_first);
  CHECK(high.words[0] == 0x1234);
  CHECK(high.words[1] == 0x5678);
  const auto low = encode_registers(0x12345678, RegisterType::uint32, WordOrder::low_first);
  CHECK(low.words[0] == 0x5678);
  CHECK(low.words[1] == 0x1234);
}

TEST_CASE("raw_for_newtons inverts newtons = raw * scale + offset") {
  lever::board::GaugeRegisterMap map;
  map.scale = 9.80665e-3;
  map.offset = -2.5;
  for (const double raw : {0.0, 1.0, -250.0, 12345.0}) {
    CHECK(raw_for_newtons(raw * map.scale + map.offset, map) == Approx(raw).margin(1e-9));
  }
  map.scale = -0.5;
  CHECK(raw_for_newtons(-10.0 + map.offset, map) == Approx(20.0));
}
