#pragma once
// Signal handlers that stop the motors before anything else happens.
//
// Requests to stop (SIGINT, SIGTERM, SIGHUP, SIGQUIT): the handler stops every PwmMotor at once
// (PwmMotor::emergency_stop_all) and records the signal; the program sees it with stop_signal_received() and
// winds down in order, its destructors releasing the enable lines. Each handler is reset as it runs, so a
// second such signal ends the process outright.
// Crashes (SIGABRT, so std::terminate and abort too; SIGSEGV, SIGBUS, SIGFPE, SIGILL): the motors stop, then
// the signal takes its default course.
#include "lever/board/result.hpp"

namespace lever::board {

// true, or which sigaction failed. Installing again is harmless.
Result<bool> install_motor_stop_signal_handlers();

// The stop request's signal number, 0 while none came. Async-signal-safe.
int stop_signal_received() noexcept;

}  // namespace lever::board
