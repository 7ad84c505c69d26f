// The motor guard (board/motor_guard.hpp) as lever-fw runs it: the real program (lever-fw --motor-guard) exec'd
// beside a lever process on a temporary sysfs tree. Each case runs its lever in a forked child: a guard is one per
// process, and its end latches the process's emergency stop. What is checked is what the guard wrote to the PWM,
// never what it says: the defined inactive state is duty 0 with the PWM enabled.
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <string>
#include <thread>

#include "fork_child.hpp"
#include "lever/board/monotonic_clock.hpp"
#include "lever/board/motor_guard.hpp"
#include "lever/board/pwm_motor.hpp"
#include "pwm_sysfs_tree.hpp"
#include "pwm_test_motor.hpp"

using lever::board::MotorGuard;
using lever::board::MotorGuardConfig;
using lever::board::PwmMotor;
using lever::test::driving_motor;
using lever::test::PwmSysfsTree;
using lever::test::wait_status_of_child;

namespace {

MotorGuardConfig guard_config(std::chrono::milliseconds deadline) {
  MotorGuardConfig c;
  c.deadline = deadline;
  c.check = std::chrono::milliseconds(5);
  c.program = LEVER_FW_PROGRAM;
  return c;
}

bool inactive(const PwmSysfsTree& tree) { return tree.read("duty_cycle") == "0" && tree.read("enable") == "1"; }

// Polls (1 ms) until the condition holds or 5 s have passed: how long it took is the rig's and the images' to
// measure, not a unit test's on a shared machine.
template <typename F>
bool within_5_s(F&& condition) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  while (!condition()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return true;
}

}  // namespace

TEST_CASE("MotorGuard: a loop that stops stepping has its motor put in the inactive state, and is told", "[guard]") {
  PwmSysfsTree tree(lever::test::kPwmTestChip, lever::test::kPwmTestChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);
    // 200 ms: far above this loop's 1 ms sleeps, however busy the machine, so only the stop below can trip it.
    auto guard = MotorGuard::start(guard_config(std::chrono::milliseconds(200)), motor.guard_handles());
    if (!guard) return 10;
    for (int i = 0; i < 300; ++i) {
      guard.value().stepped(lever::board::monotonic_ns());
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (guard.value().take_trip() || !(tree.read("duty_cycle") == "15000")) return 11;  // stepping: left alone
    if (!within_5_s([&] { return inactive(tree); })) return 12;
    // The guard counts the trip after its writes, so the lever never forgets values it may still write over.
    if (!within_5_s([&] { return guard.value().take_trip(); })) return 13;
    // The lever's next command writes every value again, the motor's cache of them being stale now.
    motor.note_external_stop();
    motor.command({0.3, true});
    if (tree.read("duty_cycle") != "15000") return 14;
    return 0;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}

TEST_CASE("MotorGuard: a lever killed has its motor put in the inactive state by its guard", "[guard]") {
  PwmSysfsTree tree(lever::test::kPwmTestChip, lever::test::kPwmTestChannel);
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  std::fflush(nullptr);
  const pid_t lever = ::fork();
  REQUIRE(lever >= 0);
  if (lever == 0) {
    ::alarm(20);
    PwmMotor motor = driving_motor(tree);
    auto guard = MotorGuard::start(guard_config(std::chrono::milliseconds(10'000)), motor.guard_handles());
    if (!guard) ::_exit(10);
    [[maybe_unused]] const auto ignored = ::write(ready[1], "r", 1);
    for (;;) ::pause();
  }
  ::close(ready[1]);
  char byte = 0;
  const bool started = ::read(ready[0], &byte, 1) == 1;
  ::close(ready[0]);
  if (!started) {
    int status = 0;
    ::waitpid(lever, &status, 0);
    FAIL("the lever did not start its guard: exit " << WEXITSTATUS(status));
  }
  CHECK(tree.read("duty_cycle") == "15000");  // on when it is killed
  REQUIRE(::kill(lever, SIGKILL) == 0);
  int status = 0;
  REQUIRE(::waitpid(lever, &status, 0) == lever);
  REQUIRE(WIFSIGNALED(status));
  CHECK(within_5_s([&] { return inactive(tree); }));
}

TEST_CASE("MotorGuard: a guard killed has the lever stop its motor itself and say so", "[guard]") {
  PwmSysfsTree tree(lever::test::kPwmTestChip, lever::test::kPwmTestChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);
    auto guard = MotorGuard::start(guard_config(std::chrono::milliseconds(10'000)), motor.guard_handles());
    if (!guard) return 10;
    if (MotorGuard::lost()) return 11;
    ::kill(guard.value().pid(), SIGKILL);
    if (!within_5_s([] { return MotorGuard::lost(); })) return 12;
    if (tree.read("duty_cycle") != "0") return 13;
    motor.command({0.3, true});  // latched: nothing drives any more
    if (tree.read("duty_cycle") != "0") return 14;
    return 0;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}

TEST_CASE("MotorGuard: the guard program refuses a spec it cannot read, and a program that is not there fails start",
          "[guard]") {
  CHECK(lever::board::run_motor_guard("lever=1") == 2);
  CHECK(lever::board::run_motor_guard("duty=3,enable=4,nonsense") == 2);
  PwmSysfsTree tree(lever::test::kPwmTestChip, lever::test::kPwmTestChannel);
  const int status = wait_status_of_child([&] {
    auto motor = PwmMotor::open(lever::test::pwm_test_config(tree));
    if (!motor) return 90;
    MotorGuardConfig c = guard_config(std::chrono::milliseconds(100));
    c.program = "/nonexistent/lever-fw";
    auto guard = MotorGuard::start(c, motor.value().guard_handles());
    if (guard) return 10;
    return guard.error().message.find("/nonexistent/lever-fw") != std::string::npos ? 0 : 11;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}
