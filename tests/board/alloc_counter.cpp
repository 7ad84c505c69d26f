#include "alloc_counter.hpp"

#include <atomic>
#include <cstddef>

namespace {
std::atomic<bool> counting{false};
std::atomic<std::uint64_t> allocations{0};
}  // namespace

#if defined(__SANITIZE_ADDRESS__)

namespace lever::test {
bool alloc_counting_available() noexcept { return false; }
void alloc_count_begin() noexcept {}
std::uint64_t alloc_count_end() noexcept { return 0; }
}  // namespace lever::test

#else

// glibc's own entry points: defining malloc here makes every caller in the process (libgpiod included) come
// through the counter, which then hands over to glibc.
extern "C" {
void* __libc_malloc(std::size_t size);
void* __libc_calloc(std::size_t count, std::size_t size);
void* __libc_realloc(void* p, std::size_t size);
void __libc_free(void* p);

void* malloc(std::size_t size) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_malloc(size);
}
void* calloc(std::size_t count, std::size_t size) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_calloc(count, size);
}
void* realloc(void* p, std::size_t size) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
  return __libc_realloc(p, size);
}
void free(void* p) { __libc_free(p); }
}

namespace lever::test {
bool alloc_counting_available() noexcept { return true; }
void alloc_count_begin() noexcept {
  allocations.store(0);
  counting.store(true);
}
std::uint64_t alloc_count_end() noexcept {
  counting.store(false);
  return allocations.load();
}
}  // namespace lever::test

#endif
