#pragma once
// A pause inside one pwrite, to hold a thread in the middle of what it is doing (a motor command between its
// writes) while another thread acts. This test program's own pwrite stands in for libc's (the board library
// is linked in statically, so its calls land here); unless armed it is the system call and nothing else.
#include <chrono>
#include <string_view>

namespace lever::test {

// The next pwrite of exactly `text` (e.g. "1\n", the PWM enabled) first says so (pwrite_paused() turns true),
// sleeps `pause` and calls `meanwhile` (when given: what a signal handler on the writing thread would do), then
// writes (pwrite_resumed() turns true once it has). Once only.
void pause_next_pwrite_of(std::string_view text, std::chrono::milliseconds pause, void (*meanwhile)() = nullptr);
bool pwrite_paused();
bool pwrite_resumed();

}  // namespace lever::test
