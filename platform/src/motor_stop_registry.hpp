#pragma once
// Every open PwmMotor's two PWM files, kept where a signal handler can reach them: the process-wide
// emergency stop writes duty 0 and disable to each, with pwrite alone.
#include <cstddef>

namespace lever::platform {

inline constexpr std::size_t kMaxStoppableMotors = 8;

// A slot for a motor's duty_cycle and enable files; -1 when all are taken. The first registration also has
// the process stop its motors at exit().
int register_motor_stop(int duty_fd, int enable_fd) noexcept;
// Frees the slot, after any emergency stop running on another thread is through with it (the fds may be
// closed and their numbers reused right after).
void unregister_motor_stop(int slot) noexcept;

// Async-signal-safe: atomics and pwrite only; errno is preserved. Latches: motors stay stopped afterwards.
void emergency_stop_registered_motors() noexcept;
bool emergency_stop_latched() noexcept;

}  // namespace lever::platform
