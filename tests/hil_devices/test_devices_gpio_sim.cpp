// The HIL's encoder lines and motor readback on a real kernel GPIO stack: gpio-sim chips in the kernel rig's
// guest, read and driven by the board layer's own GpioEncoder and PwmMotor. Run by tests/kernel/hil_devices.sh, which
// makes two chips and sets LEVER_ENC_CHIP (lines 0 "enc-a", 1 "enc-b", 2 "enc-z") and LEVER_MOT_CHIP (lines
// 0 "mot-en", 1 "mot-dir", 2 "mot-fault"), each the chip's label. The guest's clock is emulated and slow: the
// tests assert what arrives, never how fast, and wait generously.
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <array>
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include "lever/board/gpio_encoder.hpp"
#include "lever/board/pwm_motor.hpp"
#include "lever/hil/devices/encoder_lines.hpp"
#include "lever/hil/devices/motor_readback.hpp"

using lever::board::GpioEncoder;
using lever::board::GpioEncoderConfig;
using lever::board::LineRef;
using lever::board::MotorLineConfig;
using lever::board::PwmMotor;
using lever::board::PwmMotorConfig;
using lever::fw::AbState;
using lever::fw::EncoderEdge;
using lever::hil::devices::EncoderLines;
using lever::hil::devices::EncoderLinesOptions;
using lever::hil::devices::MotorReadback;
using lever::hil::devices::ReleasedLines;

namespace {

std::string env(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') FAIL(name << " is not set: run this through tests/kernel/hil_devices.sh");
  return v;
}

template <typename T>
T opened(lever::board::Result<T> result) {
  if (!result) FAIL(result.error().message);
  return std::move(result).value();
}

// The test's own decoder, as in test_gpio_sim.cpp: Gray order 00 01 11 10 counts up; a jump of two states is
// illegal and counts nothing.
class Decoder {
 public:
  explicit Decoder(AbState start) : state_(start) {}
  void feed(AbState levels) {
    static constexpr int kIllegal = 9;
    static constexpr int table[4][4] = {
        {0, +1, -1, kIllegal}, {-1, 0, kIllegal, +1}, {+1, kIllegal, 0, -1}, {kIllegal, -1, +1, 0}};
    const int step = table[state_][levels];
    if (step == kIllegal) {
      ++illegal_;
    } else {
      count_ += step;
    }
    state_ = levels;
  }
  std::int64_t count() const { return count_; }
  std::uint64_t illegal() const { return illegal_; }

 private:
  AbState state_;
  std::int64_t count_ = 0;
  std::uint64_t illegal_ = 0;
};

// The board's side: the real encoder, drained every millisecond as lever-fw's loop does, and decoded.
class Reader {
 public:
  explicit Reader(const GpioEncoderConfig& config)
      : encoder_(opened(GpioEncoder::open(config))), decoder_(encoder_.levels()) {}

  void drain() {
    std::array<EncoderEdge, 256> buffer{};
    const auto d = encoder_.drain_edges(buffer.data(), buffer.size());
    lost_ += d.lost;
    for (std::size_t i = 0; i < d.count; ++i) {
      if (buffer[i].index) {
        index_at_.push_back(decoder_.count());
      } else {
        decoder_.feed(buffer[i].levels);
      }
    }
  }

  // Drains each millisecond for `ticks` ms, calling `world(tick)` first each time.
  template <typename World>
  void run(int ticks, World world) {
    timespec next{};
    ::clock_gettime(CLOCK_MONOTONIC, &next);
    for (int tick = 0; tick < ticks; ++tick) {
      world(tick);
      drain();
      next.tv_nsec += 1'000'000;
      if (next.tv_nsec >= 1'000'000'000) {
        next.tv_nsec -= 1'000'000'000;
        ++next.tv_sec;
      }
      ::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next, nullptr);
    }
  }

  // Drains until the lines have reached `target` and the decoder has seen them there, or 60 s pass.
  bool settle(const EncoderLines& lines, std::int64_t target) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
      const bool arrived = lines.stats().count == target;
      run(20, [](int) {});
      if (arrived && decoder_.count() == target) return true;
    }
    return false;
  }

  std::int64_t count() const { return decoder_.count(); }
  std::uint64_t illegal() const { return decoder_.illegal(); }
  std::uint64_t lost() const { return lost_; }
  const std::vector<std::int64_t>& index_at() const { return index_at_; }
  const GpioEncoder& encoder() const { return encoder_; }

 private:
  GpioEncoder encoder_;
  Decoder decoder_;
  std::uint64_t lost_ = 0;
  std::vector<std::int64_t> index_at_;
};

GpioEncoderConfig encoder_config(bool active_low) {
  GpioEncoderConfig c;
  c.chip = env("LEVER_ENC_CHIP");
  c.line_a = LineRef::name("enc-a");
  c.line_b = LineRef::name("enc-b");
  c.line_z = LineRef::name("enc-z");
  c.active_low = active_low;
  return c;
}

// The guest writes sysfs slowly; the board's FIFOs hold 16 edges a line, so stay well within a drain's reach.
constexpr double kRate = 2000;

}  // namespace

TEST_CASE("encoder lines: forward, back, a reversal and a 2000-count move arrive exactly, index at its count") {
  const bool active_low = GENERATE(false, true);
  CAPTURE(active_low);
  const GpioEncoderConfig config = encoder_config(active_low);
  EncoderLines lines = opened(EncoderLines::open(config, EncoderLinesOptions{kRate, 100}));
  INFO(lines.description());
  Reader reader(config);

  lines.set_count(150);  // forward across the index
  REQUIRE(reader.settle(lines, 150));
  CHECK(reader.index_at() == std::vector<std::int64_t>{100});

  lines.set_count(-40);  // back across it, and across zero
  REQUIRE(reader.settle(lines, -40));
  CHECK(reader.index_at() == std::vector<std::int64_t>{100, 100});

  // A reversal before the lines get there: the world turns round while they run behind.
  reader.run(10, [&](int tick) { lines.set_count(-40 + 5 * (tick + 1)); });
  lines.set_count(-60);
  REQUIRE(reader.settle(lines, -60));

  // 2000 counts as the world would give them, a tick at a time, faster than the rate: the lines run behind.
  reader.run(100, [&](int tick) { lines.set_count(-60 + 20 * (tick + 1)); });
  REQUIRE(reader.settle(lines, 1940));
  const auto stats = lines.stats();
  CHECK(stats.count == 1940);
  CHECK(stats.max_backlog > 20);
  CHECK(stats.write_errors == 0);
  CHECK(reader.index_at() == std::vector<std::int64_t>{100, 100, 100});
  CHECK(stats.index_pulses == 3);
  CHECK(reader.illegal() == 0);
  CHECK(reader.lost() == 0);
  CHECK(reader.encoder().stats().lost == 0);
  // Every edge the lines wrote reached the board: one event each (the index events apart).
  CHECK(reader.encoder().stats().edges == stats.edges);
}

namespace {

PwmMotorConfig motor_config(const std::string& root, bool active_low) {
  PwmMotorConfig c;
  c.sysfs_root = root;
  c.torque_constant_nm_per_a = 0.05;
  c.gear_ratio = 10.0;
  c.full_scale_current_a = 2.0;  // 1 Nm at full duty
  c.max_duty = 1.0;
  const std::string chip = env("LEVER_MOT_CHIP");
  c.enable_line = MotorLineConfig{chip, LineRef::name("mot-en"), active_low};
  c.direction_line = MotorLineConfig{chip, LineRef::name("mot-dir"), active_low};
  c.fault_line = MotorLineConfig{chip, LineRef::name("mot-fault"), active_low};
  return c;
}

class TempDir {
 public:
  TempDir() {
    std::string pattern = "/tmp/lever-motor-XXXXXX";
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

}  // namespace

TEST_CASE("motor readback: sign from the direction line, enable from the line and the PWM, the fault seen") {
  const bool active_low = GENERATE(false, true);
  CAPTURE(active_low);
  TempDir dir;
  const PwmMotorConfig config = motor_config(dir.path(), active_low);
  MotorReadback readback = opened(MotorReadback::open(config));
  INFO(readback.description());
  CHECK_FALSE(readback.read().enabled);  // the enable line's pull holds the driver off before anyone drives it
  {
    PwmMotor motor = opened(PwmMotor::open(config));
    constexpr double kQuantum = 1.0 / 50'000;

    motor.command({-0.4, true});
    auto r = readback.read();
    CHECK(r.enabled);
    CHECK(r.negative);
    CHECK(std::abs(r.torque_nm - -0.4) <= kQuantum);

    motor.command({0.3, true});
    r = readback.read();
    CHECK_FALSE(r.negative);
    CHECK(std::abs(r.torque_nm - 0.3) <= kQuantum);

    motor.command({-0.25, false});
    r = readback.read();
    CHECK_FALSE(r.enabled);
    CHECK(r.torque_nm == 0.0);

    CHECK_FALSE(motor.driver_fault());
    REQUIRE(readback.set_fault(true));
    CHECK(motor.driver_fault());
    REQUIRE(readback.set_fault(false));
    CHECK_FALSE(motor.driver_fault());

    motor.command({-0.6, true});
    CHECK(std::abs(readback.read().torque_nm - -0.6) <= kQuantum);
    CHECK(readback.read_errors() == 0);
  }
  // The motor's destructor stops it: the PWM at duty 0, enabled, its pin inactive. (Its enable line's low level,
  // driven for less than the time between two reads before it is released, is not seen: the world holds the line
  // where it last saw it, asserted; so the PWM's inactive level alone is what stops the driver here.)
  CHECK(readback.read().duty == 0.0);
  CHECK(readback.read().torque_nm == 0.0);
}

TEST_CASE("motor readback: the enable line alone decides when the PWM runs") {
  TempDir dir;
  const PwmMotorConfig config = motor_config(dir.path(), false);
  MotorReadback readback = opened(MotorReadback::open(config));
  PwmMotor motor = opened(PwmMotor::open(config));
  motor.command({0.5, true});
  REQUIRE(readback.read().enabled);
  // Another program's PWM half (a board script, a test) enabling the channel does not enable the driver.
  motor.command({0.5, false});
  std::ofstream(dir.path() + "/class/pwm/pwmchip0/pwm0/enable") << "1\n";
  std::ofstream(dir.path() + "/class/pwm/pwmchip0/pwm0/duty_cycle") << "25000\n";
  CHECK_FALSE(readback.read().enabled);
  CHECK(readback.read().torque_nm == 0.0);
}

// A lever-fw killed (SIGKILL) while it drives: nothing of it runs, and the kernel releases its lines. A real GPIO
// controller keeps the enable line where it was, so the motor runs on until something else stops it; the world
// must show that (ReleasedLines::hold), or a test of that something passes without it. With ::pull the line
// falls to the board's resistor, as gpio-sim on its own does.
TEST_CASE("motor readback: a line released by a killed program keeps its level, or falls to its pull") {
  const auto released = GENERATE(ReleasedLines::hold, ReleasedLines::pull);
  CAPTURE(released == ReleasedLines::hold ? "hold" : "pull");
  TempDir dir;
  const PwmMotorConfig config = motor_config(dir.path(), false);
  MotorReadback readback = opened(MotorReadback::open(config, released));
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t child = ::fork();
  REQUIRE(child >= 0);
  if (child == 0) {
    auto motor = PwmMotor::open(config);
    if (!motor) ::_exit(90);
    motor.value().command({-0.4, true});
    (void)!::write(ready[1], "x", 1);
    for (;;) ::pause();
  }
  ::close(ready[1]);
  char byte = 0;
  REQUIRE(::read(ready[0], &byte, 1) == 1);
  ::close(ready[0]);
  auto r = readback.read();  // the world's tick while the program drives
  REQUIRE(r.enabled);
  REQUIRE(r.negative);
  ::kill(child, SIGKILL);
  int status = 0;
  REQUIRE(::waitpid(child, &status, 0) == child);
  r = readback.read();
  if (released == ReleasedLines::hold) {
    CHECK(r.enabled);
    CHECK(r.negative);
    CHECK(std::abs(r.torque_nm - -0.4) <= 1.0 / 50'000);
  } else {
    CHECK_FALSE(r.enabled);
    CHECK(r.torque_nm == 0.0);
  }
  // What stops it then: another process opening the motor (lever-fw --motor-off), whose stop the world sees.
  {
    PwmMotor off = opened(PwmMotor::open(config));
    CHECK_FALSE(readback.read().enabled);
  }
  CHECK_FALSE(readback.read().enabled);
  CHECK(readback.read_errors() == 0);
}
