#include "semihosting.hpp"

namespace lever::mcu {
namespace {

constexpr int kWrite0 = 0x04;
constexpr int kExit = 0x18;
constexpr unsigned long kApplicationExit = 0x20026;
constexpr unsigned long kRunTimeErrorUnknown = 0x20023;

long call(int op, const void* arg) {
  register int r0 asm("r0") = op;
  register const void* r1 asm("r1") = arg;
  asm volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
  return r0;
}

}  // namespace

void write(const char* text) { call(kWrite0, text); }

void write_number(unsigned long value) {
  char digits[24];
  char* p = digits + sizeof digits;
  *--p = '\0';
  do {
    *--p = static_cast<char>('0' + value % 10);
    value /= 10;
  } while (value != 0);
  write(p);
}

void exit(bool success) {
  // On Cortex-M (no 64-bit SYS_EXIT), the argument is the reason code itself.
  call(kExit, reinterpret_cast<const void*>(success ? kApplicationExit : kRunTimeErrorUnknown));
  for (;;) {
  }
}

}  // namespace lever::mcu
