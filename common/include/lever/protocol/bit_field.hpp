#pragma once
// Little-endian (DBC "@1", Intel) bit fields in an 8-byte CAN payload, the layout common/protocol/lever.dbc
// describes. Bit-by-bit on purpose: fields need not be byte-aligned, and the code reads like the DBC.
#include <array>
#include <cstdint>

namespace lever::protocol {

using Payload = std::array<std::uint8_t, 8>;

constexpr void put_bits(Payload& data, unsigned start, unsigned length, std::uint64_t raw) noexcept {
  for (unsigned i = 0; i < length; ++i) {
    const unsigned bit = start + i;
    const auto mask = static_cast<std::uint8_t>(1u << (bit % 8));
    if ((raw >> i) & 1u) {
      data[bit / 8] = static_cast<std::uint8_t>(data[bit / 8] | mask);
    } else {
      data[bit / 8] = static_cast<std::uint8_t>(data[bit / 8] & ~mask);
    }
  }
}

constexpr std::uint64_t get_bits(const Payload& data, unsigned start, unsigned length) noexcept {
  std::uint64_t raw = 0;
  for (unsigned i = 0; i < length; ++i) {
    const unsigned bit = start + i;
    raw |= static_cast<std::uint64_t>((data[bit / 8] >> (bit % 8)) & 1u) << i;
  }
  return raw;
}

// Two's complement field of `length` bits, sign-extended.
constexpr std::int64_t get_signed_bits(const Payload& data, unsigned start, unsigned length) noexcept {
  const std::uint64_t raw = get_bits(data, start, length);
  const std::uint64_t sign = std::uint64_t{1} << (length - 1);
  return static_cast<std::int64_t>(raw ^ sign) - static_cast<std::int64_t>(sign);
}

constexpr void put_signed_bits(Payload& data, unsigned start, unsigned length, std::int64_t value) noexcept {
  put_bits(data, start, length, static_cast<std::uint64_t>(value));
}

}  // namespace lever::protocol
