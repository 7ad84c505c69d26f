#pragma once
// One lever's controller and hardware at its site, as lever-hil run steps them (its mechanics are in the World).
// The firmware can be rebooted: it is rebuilt from its power-up state on the same hardware, with its own tick
// counting from 1 again.
#include <cmath>
#include <cstdint>
#include <optional>

#include "lever/fw/lever_config.hpp"
#include "lever/hil/can_bus.hpp"
#include "lever/hil/sim_hal.hpp"
#include "lever/hil/strain_gauge_model.hpp"

namespace lever::hil {

template <typename LeverT>
struct LeverSite {
  LeverSite(const fw::LeverConfig& fw_config, double angle, const StrainGaugeParams& gauge, std::uint64_t seed,
            CanBus& bus, const Nanos& now, Nanos tx_delay)
      : hal(fw_config.counts_per_rev, angle, gauge, seed), config(fw_config) {
    hal.can_ = {&bus, bus.add_node(), &now, tx_delay};
    boot(1);
  }
  SimHal hal;
  fw::LeverConfig config;
  std::optional<LeverT> lever;
  fw::Tick boot_tick = 0;  // the simulation tick before the firmware's tick 1
  bool down = false;       // rebooting: silent, motor disabled (the driver's enable line defaults to off)
  bool skip = false;       // tick-late: not stepped, the motor keeps its last command
  std::uint64_t rearms_sent = 0;
  std::uint64_t rearms_at_fault = 0;
  fw::LeverState previous_state = fw::LeverState::init;

  void boot(fw::Tick tick) {
    fw::EncoderEdge discard[64];
    while (hal.encoder_.drain_edges(discard, 64).count > 0) {
    }  // the kernel's event queue does not survive a reboot
    lever.emplace(hal, config);
    boot_tick = tick - 1;
    hal.gauge_.set_clock_offset(boot_tick);  // a board's driver stamps readings on the firmware's clock
    down = false;
  }
  void go_down() {
    down = true;
    hal.motor_.last = {};
  }
  void step(fw::Tick tick) {
    if (!down && !skip) lever->step(tick - boot_tick);
  }
  // The tick's halves when both levers run in one controller (fw::Lever::sample, act).
  void sample(fw::Tick tick) {
    if (!down && !skip) lever->sample(tick - boot_tick);
  }
  void act(fw::Tick tick) {
    if (!down && !skip) lever->act(tick - boot_tick);
  }
  fw::LeverState state() const { return lever->supervisor().state(); }
  double torque() const { return hal.motor_.last.enable ? hal.motor_.last.torque_nm : 0.0; }
  bool needs_homing() const {
    const auto s = state();
    return !lever->position().valid() && (s == fw::LeverState::disarmed || s == fw::LeverState::fault);
  }
  bool needs_arming() const {
    const auto s = state();
    return lever->position().valid() && (s == fw::LeverState::disarmed || s == fw::LeverState::fault);
  }
  // Its safe behaviour in force: an HSI's motor off, a TOP holding with no more than its safe hold torque.
  bool safe_now() const {
    const SimMotor& motor = hal.motor_;
    if constexpr (!LeverT::role_type::kHoldsOnFault) {
      return !motor.last.enable || motor.last.torque_nm == 0.0;
    } else {
      return std::fabs(motor.last.torque_nm) <= lever->config().safe_hold_torque_nm;
    }
  }
};

}  // namespace lever::hil
