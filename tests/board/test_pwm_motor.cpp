// The PWM motor on a temporary sysfs tree (pwm_sysfs_tree.hpp): what open() writes, duty following torque,
// unchanged values left alone, and the motor stopped on every way out: destruction, exit(), the emergency
// stop, SIGINT and SIGTERM, abort(). The GPIO lines are tested in the kernel rig (test_pwm_motor_gpio_sim.cpp);
// here the motor has none, so it is configured positive_torque_only.
#include <sys/resource.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <limits>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "fork_child.hpp"
#include "lever/board/motor_stop_signals.hpp"
#include "lever/board/pwm_motor.hpp"
#include "lever/board/torque_to_duty.hpp"
#include "pwm_sysfs_tree.hpp"
#include "pwm_test_motor.hpp"
#include "pwrite_pause.hpp"

using lever::board::LineRef;
using lever::board::MotorLineConfig;
using lever::board::PwmMotor;
using lever::board::PwmMotorConfig;
using lever::board::TorqueToDuty;
using lever::fw::MotorCommand;
using lever::test::driving_motor;
using lever::test::PwmSysfsTree;
using lever::test::wait_status_of_child;

namespace {

constexpr unsigned kChip = lever::test::kPwmTestChip;
constexpr unsigned kChannel = lever::test::kPwmTestChannel;

PwmMotorConfig config_for(const PwmSysfsTree& tree) { return lever::test::pwm_test_config(tree); }

PwmMotor open_or_fail(const PwmMotorConfig& config) {
  auto motor = PwmMotor::open(config);
  if (!motor) FAIL(motor.error().message);
  return std::move(motor).value();
}

bool mentions(const std::vector<std::string>& problems, const std::string& text) {
  for (const auto& p : problems)
    if (p.find(text) != std::string::npos) return true;
  return false;
}

// Stopped is the inactive state: duty 0 with the channel enabled. A disabled channel's output is undefined (the
// kernel's PWM documentation): some controllers hold the pin where it was, so "enable 0" is not off.
bool stopped(const PwmSysfsTree& tree) { return tree.read("duty_cycle") == "0" && tree.read("enable") == "1"; }

}  // namespace

TEST_CASE("PwmMotorConfig: each problem names its field", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  CHECK(config_for(tree).validate().empty());

  PwmMotorConfig c = config_for(tree);
  c.sysfs_root.clear();
  c.period_ns = 500;
  c.torque_constant_nm_per_a = 0.0;
  c.gear_ratio = -1.0;
  c.full_scale_current_a = std::numeric_limits<double>::quiet_NaN();
  c.max_duty = 1.5;
  c.deadband_nm = -0.1;
  c.consumer = std::string(40, 'x');
  const auto problems = c.validate();
  CHECK(mentions(problems, "sysfs_root:"));
  CHECK(mentions(problems, "period_ns: 500"));
  CHECK(mentions(problems, "torque_constant_nm_per_a: 0,"));
  CHECK(mentions(problems, "gear_ratio: -1,"));
  CHECK(mentions(problems, "full_scale_current_a: nan"));
  CHECK(mentions(problems, "max_duty: 1.5"));
  CHECK(mentions(problems, "deadband_nm: -0.1"));
  CHECK(mentions(problems, "consumer: 40 characters"));

  PwmMotorConfig lines = config_for(tree);
  lines.positive_torque_only = false;
  CHECK(mentions(lines.validate(), "direction_line: none"));
  lines.direction_line = MotorLineConfig{"gpiochip0", LineRef::name("DIR"), false};
  lines.enable_line = MotorLineConfig{"gpiochip0", LineRef::name("DIR"), false};
  lines.fault_line = MotorLineConfig{"", LineRef::name(""), true};
  const auto line_problems = lines.validate();
  CHECK(mentions(line_problems, "direction_line: the same line as enable_line"));
  CHECK(mentions(line_problems, "fault_line.chip: empty"));
  CHECK(mentions(line_problems, "fault_line.line: empty name"));
  lines.positive_torque_only = true;
  CHECK(mentions(lines.validate(), "positive_torque_only: set, yet direction_line is given"));

  const auto refused = PwmMotor::open(c);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("motor config: sysfs_root:") == 0);
}

TEST_CASE("TorqueToDuty: magnitude over the torque at full duty, clamped, with a deadband and a sign", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotorConfig c = config_for(tree);
  c.positive_torque_only = false;
  const TorqueToDuty map(c);
  CHECK(map.torque_at_full_duty_nm() == Approx(1.0));
  CHECK(map(0.3).duty_ns == 15'000);
  CHECK_FALSE(map(0.3).negative);
  CHECK(map(-0.3).duty_ns == 15'000);
  CHECK(map(-0.3).negative);
  CHECK(map(0.200018).duty_ns == 10'001);  // 10000.9 ns: rounded to the nearest, not truncated
  CHECK(map(0.95).duty_ns == 45'000);      // max_duty 0.9
  CHECK(map(-7.0).duty_ns == 45'000);
  CHECK(map(std::numeric_limits<double>::infinity()).duty_ns == 45'000);
  CHECK(map(0.009).duty_ns == 0);  // deadband 0.01
  CHECK(map(-0.009).duty_ns == 0);
  CHECK(map(0.01).duty_ns == 500);
  CHECK(map(0.0).duty_ns == 0);
  CHECK(map(std::numeric_limits<double>::quiet_NaN()).duty_ns == 0);

  c.positive_torque_only = true;
  const TorqueToDuty positive_only(c);
  CHECK(positive_only(0.3).duty_ns == 15'000);
  CHECK(positive_only(-0.3).duty_ns == 0);
}

TEST_CASE("PwmMotor: open zeroes the duty, writes the period and polarity, and leaves the channel enabled at duty 0",
          "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);       // as a crashed run left it: enabled, duty 123456, inversed
  tree.overwrite("enable", "untouched\n");  // so that the 1 read below is one open wrote
  PwmMotorConfig c = config_for(tree);
  SECTION("normal polarity") {
    const PwmMotor motor = open_or_fail(c);
    CHECK(tree.read("enable") == "1");
    CHECK(tree.read("duty_cycle") == "0");
    CHECK(tree.read("period") == "50000");
    CHECK(tree.read("polarity") == "normal");
    CHECK(tree.read_export().empty());  // pwm1/ was there: taken over, not exported again
    CHECK(motor.description().find("pwmchip2/pwm1 20000 Hz") == 0);
  }
  SECTION("inversed polarity") {
    c.pwm_inversed = true;
    c.period_ns = 40'000;
    const PwmMotor motor = open_or_fail(c);
    CHECK(tree.read("period") == "40000");
    CHECK(tree.read("polarity") == "inversed");
  }
}

TEST_CASE("PwmMotor: open exports a channel that is not there, and names it when it never appears", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel, /*with_channel=*/false);
  PwmMotorConfig c = config_for(tree);
  c.export_timeout_ms = 20;  // a regular file cannot make the kernel create pwm1/: it never comes
  const auto motor = PwmMotor::open(c);
  REQUIRE_FALSE(motor.ok());
  CHECK(tree.read_export() == "1");
  CHECK(motor.error().message.find("pwmchip2/pwm1/enable and duty_cycle not writable 20 ms after the export") !=
        std::string::npos);
}

TEST_CASE("PwmMotor: open names a PWM chip that is not there", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotorConfig c = config_for(tree);
  c.pwm_chip = 7;
  const auto motor = PwmMotor::open(c);
  REQUIRE_FALSE(motor.ok());
  CHECK(motor.error().message.find("class/pwm/pwmchip7") != std::string::npos);
}

TEST_CASE("PwmMotor: the duty follows the torque; disabled, the channel is at zero duty, still enabled", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotor motor = open_or_fail(config_for(tree));
  motor.command({0.3, true});
  CHECK(tree.read("duty_cycle") == "15000");
  CHECK(tree.read("enable") == "1");
  CHECK(motor.stats().duty_ns == 15'000);
  motor.command({1.5, true});  // clamped at max_duty 0.9
  CHECK(tree.read("duty_cycle") == "45000");
  motor.command({0.005, true});  // inside the deadband: no torque, still enabled
  CHECK(tree.read("duty_cycle") == "0");
  CHECK(tree.read("enable") == "1");
  motor.command({-0.3, true});  // positive_torque_only: never the positive torque
  CHECK(tree.read("duty_cycle") == "0");
  motor.command({0.2, true});
  CHECK(tree.read("duty_cycle") == "10000");
  motor.command({0.2, false});
  CHECK(tree.read("duty_cycle") == "0");
  CHECK(tree.read("enable") == "1");
  CHECK_FALSE(motor.driver_fault());
  CHECK(motor.stats().failed_commands == 0);
}

TEST_CASE("PwmMotor: a value already written is not written again", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotor motor = open_or_fail(config_for(tree));
  motor.command({0.3, true});
  tree.overwrite("duty_cycle", "untouched\n");
  tree.overwrite("enable", "untouched\n");
  motor.command({0.3, true});
  CHECK(tree.read("duty_cycle") == "untouched");
  CHECK(tree.read("enable") == "untouched");
  motor.command({0.4, true});
  CHECK(tree.read("duty_cycle") == "20000");
  CHECK(tree.read("enable") == "untouched");
}

TEST_CASE("PwmMotor: an unchanged duty is written again every kConfirmEvery commands, proving the channel there",
          "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotor motor = open_or_fail(config_for(tree));
  // Up to the next confirming command the value stays as overwritten; that command writes it again.
  motor.command({0.3, true});
  tree.overwrite("duty_cycle", "untouched\n");
  unsigned rewritten_after = 0;
  for (unsigned i = 1; i <= PwmMotor::kConfirmEvery && rewritten_after == 0; ++i) {
    motor.command({0.3, true});
    if (tree.read("duty_cycle") == "15000") rewritten_after = i;
  }
  CHECK(rewritten_after >= 1);
  CHECK(rewritten_after <= PwmMotor::kConfirmEvery);
  // And from then on, exactly every kConfirmEvery commands.
  tree.overwrite("duty_cycle", "untouched\n");
  for (unsigned i = 1; i < PwmMotor::kConfirmEvery; ++i) motor.command({0.3, true});
  CHECK(tree.read("duty_cycle") == "untouched");
  motor.command({0.3, true});
  CHECK(tree.read("duty_cycle") == "15000");
  CHECK(tree.read("enable") == "1");
}

// Another process writing the enable (another instance's --motor-off naming this lever's channel) changes
// nothing this lever writes, so only a read-back sees it. What the lever writes at rest is not assumed here: the
// foreign write is the other value than the one it last wrote.
TEST_CASE(
    "PwmMotor: a foreign write of the enable is seen within kConfirmEvery commands and reported as a driver "
    "fault",
    "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotor motor = open_or_fail(config_for(tree));
  const auto seen_within = [&](const MotorCommand& command) {
    unsigned seen_after = 0;
    for (unsigned i = 1; i <= PwmMotor::kConfirmEvery && seen_after == 0; ++i) {
      motor.command(command);
      if (motor.driver_fault()) seen_after = i;
    }
    return seen_after;
  };
  SECTION("driving: the PWM disabled under it; the motor is released in that command") {
    motor.command({0.3, true});
    REQUIRE(tree.read("enable") == "1");
    tree.overwrite("enable", "0\n");
    const unsigned seen_after = seen_within({0.3, true});
    CHECK(seen_after >= 1);
    CHECK(seen_after <= PwmMotor::kConfirmEvery);
    CHECK_FALSE(motor.stats().enabled);
    CHECK(motor.stats().duty_ns == 0);
    CHECK(tree.read("duty_cycle") == "0");
    CHECK(motor.stats().failed_commands == 1);
  }
  SECTION("at rest: the enable changed under it; the lever's own value is written again") {
    motor.command({0.0, false});
    const std::string own = tree.read("enable");
    tree.overwrite("enable", own == "1" ? "0\n" : "1\n");
    const unsigned seen_after = seen_within({0.0, false});
    CHECK(seen_after >= 1);
    CHECK(seen_after <= PwmMotor::kConfirmEvery);
    CHECK(tree.read("enable") == own);
    CHECK(tree.read("duty_cycle") == "0");
    CHECK(motor.stats().failed_commands == 1);
  }
  // Reported once per foreign write: the core latches MOTOR_DRIVER on it, and a read-back that agrees again
  // reports nothing.
  for (unsigned i = 0; i < 2 * PwmMotor::kConfirmEvery; ++i) motor.command({0.0, false});
  CHECK_FALSE(motor.driver_fault());
}

// In a child: from here on no write may grow a file past `bytes` (the writes fail with EFBIG, partly done), so
// that a PWM attribute the motor holds open refuses values longer than that, as a channel gone does.
bool limit_writes_to(rlim_t bytes) {
  std::signal(SIGXFSZ, SIG_IGN);
  const rlimit limit{bytes, bytes};
  return ::setrlimit(RLIMIT_FSIZE, &limit) == 0;
}

TEST_CASE("PwmMotor: a duty that cannot be written is never driven: the enable is not raised behind it", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = open_or_fail(config_for(tree));
    // Enabled at duty 0 since open(): the next command has nothing to write to enable, before or after its duty.
    tree.overwrite("enable", "untouched\n");
    if (!limit_writes_to(3)) return 80;  // "15000\n" cannot be written, "1\n" and "0\n" can
    motor.command({0.3, true});
    if (tree.read("enable") != "untouched") return 1;
    if (motor.stats().enabled || motor.stats().failed_commands != 1) return 2;
    if (!motor.driver_fault()) return 3;
    return 0;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}

TEST_CASE("PwmMotor: a driven motor whose new duty cannot be written is released in that command", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);  // 15000 ns, enabled
    if (!limit_writes_to(3)) return 80;
    motor.command({0.4, true});  // "20000\n": refused
    if (tree.read("duty_cycle") != "0" || tree.read("enable") != "1") return 1;
    if (motor.stats().enabled || motor.stats().duty_ns != 0) return 2;
    if (!motor.driver_fault()) return 3;
    return 0;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}

TEST_CASE("PwmMotor: a command allocates nothing", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmMotor motor = open_or_fail(config_for(tree));
  lever::test::alloc_count_begin();
  for (int i = 0; i < 100; ++i) {
    motor.command({0.001 * i, i % 10 != 0});
    (void)motor.driver_fault();
  }
  CHECK(lever::test::alloc_count_end() == 0);
}

TEST_CASE("PwmMotor: destruction and reassignment leave the channel at zero duty, enabled", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  PwmSysfsTree other(kChip, kChannel + 1);
  {
    PwmMotor motor = open_or_fail(config_for(tree));
    motor.command({0.3, true});
    REQUIRE_FALSE(stopped(tree));
    PwmMotor moved = std::move(motor);  // the moved-from one must not stop the motor its successor drives
    moved.command({0.4, true});
    REQUIRE(tree.read("duty_cycle") == "20000");

    PwmMotorConfig second = config_for(other);
    second.pwm_channel = kChannel + 1;
    moved = open_or_fail(second);
    CHECK(stopped(tree));
    moved.command({0.1, true});
    REQUIRE_FALSE(stopped(other));
  }
  CHECK(stopped(other));
}

TEST_CASE("PwmMotor: the emergency stop zeroes every open motor at once and latches", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);
    PwmMotor::emergency_stop_all();
    if (!stopped(tree)) return 1;
    if (!motor.driver_fault()) return 2;
    motor.command({0.5, true});  // latched: still off
    if (!stopped(tree)) return 3;
    return 0;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(stopped(tree));
}

// A crash handler's stop on one thread while the loop's thread is in the middle of a command (a multicore board):
// no write of the command may land after the stop's, since the process may die right after its handler's stop
// and nothing would write again. The loop's thread is held inside its write of the duty (a pause in pwrite,
// pwrite_pause.hpp) while the other thread stops every motor: the stop must return only once that write is done
// and with the motor stopped. In a child: the stop latches for the process.
TEST_CASE("PwmMotor: a loop thread in the middle of a command cannot undo the emergency stop", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);
    motor.command({0.0, false});
    lever::test::pause_next_pwrite_of("15000\n", std::chrono::milliseconds(30));
    std::thread loop([&] {
      motor.command({0.3, true});  // the duty: held there
      while (!motor.driver_fault()) motor.command({0.3, true});
    });
    while (!lever::test::pwrite_paused()) std::this_thread::yield();
    PwmMotor::emergency_stop_all();
    const bool write_done_on_return = lever::test::pwrite_resumed();
    const bool stopped_on_return = stopped(tree);
    loop.join();
    if (!write_done_on_return) return 1;
    if (!stopped_on_return) return 2;
    return stopped(tree) ? 0 : 3;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(stopped(tree));
}

// The same stop from a signal handler on the loop's own thread, which cannot wait for the command it interrupted:
// the command, its writes done, finds the latch and stops the motor again.
TEST_CASE("PwmMotor: a command interrupted by the emergency stop on its own thread stops the motor at its end",
          "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);
    motor.command({0.0, false});
    lever::test::pause_next_pwrite_of("15000\n", std::chrono::milliseconds(0), [] { PwmMotor::emergency_stop_all(); });
    motor.command({0.3, true});
    if (!lever::test::pwrite_resumed()) return 1;
    return stopped(tree) ? 0 : 2;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(stopped(tree));
}

TEST_CASE("PwmMotor: SIGINT and SIGTERM stop the motor in the handler; a second one ends the process", "[motor]") {
  const int signal_number = GENERATE(SIGINT, SIGTERM);
  CAPTURE(signal_number);
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    if (!lever::board::install_motor_stop_signal_handlers()) return 80;
    PwmMotor motor = driving_motor(tree);
    ::raise(signal_number);
    if (lever::board::stop_signal_received() != signal_number) return 1;
    // The handler alone, no destructor: it must have stopped the motor by itself.
    if (!stopped(tree)) return 2;
    ::raise(signal_number);
    return 3;  // the second signal should have ended the process
  });
  REQUIRE(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == signal_number);
  CHECK(stopped(tree));
}

TEST_CASE("PwmMotor: a normal exit, exit() or a return from main, with the motor still open stops it", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    PwmMotor motor = driving_motor(tree);
    std::exit(0);  // what a return from main ends in; this motor's destructor never runs
    return 1;
  });
  REQUIRE(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(stopped(tree));
}

TEST_CASE("PwmMotor: abort() (so std::terminate) stops the motor before the process dies", "[motor]") {
  PwmSysfsTree tree(kChip, kChannel);
  const int status = wait_status_of_child([&] {
    if (!lever::board::install_motor_stop_signal_handlers()) return 80;
    PwmMotor motor = driving_motor(tree);
    std::abort();
    return 1;
  });
  REQUIRE(WIFSIGNALED(status));
  CHECK(WTERMSIG(status) == SIGABRT);
  CHECK(stopped(tree));
}
