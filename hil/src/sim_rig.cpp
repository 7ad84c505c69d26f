#include "sim_rig.hpp"

#include <stdexcept>

namespace lever::hil {
namespace {

constexpr Nanos kTick = 1'000'000;
constexpr fw::Tick kPowerUpLimit = 30'000;  // homing and arming must be done by then

const SimConfig& checked(const SimConfig& config) {
  if (!(config.bridge_latency_us >= 1.0))
    throw std::invalid_argument("HIL: a bridge takes at least 1 us from receiving a frame to sending it");
  return config;
}

WorldParams world_params(const SimConfig& c) {
  return {c.scenario, c.hsi_plant, c.top_plant, c.wall, c.operator_params, c.substeps, c.seed * 4 + 5};
}

}  // namespace

// The order of the parts is the order of the nodes on the buses: each lever, the host, the bridges.
SimRig::SimRig(const SimConfig& config)
    : config_(checked(config)),
      angles_(power_up_angles(config)),
      transport_(config),
      levers_(config, angles_, transport_, now_),
      world_(world_params(config), angles_.hsi, angles_.top),
      host_(transport_.hsi_bus(), config.hsi_firmware.pair, now_),
      faults_(config.faults, config.rearm_after_s),
      metrics_(config),
      fault_watch_(config.faults),
      trace_(config) {
  transport_.add_bridges();
}

void SimRig::step(fw::Tick tick, double t) {
  now_ = static_cast<Nanos>(tick) * kTick;
  // The operator takes the handle once both levers are armed, and lets go while the HSI homes.
  world_.set_hand_on(levers_.hsi().state() != fw::LeverState::homing, tick);
  // Physics over the last millisecond, with the motor commands of the last step.
  world_.advance(levers_.hsi().hal.motor_.last, levers_.top().hal.motor_.last, [&] { levers_.track(world_); });
  forces_.contact = world_.contact_force();
  forces_.hand = world_.hand_force();
  const bool faults_hold = faults_.step(t, tick, start_ != 0, transport_, levers_);
  levers_.sense(forces_.contact, forces_.hand, tick);
  transport_.step(now_);
  host_.step(tick, start_, faults_hold, levers_);
  world_.update_operator(tick, forces_.hand);
  if (config_.topology == Topology::one_controller) {
    levers_.sample(tick);
    transport_.hand_over(now_);
    levers_.act(tick);
  } else {
    levers_.step(tick);
  }
}

fw::Tick SimRig::power_up() {
  for (fw::Tick tick = 1;; ++tick) {
    if (tick > kPowerUpLimit)
      throw std::runtime_error("HIL: the levers were not homed and armed within 30 s of power-up");
    step(tick, -1e-3);
    if (levers_.both_armed()) {
      start_ = tick;
      world_.start_operator(tick);
    }
    observe(-1e-3, tick);
    if (start_ != 0) return start_;
  }
}

void SimRig::scenario_step(fw::Tick tick) {
  const double t = static_cast<double>(tick - start_) * 1e-3;
  step(tick, t);
  forces_.measured = levers_.top().lever->telemetry().force_n.value_or(0.0);
  forces_.displayed = levers_.hsi().lever->telemetry().remote.value_or(0.0);
  metrics_.step(tick, forces_, world_, levers_);
  fault_watch_.step(t, levers_);
  trace_.step(t, forces_, world_, levers_);
  observe(t, tick);
}

void SimRig::finish(SimResult& result) {
  metrics_.finish(result, levers_);
  transport_.finish(result);
  fault_watch_.finish(result);
  trace_.finish(result);
}

}  // namespace lever::hil
