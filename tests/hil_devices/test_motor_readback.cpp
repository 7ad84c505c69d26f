// MotorReadback with the board's own PWM motor (board::PwmMotor, same config) writing the tree it makes: no
// GPIO lines, so no gpio-sim; the lines are tested in the guest (test_devices_gpio_sim.cpp).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "lever/board/pwm_motor.hpp"
#include "lever/hil/devices/motor_readback.hpp"

using lever::board::PwmMotor;
using lever::board::PwmMotorConfig;
using lever::hil::devices::MotorReadback;

namespace {

class TempDir {
 public:
  TempDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/lever-motor-XXXXXX";
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// 1.2 Nm at full duty, a period whose quantum is visible (12 uNm a nanosecond).
PwmMotorConfig config_in(const std::string& root) {
  PwmMotorConfig c;
  c.sysfs_root = root + "/sys";
  c.pwm_chip = 2;
  c.pwm_channel = 1;
  c.period_ns = 100'000;
  c.torque_constant_nm_per_a = 0.04;
  c.gear_ratio = 10.0;
  c.full_scale_current_a = 3.0;
  c.max_duty = 1.0;
  c.positive_torque_only = true;
  return c;
}

constexpr double kFullDutyNm = 0.04 * 10.0 * 3.0;

template <typename T>
T opened(lever::board::Result<T> result) {
  if (!result) FAIL(result.error().message);
  return std::move(result).value();
}

}  // namespace

TEST_CASE("the torque the board's motor commands is read back within one duty quantum") {
  TempDir dir;
  PwmMotorConfig config = config_in(dir.path());
  config.pwm_inversed = GENERATE(false, true);
  CAPTURE(config.pwm_inversed);
  MotorReadback readback = opened(MotorReadback::open(config));
  PwmMotor motor = opened(PwmMotor::open(config));
  const double quantum = kFullDutyNm / config.period_ns;

  CHECK(readback.read().torque_nm == 0.0);
  CHECK(readback.read().duty == 0.0);  // open() leaves the PWM enabled at duty 0: the driver's input inactive
  for (const double torque : {0.001, 0.1, 0.3333, 0.6, 1.1, 1.2}) {
    CAPTURE(torque);
    motor.command({torque, true});
    const auto reading = readback.read();
    CHECK(reading.enabled);
    CHECK_FALSE(reading.negative);
    CHECK(std::abs(reading.torque_nm - torque) <= quantum);
    CHECK(reading.duty == Approx(torque / kFullDutyNm).margin(1.0 / config.period_ns));
  }
  motor.command({0.5, false});
  CHECK(readback.read().torque_nm == 0.0);
  CHECK(readback.read().duty == 0.0);
  motor.command({-0.5, true});  // positive_torque_only: nothing
  CHECK(readback.read().torque_nm == 0.0);
  motor.command({0.7, true});
  CHECK(std::abs(readback.read().torque_nm - 0.7) <= quantum);
  CHECK(readback.read_errors() == 0);
  CHECK(readback.description() == "pwmchip2/pwm1 under " + config.sysfs_root);
}

TEST_CASE("a polarity the board does not undo reads as the complement of the duty") {
  TempDir dir;
  PwmMotorConfig config = config_in(dir.path());
  MotorReadback readback = opened(MotorReadback::open(config));
  PwmMotorConfig wrong = config;
  wrong.pwm_inversed = true;  // the program thinks the board inverts; the readback's board does not
  PwmMotor motor = opened(PwmMotor::open(wrong));
  motor.command({0.3, true});
  CHECK(readback.read().torque_nm == Approx(kFullDutyNm - 0.3).margin(kFullDutyNm / config.period_ns));
}

// The kernel leaves a disabled PWM's output undefined; the tree's pin does the worst a controller does (stops in
// the high part of its period), so a program that takes "enable 0" for off is seen driving the motor.
TEST_CASE("a PWM disabled while its pin was high holds it high: torque at the driver, unless the board inverts it") {
  TempDir dir;
  PwmMotorConfig config = config_in(dir.path());
  config.pwm_inversed = GENERATE(false, true);
  CAPTURE(config.pwm_inversed);
  MotorReadback readback = opened(MotorReadback::open(config));
  PwmMotor motor = opened(PwmMotor::open(config));
  const std::string channel = config.sysfs_root + "/class/pwm/pwmchip2/pwm1";
  motor.command({0.3, true});
  REQUIRE(readback.read().torque_nm == Approx(0.3).margin(kFullDutyNm / config.period_ns));
  std::ofstream(channel + "/enable") << "0\n";  // disabled at duty 0.3: the pin was high for part of a period
  // Normal polarity: held high, full duty at the driver. Inversed: the pin was high too (for the other 0.7), held
  // high, and the board turns that into none.
  CHECK(readback.read().torque_nm == Approx(config.pwm_inversed ? 0.0 : kFullDutyNm));
  CHECK(readback.read().duty == Approx(config.pwm_inversed ? 0.0 : 1.0));
}

TEST_CASE("the tree is kept across a readback's restart, so a running program stays connected") {
  TempDir dir;
  const PwmMotorConfig config = config_in(dir.path());
  std::optional<MotorReadback> readback(opened(MotorReadback::open(config)));
  PwmMotor motor = opened(PwmMotor::open(config));
  motor.command({0.6, true});
  readback.reset();
  readback.emplace(opened(MotorReadback::open(config)));
  CHECK(readback->read().torque_nm == Approx(0.6).margin(1e-4));
  motor.command({0.2, true});
  CHECK(readback->read().torque_nm == Approx(0.2).margin(1e-4));
}

TEST_CASE("the readback refuses the real sysfs and a tree it cannot trust") {
  TempDir dir;
  for (const std::string root : {"/sys", "/sys/", "/sys/class", "/tmp/../sys", "/sys/../sys/kernel"}) {
    CAPTURE(root);
    PwmMotorConfig config = config_in(dir.path());
    config.sysfs_root = root;
    const auto refused = MotorReadback::open(config);
    REQUIRE_FALSE(refused.ok());
    CHECK(refused.error().message.find("the real sysfs") != std::string::npos);
  }
  PwmMotorConfig config = config_in(dir.path());
  std::filesystem::create_directories(config.sysfs_root + "/class/pwm/pwmchip2/pwm1/enable");
  const auto odd = MotorReadback::open(config);
  REQUIRE_FALSE(odd.ok());
  CHECK(odd.error().message.find("pwm1/enable exists and is not a regular file") != std::string::npos);

  PwmMotorConfig bad = config_in(dir.path());
  bad.full_scale_current_a = 0;
  const auto invalid = MotorReadback::open(bad);
  REQUIRE_FALSE(invalid.ok());
  CHECK(invalid.error().message.find("motor readback: full_scale_current_a") == 0);
}

TEST_CASE("lines on a chip that is not there: an error naming the field") {
  TempDir dir;
  PwmMotorConfig config = config_in(dir.path());
  config.fault_line = lever::board::MotorLineConfig{"no-such-chip", lever::board::LineRef::name("f"), false};
  const auto refused = MotorReadback::open(config);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find("motor readback: fault_line: cannot open chip \"no-such-chip\"") == 0);
}
