#include "lever/hil/simulation.hpp"

#include <chrono>
#include <cmath>
#include <stdexcept>

#include "sim_rig.hpp"

namespace lever::hil {
namespace {
constexpr Nanos kTick = 1'000'000;
}

fw::LeverConfig SimConfig::default_firmware(protocol::Role role) {
  fw::LeverConfig c;
  c.role = role;
  c.use_force_sensor = role == protocol::Role::top;
  c.motion_velocity = fw::MotionVelocity::difference;  // the paper's chain (III-E)
  return c;
}

void set_hsi_force_loop(SimConfig& config, bool on) {
  config.hsi_firmware.display.closed_loop = on;
  config.hsi_firmware.use_force_sensor = on;
}

bool hsi_force_loop_offered(const SimConfig& config) { return !reads_paper_gauge(config); }

void check_offered(const SimConfig& config) {
  if (fw::reference_low_pass_conflicts(configured_top_firmware(config)))
    throw std::invalid_argument(
        "the TOP's reference low-pass must be 0 under tdpa: after the passivity port it would apply a velocity the "
        "port never counted (docs/firmware.md, \"Passivity under delay\")");
  if (config.hsi_firmware.display.closed_loop && config.hsi_firmware.use_force_sensor &&
      !hsi_force_loop_offered(config))
    throw std::invalid_argument(
        "--hsi-force-loop on makes the contact chatter on the assumed AD620 chain and is left out there "
        "(docs/hil-model.md, "
        "\"The contact check\"): use --gauge-chain dad141 or the loop off");
}

int nominal_one_way_delay_ticks(const SimConfig& config) {
  if (config.topology == Topology::one_controller) return 0;  // handed over within the tick
  const double frame_ns = protocol::frame_bits_worst_case(8) * 1e9 / config.bitrate;
  const double ns = config.topology == Topology::one_site
                        ? frame_ns
                        : 2 * frame_ns + 2 * config.bridge_latency_us * 1e3 + config.network.delay_ms * 1e6;
  return static_cast<int>(std::ceil(ns / static_cast<double>(kTick)));
}

SimResult run_simulation(const SimConfig& config) {
  const auto wall_start = std::chrono::steady_clock::now();
  check_offered(config);
  SimRig rig(config);
  SimResult result;
  const fw::Tick start = rig.power_up();
  result.homed_at_s = static_cast<double>(start) * 1e-3;
  const auto scenario_ticks = static_cast<fw::Tick>(std::llround(config.duration_s * 1000.0));
  for (fw::Tick tick = start + 1; tick <= start + scenario_ticks; ++tick) rig.scenario_step(tick);
  rig.finish(result);
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.realtime_factor = config.duration_s / result.wall_time_s;
  return result;
}

}  // namespace lever::hil
