// Only in lever-mcu-heap-control: one allocation at start-up, which scripts/build-mcu's no-heap check must
// report, or the check proves nothing.
#include <cstdlib>

namespace {
struct Allocates {
  Allocates() { block = std::malloc(64); }
  void* block;
} allocates;
}  // namespace

// newlib's malloc asks for memory through _sbrk; a bump over a static block is enough for the control.
extern "C" void* _sbrk(int increment) {
  static char heap[1024];
  static int used = 0;
  if (increment < 0 || used + increment > static_cast<int>(sizeof heap)) return reinterpret_cast<void*>(-1);
  void* p = heap + used;
  used += increment;
  return p;
}
