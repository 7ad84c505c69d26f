// decode_registers: every type in both word orders, signs, limits, and float32 values that are not numbers.
#include <catch2/catch.hpp>
#include <cstdint>
#include <vector>

#include "lever/board/modbus_register_decode.hpp"

using lever::board::decode_registers;
using lever::board::RegisterType;
using lever::board::WordOrder;

namespace {

std::optional<double> decode(std::vector<std::uint16_t> words, RegisterType type, WordOrder order) {
  return decode_registers(words, type, order);
}

constexpr auto high = WordOrder::high_first;
constexpr auto low = WordOrder::low_first;

}  // namespace

TEST_CASE("int16 is a two's complement register, whatever the word order") {
  CHECK(decode({0x04D2}, RegisterType::int16, high) == 1234.0);
  CHECK(decode({0xFB2E}, RegisterType::int16, high) == -1234.0);
  CHECK(decode({0x8000}, RegisterType::int16, high) == -32768.0);
  CHECK(decode({0x7FFF}, RegisterType::int16, high) == 32767.0);
  CHECK(decode({0xFB2E}, RegisterType::int16, low) == -1234.0);
}

TEST_CASE("uint16 is the register as it is") {
  CHECK(decode({0xFFFF}, RegisterType::uint16, high) == 65535.0);
  CHECK(decode({0x8000}, RegisterType::uint16, high) == 32768.0);
  CHECK(decode({0x0000}, RegisterType::uint16, low) == 0.0);
}

TEST_CASE("int32 in both word orders, negative values included") {
  CHECK(decode({0xF8A4, 0x32EB}, RegisterType::int32, high) == -123456789.0);
  CHECK(decode({0x32EB, 0xF8A4}, RegisterType::int32, low) == -123456789.0);
  CHECK(decode({0x0001, 0x2345}, RegisterType::int32, high) == 74565.0);
  CHECK(decode({0x2345, 0x0001}, RegisterType::int32, low) == 74565.0);
  CHECK(decode({0xFFFF, 0xFFFF}, RegisterType::int32, high) == -1.0);
  CHECK(decode({0x8000, 0x0000}, RegisterType::int32, high) == -2147483648.0);
  CHECK(decode({0xFFFF, 0x7FFF}, RegisterType::int32, low) == 2147483647.0);
}

TEST_CASE("uint32 in both word orders, beyond the int32 range") {
  CHECK(decode({0xEE6B, 0x2800}, RegisterType::uint32, high) == 4000000000.0);
  CHECK(decode({0x2800, 0xEE6B}, RegisterType::uint32, low) == 4000000000.0);
  CHECK(decode({0xFFFF, 0xFFFF}, RegisterType::uint32, high) == 4294967295.0);
  CHECK(decode({0x0001, 0x2345}, RegisterType::uint32, high) == 74565.0);
  CHECK(decode({0x2345, 0x0001}, RegisterType::uint32, low) == 74565.0);
}

TEST_CASE("float32 in both word orders") {
  CHECK(decode({0x3FC0, 0x0000}, RegisterType::float32, high) == 1.5);
  CHECK(decode({0x0000, 0x3FC0}, RegisterType::float32, low) == 1.5);
  CHECK(decode({0xC148, 0x0000}, RegisterType::float32, high) == -12.5);
  CHECK(decode({0x0FDB, 0x4049}, RegisterType::float32, low) == static_cast<double>(3.14159274f));
  CHECK(decode({0x4049, 0x0FDB}, RegisterType::float32, high) == static_cast<double>(3.14159274f));
  CHECK(decode({0x7F7F, 0xFFFF}, RegisterType::float32, high) == 3.4028234663852886e38);  // largest finite
  CHECK(decode({0x0000, 0x0001}, RegisterType::float32, high) > 0.0);                     // smallest denormal
}

TEST_CASE("float32 NaN and infinities are failed readings, never values") {
  CHECK_FALSE(decode({0x7FC0, 0x0000}, RegisterType::float32, high));  // quiet NaN
  CHECK_FALSE(decode({0x7F80, 0x0001}, RegisterType::float32, high));  // signalling NaN
  CHECK_FALSE(decode({0xFFC0, 0x0000}, RegisterType::float32, high));  // negative NaN
  CHECK_FALSE(decode({0x7F80, 0x0000}, RegisterType::float32, high));  // +inf
  CHECK_FALSE(decode({0xFF80, 0x0000}, RegisterType::float32, high));  // -inf
  CHECK_FALSE(decode({0x0000, 0x7FC0}, RegisterType::float32, low));   // NaN, low word first
  CHECK_FALSE(decode({0x0000, 0xFF80}, RegisterType::float32, low));   // -inf, low word first
}

TEST_CASE("too few words is a failed reading") {
  CHECK_FALSE(decode({}, RegisterType::int16, high));
  CHECK_FALSE(decode({0x1234}, RegisterType::int32, high));
  CHECK_FALSE(decode({0x1234}, RegisterType::float32, low));
}
