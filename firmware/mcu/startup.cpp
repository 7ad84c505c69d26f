// The minimum a Cortex-M7 needs before main: the vector table, .data copied from flash, .bss zeroed, the FPU
// enabled (the core computes in double), static constructors run.
#include <cstdint>

extern "C" {
extern std::uint32_t __data_load, __data_start, __data_end, __bss_start, __bss_end, __stack_top;
extern void (*__init_array_start[])();
extern void (*__init_array_end[])();
int main();
void reset_handler();
void fault_handler();
}

namespace {
using Handler = void (*)();
}

// Initial stack pointer, reset, and every fault to one handler that stops (the smoke test then times out).
__attribute__((section(".vectors"), used)) const Handler vectors[16] = {reinterpret_cast<Handler>(&__stack_top),
                                                                        reset_handler,
                                                                        fault_handler,
                                                                        fault_handler,
                                                                        fault_handler,
                                                                        fault_handler,
                                                                        fault_handler,
                                                                        nullptr,
                                                                        nullptr,
                                                                        nullptr,
                                                                        nullptr,
                                                                        fault_handler,
                                                                        fault_handler,
                                                                        nullptr,
                                                                        fault_handler,
                                                                        fault_handler};

extern "C" void reset_handler() {
  for (std::uint32_t *src = &__data_load, *dst = &__data_start; dst < &__data_end;) *dst++ = *src++;
  for (std::uint32_t* dst = &__bss_start; dst < &__bss_end;) *dst++ = 0;
  // CPACR: full access to CP10 and CP11, the FPU.
  *reinterpret_cast<volatile std::uint32_t*>(0xE000ED88) |= (0xFu << 20);
  asm volatile("dsb\n isb" ::: "memory");
  for (auto* init = __init_array_start; init != __init_array_end; ++init) (*init)();
  main();
  for (;;) {
  }
}

extern "C" void fault_handler() {
  for (;;) {
  }
}
