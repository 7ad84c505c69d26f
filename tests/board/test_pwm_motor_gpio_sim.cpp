// The PWM motor's GPIO lines against the real kernel GPIO stack: a gpio-sim chip in the kernel rig's guest.
// Run by tests/kernel/pwm_motor_gpio.sh, which makes the chip and sets:
//   LEVER_GPIO_CHIP   the chip's name (gpiochipN)      LEVER_GPIO_LABEL  its label ("motor")
//   LEVER_GPIO_SYSFS  its sysfs directory: sim_gpioN/value shows a line's level, sim_gpioN/pull drives an input
// The chip's lines: 0 "mot-en", 1 "mot-dir", 2 "mot-fault". The PWM side is a temporary sysfs tree, as in
// test_pwm_motor.cpp.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <string>

#include "fork_child.hpp"
#include "lever/board/motor_stop_signals.hpp"
#include "lever/board/pwm_motor.hpp"
#include "pwm_sysfs_tree.hpp"

using lever::board::LineRef;
using lever::board::MotorLineConfig;
using lever::board::PwmMotor;
using lever::board::PwmMotorConfig;
using lever::test::PwmSysfsTree;

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') FAIL(name << " is not set: run this through tests/kernel/pwm_motor_gpio.sh");
  return v;
}

// The physical level of line `offset` as the simulated chip holds it.
int level(unsigned offset) {
  std::ifstream in(env("LEVER_GPIO_SYSFS") + "/sim_gpio" + std::to_string(offset) + "/value");
  int v = -1;
  in >> v;
  return v;
}

void pull(unsigned offset, bool up) {
  std::ofstream out(env("LEVER_GPIO_SYSFS") + "/sim_gpio" + std::to_string(offset) + "/pull");
  out << (up ? "pull-up" : "pull-down");
}

constexpr unsigned kEnable = 0, kDirection = 1, kFault = 2;

// 1 Nm at full duty, as on the host; the lines by name on the chip found by its label.
PwmMotorConfig config_for(const PwmSysfsTree& tree) {
  PwmMotorConfig c;
  c.sysfs_root = tree.root();
  c.pwm_chip = 0;
  c.pwm_channel = 0;
  c.torque_constant_nm_per_a = 0.05;
  c.gear_ratio = 10.0;
  c.full_scale_current_a = 2.0;
  const std::string chip = env("LEVER_GPIO_LABEL");
  c.enable_line = MotorLineConfig{chip, LineRef::name("mot-en"), false};
  c.direction_line = MotorLineConfig{chip, LineRef::name("mot-dir"), false};
  c.fault_line = MotorLineConfig{chip, LineRef::name("mot-fault"), false};
  return c;
}

PwmMotor open_or_fail(const PwmMotorConfig& config) {
  auto motor = PwmMotor::open(config);
  if (!motor) FAIL(motor.error().message);
  return std::move(motor).value();
}

}  // namespace

TEST_CASE("enable and direction lines follow the commands; deasserted from the start") {
  PwmSysfsTree tree(0, 0);
  PwmMotor motor = open_or_fail(config_for(tree));
  INFO(motor.description());
  CHECK(level(kEnable) == 0);
  CHECK(level(kDirection) == 0);

  motor.command({0.3, true});
  CHECK(level(kEnable) == 1);
  CHECK(level(kDirection) == 0);
  CHECK(tree.read("duty_cycle") == "15000");

  motor.command({-0.4, true});
  CHECK(level(kEnable) == 1);
  CHECK(level(kDirection) == 1);
  CHECK(tree.read("duty_cycle") == "20000");

  motor.command({-0.4, false});
  CHECK(level(kEnable) == 0);
  CHECK(tree.read("duty_cycle") == "0");
  CHECK(tree.read("enable") == "1");  // at duty 0, the inactive state: the PWM is not disabled

  motor.command({0.0, true});  // zero torque leaves the direction as it was: nothing to drive either way
  CHECK(level(kEnable) == 1);
  CHECK(level(kDirection) == 1);
  motor.command({0.2, true});
  CHECK(level(kDirection) == 0);
  CHECK(motor.stats().failed_commands == 0);
}

TEST_CASE("active-low lines are high while deasserted") {
  PwmSysfsTree tree(0, 0);
  PwmMotorConfig c = config_for(tree);
  c.enable_line->active_low = true;
  c.direction_line->active_low = true;
  PwmMotor motor = open_or_fail(c);
  CHECK(level(kEnable) == 1);
  CHECK(level(kDirection) == 1);
  motor.command({0.3, true});
  CHECK(level(kEnable) == 0);
  CHECK(level(kDirection) == 1);
  motor.command({-0.3, true});
  CHECK(level(kDirection) == 0);
  motor.command({-0.3, false});
  CHECK(level(kEnable) == 1);
}

// The fault line's level comes from its edge events, which the kernel's interrupt thread queues a moment after the
// pull changes: each check waits for the event (a second at most: the rig's guest is not real time).
bool fault_becomes(PwmMotor& motor, bool expected) {
  for (int i = 0; i < 1000; ++i) {
    if (motor.driver_fault() == expected) return true;
    ::usleep(1000);
  }
  return false;
}

TEST_CASE("the driver's fault input follows the line's edges, active-high or active-low") {
  PwmSysfsTree tree(0, 0);
  PwmMotorConfig c = config_for(tree);
  const bool active_low = GENERATE(false, true);
  CAPTURE(active_low);
  c.fault_line->active_low = active_low;
  PwmMotor motor = open_or_fail(c);
  pull(kFault, /*up=*/!active_low);
  CHECK(fault_becomes(motor, true));
  pull(kFault, /*up=*/active_low);
  CHECK(fault_becomes(motor, false));
  pull(kFault, /*up=*/!active_low);
  CHECK(fault_becomes(motor, true));
  pull(kFault, false);
  CHECK(motor.stats().fault_read_errors == 0);
}

TEST_CASE("a fault asserted before the lever started is seen at the first call, with no edge after it") {
  PwmSysfsTree tree(0, 0);
  pull(kFault, true);
  PwmMotor motor = open_or_fail(config_for(tree));
  CHECK(motor.driver_fault());
  ::usleep(20000);
  CHECK(motor.driver_fault());
  pull(kFault, false);
  CHECK(fault_becomes(motor, false));
}

TEST_CASE("more edges than the kernel's event FIFO holds between two calls: the level is still the line's") {
  PwmSysfsTree tree(0, 0);
  PwmMotor motor = open_or_fail(config_for(tree));
  CHECK_FALSE(motor.driver_fault());
  const bool last = GENERATE(false, true);
  CAPTURE(last);
  // 40 changes, 24 more than the FIFO's 16: the kernel drops the newest, which say the level now.
  for (int i = 0; i < 40; ++i) {
    pull(kFault, i % 2 == 0);
    ::usleep(200);  // each change its own interrupt, so each is an event or a drop, never merged
  }
  pull(kFault, last);
  ::usleep(50000);
  CHECK(motor.driver_fault() == last);
  CHECK(motor.stats().fault_read_errors == 0);
  pull(kFault, false);
}

TEST_CASE("lines by offset on a chip named by its path") {
  PwmSysfsTree tree(0, 0);
  PwmMotorConfig c = config_for(tree);
  const std::string path = "/dev/" + env("LEVER_GPIO_CHIP");
  c.enable_line = MotorLineConfig{path, LineRef::offset(kEnable), false};
  c.direction_line = MotorLineConfig{path, LineRef::offset(kDirection), false};
  c.fault_line.reset();
  PwmMotor motor = open_or_fail(c);
  motor.command({-0.3, true});
  CHECK(level(kEnable) == 1);
  CHECK(level(kDirection) == 1);
  CHECK_FALSE(motor.driver_fault());  // no fault line: no fault from it
}

TEST_CASE("a busy or missing line gives an error naming the field, never a motor") {
  PwmSysfsTree tree(0, 0);
  PwmSysfsTree other(0, 0);
  PwmMotor first = open_or_fail(config_for(tree));
  first.command({0.3, true});

  const auto busy = PwmMotor::open(config_for(other));
  REQUIRE_FALSE(busy.ok());
  CHECK(busy.error().message.find("motor enable_line (\"mot-en\" on " + env("LEVER_GPIO_CHIP") + " [motor])") == 0);
  CHECK(busy.error().message.find("used by \"lever-motor\"") != std::string::npos);
  CHECK(level(kEnable) == 1);  // the first motor keeps its line

  PwmMotorConfig missing = config_for(other);
  missing.direction_line->line = LineRef::name("no-such-line");
  missing.enable_line.reset();
  missing.fault_line.reset();
  const auto none = PwmMotor::open(missing);
  REQUIRE_FALSE(none.ok());
  CHECK(none.error().message.find("motor direction_line (\"no-such-line\" on") == 0);
  CHECK(none.error().message.find("no line of that name") != std::string::npos);

  PwmMotorConfig no_chip = config_for(other);
  no_chip.fault_line->chip = "no-such-chip";
  no_chip.enable_line.reset();
  no_chip.direction_line.reset();
  no_chip.positive_torque_only = true;
  const auto chipless = PwmMotor::open(no_chip);
  REQUIRE_FALSE(chipless.ok());
  CHECK(chipless.error().message.find("motor fault_line: cannot open chip \"no-such-chip\"") == 0);
}

TEST_CASE("after a SIGINT the next command drops the enable line, the process still running") {
  PwmSysfsTree tree(0, 0);
  int ready[2], done[2];
  REQUIRE(::pipe(ready) == 0);
  REQUIRE(::pipe(done) == 0);
  std::fflush(nullptr);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::alarm(20);
    if (!lever::board::install_motor_stop_signal_handlers()) ::_exit(80);
    auto motor = PwmMotor::open(config_for(tree));
    if (!motor) ::_exit(81);
    motor.value().command({0.3, true});
    ::raise(SIGINT);
    motor.value().command({0.3, true});  // the loop's next tick, before it sees the stop request
    const char byte = lever::board::stop_signal_received() == SIGINT ? 'y' : 'n';
    if (::write(ready[1], &byte, 1) != 1) ::_exit(82);
    char ignored = 0;
    if (::read(done[0], &ignored, 1) != 1) ::_exit(83);
    ::_exit(0);
  }
  char byte = 0;
  REQUIRE(::read(ready[0], &byte, 1) == 1);
  CHECK(byte == 'y');
  CHECK(level(kEnable) == 0);  // still requested by the child, which drove it low
  CHECK(tree.read("duty_cycle") == "0");
  CHECK(tree.read("enable") == "1");
  REQUIRE(::write(done[1], "x", 1) == 1);
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
}
