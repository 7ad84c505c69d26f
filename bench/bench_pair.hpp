#pragma once
// An armed HSI/TOP pair of the real firmware core on an in-memory HAL, for the benchmarks: CAN frames pass
// through fixed rings between the two, and each lever drives a simple lever plant whose encoder and (TOP) force
// readings the next tick reads. The operator moves the HSI back and forth into the TOP's wall, so both
// directions carry deadband traffic, contact happens, and every code path of step() is exercised.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <numbers>
#include <optional>

#include "lever/fw/lever.hpp"

namespace lever::bench {

// Fixed-capacity CAN queue: no heap in the timed path.
class RingQueue {
 public:
  bool push(const protocol::CanFrame& f) {
    if (count_ == frames_.size()) return false;
    frames_[(head_ + count_++) % frames_.size()] = f;
    return true;
  }
  bool pop(protocol::CanFrame& f) {
    if (count_ == 0) return false;
    f = frames_[head_];
    head_ = (head_ + 1) % frames_.size();
    --count_;
    return true;
  }

 private:
  std::array<protocol::CanFrame, 64> frames_{};
  std::size_t head_ = 0, count_ = 0;
};

struct BenchHal {
  struct Encoder {
    std::int32_t counts = 0;
    std::uint32_t read_counts() const { return static_cast<std::uint32_t>(counts); }
  } encoder_;
  struct Force {
    std::optional<fw::ForceReading> reading;
    std::optional<fw::ForceReading> latest() const { return reading; }
  } force_;
  struct Motor {
    fw::MotorCommand last;
    void command(const fw::MotorCommand& c) { last = c; }
    bool driver_fault() const { return false; }
  } motor_;
  struct Can {
    RingQueue* rx = nullptr;
    RingQueue* tx = nullptr;
    bool receive(protocol::CanFrame& f) { return rx->pop(f); }
    bool send(const protocol::CanFrame& f) { return tx->push(f); }
  } can_;
  Encoder& encoder() { return encoder_; }
  Force& force() { return force_; }
  Motor& motor() { return motor_; }
  Can& can() { return can_; }
};

struct Plant {
  double angle = 0.0, speed = 0.0;
  void advance(double torque) {
    for (int i = 0; i < 10; ++i) {
      speed += (torque - 0.02 * speed) / 2e-3 * 1e-4;
      angle += speed * 1e-4;
    }
  }
};

// The levers refer to the HALs and the HALs to the rings: a pair stays where it was made.
template <typename Hal = BenchHal>
class BenchPair {
 public:
  explicit BenchPair(fw::PassivityMode passivity = fw::PassivityMode::off)
      : hsi(hsi_hal, config(protocol::Role::hsi, passivity)), top(top_hal, config(protocol::Role::top, passivity)) {
    hsi_hal.can_ = {&to_hsi, &to_top};
    top_hal.can_ = {&to_top, &to_hsi};
  }
  BenchPair(const BenchPair&) = delete;
  BenchPair& operator=(const BenchPair&) = delete;

  // What happens between two ticks: the host arms both at tick 80, the plants move under the last torques,
  // and the sensors show where they went. Then step hsi and top with `now`.
  void before_step(fw::Tick now) {
    if (now >= 80 && !arm_sent_) {
      protocol::CommandMessage arm;
      to_hsi.push(protocol::pack(arm, 0));
      to_top.push(protocol::pack(arm, 0));
      arm_sent_ = true;
    }
    const double count = 2.0 * std::numbers::pi / 16384.0;
    const double target = 0.25 + 0.1 * std::sin(2.0 * std::numbers::pi * 0.5 * static_cast<double>(now) * 1e-3);
    const double wall = top_plant.angle > 0.3 ? 200.0 * (top_plant.angle - 0.3) : 0.0;
    hsi_plant.advance(3.0 * (target - hsi_plant.angle) - 0.15 * hsi_plant.speed +
                      (hsi_hal.motor_.last.enable ? hsi_hal.motor_.last.torque_nm : 0.0));
    top_plant.advance((top_hal.motor_.last.enable ? top_hal.motor_.last.torque_nm : 0.0) - wall);
    hsi_hal.encoder_.counts = static_cast<std::int32_t>(std::floor(hsi_plant.angle / count));
    top_hal.encoder_.counts = static_cast<std::int32_t>(std::floor(top_plant.angle / count));
    top_hal.force_.reading =
        fw::ForceReading{static_cast<double>(std::lround(wall / 0.1 / (100.0 / 65536.0))), now, false};
  }

  bool armed() const { return hsi.supervisor().armed() && top.supervisor().armed(); }

  RingQueue to_hsi, to_top;
  Hal hsi_hal, top_hal;
  fw::HsiLever<Hal> hsi;
  fw::TopLever<Hal> top;
  Plant hsi_plant, top_plant;

 private:
  static fw::LeverConfig config(protocol::Role role, fw::PassivityMode passivity) {
    fw::LeverConfig c;
    c.role = role;
    c.passivity.mode = passivity;
    if (role == protocol::Role::hsi) c.use_force_sensor = false;
    c.homing.method = fw::HomingMethod::absolute;  // the benchmarks time the armed pair, not homing
    return c;
  }
  bool arm_sent_ = false;
};

}  // namespace lever::bench
