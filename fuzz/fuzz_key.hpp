#pragma once
// The fixed key the datagram fuzzer and its corpus generator share, so that the seeds are authentic.
// A test key, public by definition: never use it for a bridge.
#include <cstdint>

#include "key.hpp"

namespace lever::bridge::fuzz {

inline Key fuzz_key() noexcept {
  Key key;
  for (std::size_t i = 0; i < key.bytes.size(); ++i) key.bytes[i] = static_cast<std::uint8_t>(0xF0 ^ (i * 29));
  return key;
}

}  // namespace lever::bridge::fuzz
