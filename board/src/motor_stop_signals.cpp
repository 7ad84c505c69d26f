#include "lever/board/motor_stop_signals.hpp"

#include <signal.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <string>

#include "lever/board/pwm_motor.hpp"

namespace lever::board {

namespace {

std::atomic<int> received{0};
static_assert(std::atomic<int>::is_always_lock_free);

constexpr int kStopSignals[] = {SIGINT, SIGTERM, SIGHUP, SIGQUIT};
constexpr int kCrashSignals[] = {SIGABRT, SIGSEGV, SIGBUS, SIGFPE, SIGILL};

extern "C" void on_stop_signal(int signal_number) {
  PwmMotor::emergency_stop_all();
  received.store(signal_number);
}

// SA_RESETHAND has put the default action back; raising again delivers it once this handler returns (a fault
// would recur on its own, but a signal sent with kill or raise would not).
extern "C" void on_crash_signal(int signal_number) {
  PwmMotor::emergency_stop_all();
  ::raise(signal_number);
}

bool install(int signal_number, void (*handler)(int)) {
  struct sigaction action {};
  action.sa_handler = handler;
  ::sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND | SA_RESTART;
  return ::sigaction(signal_number, &action, nullptr) == 0;
}

}  // namespace

Result<bool> install_motor_stop_signal_handlers() {
  for (const int s : kStopSignals) {
    if (!install(s, on_stop_signal)) {
      const int err = errno;
      return Error{"sigaction(" + std::string(::strsignal(s)) + "): " + std::strerror(err), err};
    }
  }
  for (const int s : kCrashSignals) {
    if (!install(s, on_crash_signal)) {
      const int err = errno;
      return Error{"sigaction(" + std::string(::strsignal(s)) + "): " + std::strerror(err), err};
    }
  }
  return true;
}

int stop_signal_received() noexcept { return received.load(); }

}  // namespace lever::board
