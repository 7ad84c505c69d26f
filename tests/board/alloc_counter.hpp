#pragma once
// Counts heap allocations (malloc and friends, so libgpiod's too) made between begin() and end() on any
// thread. Unavailable under AddressSanitizer, which owns malloc itself.
#include <cstdint>

namespace lever::test {

bool alloc_counting_available() noexcept;
void alloc_count_begin() noexcept;
std::uint64_t alloc_count_end() noexcept;  // allocations since begin()

}  // namespace lever::test
