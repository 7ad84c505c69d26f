#pragma once
// Two levers on one in-memory CAN bus, each with a trivial plant: an HSI held by a spring-damper "hand" that
// follows a target, and a TOP that meets a stiff wall. Small on purpose: the real simulator is lever::hil.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "fake_hal.hpp"
#include "lever/fw/lever.hpp"

namespace lever::test {

struct LeverPlant {
  double inertia = 2e-3;  // kg m^2
  double viscous = 0.02;  // N m s/rad
  double angle = 0.0;
  double speed = 0.0;
  void advance(double torque, double dt) {
    speed += (torque - viscous * speed) / inertia * dt;
    angle += speed * dt;  // semi-implicit: stable with stiff contact
  }
  std::int32_t counts(double counts_per_rev) const {
    return static_cast<std::int32_t>(std::floor(angle / (2.0 * std::numbers::pi / counts_per_rev)));
  }
};

// The rig's levers have absolute encoders (no homing) unless a test says otherwise.
inline fw::LeverConfig rig_config(protocol::Role role) {
  fw::LeverConfig c;
  c.role = role;
  c.use_force_sensor = role == protocol::Role::top;
  c.homing.method = fw::HomingMethod::absolute;
  return c;
}

class PairRig {
 public:
  PairRig(const fw::LeverConfig& hsi_config = rig_config(protocol::Role::hsi),
          const fw::LeverConfig& top_config = rig_config(protocol::Role::top))
      : hsi_hal(bus), top_hal(bus), hsi(hsi_hal, hsi_config), top(top_hal, top_config) {
    top_hal.force_.reading = fw::ForceReading{0, 0, false};
  }

  // The operator's hand: a spring-damper pulling the HSI toward `hand_target`.
  double hand_target = 0.0;
  double hand_stiffness = 3.0;  // N m/rad
  double hand_damping = 0.15;   // N m s/rad
  double wall_angle = 0.3;      // rad
  double wall_stiffness = 200.0;
  double arm = 0.1;  // m

  double wall_torque() const {
    const double penetration = top_plant.angle - wall_angle;
    return penetration > 0 ? std::max(0.0, wall_stiffness * penetration + 0.4 * top_plant.speed) : 0.0;
  }
  double contact_force() const { return wall_torque() / arm; }

  void tick() {
    constexpr int kSubsteps = 10;
    for (int i = 0; i < kSubsteps; ++i) {
      const double hand = hand_stiffness * (hand_target - hsi_plant.angle) - hand_damping * hsi_plant.speed;
      hsi_plant.advance(hand + motor_torque(hsi_hal.motor_), 1e-4);
      top_plant.advance(motor_torque(top_hal.motor_) - wall_torque(), 1e-4);
    }
    hsi_hal.encoder_.counts = hsi_plant.counts(hsi.config().counts_per_rev);
    top_hal.encoder_.counts = top_plant.counts(top.config().counts_per_rev);
    if (gauge_alive) {
      const auto& g = top.config().gauge;
      const double code = std::round(contact_force() / g.newton_per_count + g.offset_counts);
      top_hal.force_.reading = fw::ForceReading{std::clamp(code, -32768.0, 32767.0), now, false};
    }
    if (one_controller) {  // both levers in one controller: both sample, then both act
      hsi.sample(now);
      top.sample(now);
      hsi.act(now);
      top.act(now);
    } else {
      hsi.step(now);
      top.step(now);
    }
    ++now;
  }
  void run(fw::Tick ticks) {
    for (fw::Tick i = 0; i < ticks; ++i) tick();
  }

  void command(protocol::Opcode op, bool to_hsi = true, bool to_top = true) {
    protocol::CommandMessage m;
    m.opcode = op;
    m.to_hsi = to_hsi;
    m.to_top = to_top;
    bus.inject(protocol::pack(m, 0));
  }
  // Let heartbeats flow, then arm both levers.
  void boot_and_arm() {
    run(60);
    command(protocol::Opcode::arm);
    run(2);
  }

  CanBus bus;
  FakeHal<> hsi_hal;
  FakeHal<> top_hal;
  fw::HsiLever<FakeHal<>> hsi;
  fw::TopLever<FakeHal<>> top;
  LeverPlant hsi_plant;
  LeverPlant top_plant;
  bool gauge_alive = true;
  bool one_controller = false;  // step the levers' halves (Lever::sample, act) instead of step()
  fw::Tick now = 1;

 private:
  static double motor_torque(const FakeMotor& m) { return m.last.enable ? m.last.torque_nm : 0.0; }
};

}  // namespace lever::test
