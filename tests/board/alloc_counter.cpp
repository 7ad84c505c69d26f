#include "alloc_counter.hpp"

#include <atomic>
#include <cstddef>
#include <cstdlib>

namespace {
std::atomic<bool> counting{false};
std::atomic<std::uint64_t> allocations{0};
}  // namespace

#if defined(__SANITIZE_ADDRESS__)

// AddressSanitizer owns malloc; it calls a hook on every allocation instead (sanitizer/allocator_interface.h, which
// GCC does not install; the function is libasan's).
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*));
namespace {
void count_allocation(const volatile void*, std::size_t) {
  if (counting.load(std::memory_order_relaxed)) allocations.fetch_add(1, std::memory_order_relaxed);
}
void ignore_free(const volatile void*) {}  // libasan installs no hook pair with a null half
// 0 when libasan refused the hooks; then nothing would be counted, so that is a failure, not a quiet zero.
const int hooks_installed = __sanitizer_install_malloc_and_free_hooks(count_allocation, ignore_free);
}  // namespace

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

#endif

namespace lever::test {
void alloc_count_begin() noexcept {
#if defined(__SANITIZE_ADDRESS__)
  if (hooks_installed == 0) std::abort();  // allocations could not be counted: no check may pass on a quiet zero
#endif
  allocations.store(0);
  counting.store(true);
}
std::uint64_t alloc_count_end() noexcept {
  counting.store(false);
  return allocations.load();
}
}  // namespace lever::test
