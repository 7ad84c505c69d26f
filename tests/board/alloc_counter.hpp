#pragma once
// Counts heap allocations (malloc and friends, so libgpiod's too) made between begin() and end() on any
// thread; under AddressSanitizer through its allocation hook.
#include <cstdint>

namespace lever::test {

void alloc_count_begin() noexcept;
std::uint64_t alloc_count_end() noexcept;  // allocations since begin()

}  // namespace lever::test
