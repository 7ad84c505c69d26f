#include "serve_world.hpp"

#include "lever/common/rng.hpp"

namespace lever::hil {
namespace {

// The levers' power-up angles, drawn as lever-hil run draws them.
World make_world(const SimConfig& sim, std::uint64_t seed) {
  Rng start(seed * 4 + 6);
  const double hsi_angle = start.uniform(-0.4, 0.25);
  const double top_angle = start.uniform(-0.4, 0.25);
  return World({sim.scenario, sim.hsi_plant, sim.top_plant, sim.wall, sim.operator_params, sim.substeps, seed * 4 + 5},
               hsi_angle, top_angle);
}

fw::MotorCommand command(const devices::MotorReading& m) { return {m.torque_nm, m.enabled}; }

}  // namespace

ServeWorld::ServeWorld(const SimConfig& sim, std::uint64_t seed)
    : step_n_(sim.gauge.step_n),
      world_(make_world(sim, seed)),
      top_gauge_(sim.gauge, seed * 4 + 4),
      hsi_gauge_(sim.gauge, seed * 4 + 3) {}

ServeTick ServeWorld::step(fw::Tick tick, bool hand_on, LeverDevices& hsi, LeverDevices& top, ServeProbe* probe) {
  world_.set_hand_on(hand_on, tick);
  const auto hsi_motor = hsi.motor->read();
  const auto top_motor = top.motor->read();
  if (probe) probe->motors_read(tick, hsi_motor, top_motor);
  ServeTick s{command(hsi_motor), command(top_motor)};
  if (!probe || !probe->holds_levers()) world_.advance(s.hsi_command, s.top_command);
  const std::int64_t hsi_count = hsi.count_at(world_.hsi().angle()) + (probe ? probe->hsi_count_offset() : 0);
  const std::int64_t top_count = top.count_at(world_.top().angle());
  hsi.encoder->set_count(hsi_count);
  top.encoder->set_count(top_count);
  if (probe) probe->encoders_set(tick, hsi_count, top_count);
  sense(s, tick, hsi, top, probe);
  world_.update_operator(tick, s.hand);
  return s;
}

// The gauges' amplifier (noise, filter, output rate, display step), then the register layout the lever's config
// names.
void ServeWorld::sense(ServeTick& s, fw::Tick tick, LeverDevices& hsi, LeverDevices& top, ServeProbe* probe) {
  s.contact = world_.contact_force();
  s.hand = world_.hand_force();
  top_gauge_.update(s.contact, tick);
  if (const auto r = top_gauge_.latest()) measured_ = r->raw * step_n_;
  if (top.gauge) {
    const auto generated = probe ? probe->top_force_n() : std::nullopt;
    const auto replies_before = top.gauge->set_force(generated.value_or(measured_));
    if (probe) probe->top_gauge_set(tick, replies_before);
  }
  if (hsi.gauge) {
    hsi_gauge_.update(s.hand, tick);
    if (const auto r = hsi_gauge_.latest()) hsi.gauge->set_force(r->raw * step_n_);
  }
  s.measured = measured_;
}

void ServeWorld::reseed_noise(std::uint64_t seed) {
  top_gauge_.reseed(seed * 4 + 4);
  hsi_gauge_.reseed(seed * 4 + 3);
}

}  // namespace lever::hil
