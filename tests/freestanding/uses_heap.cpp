// Control sample for the freestanding check: it must be rejected, or the check proves nothing.
#include <memory>

int* leak_an_int() { return new int(42); }
