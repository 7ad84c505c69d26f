#include "serve_pair.hpp"

#include <fmt/format.h>

#include <cstdio>

namespace lever::hil {

std::optional<ServePair> load_serve_pair(const ServeOptions& o) {
  auto hsi_loaded = app::load_fw_config(o.hsi_config);
  auto top_loaded = app::load_fw_config(o.top_config);
  for (const auto* loaded : {&hsi_loaded, &top_loaded}) {
    if (!loaded->error.empty()) {
      fmt::print(stderr, "lever-hil serve: {}\n", loaded->error);
      return std::nullopt;
    }
  }
  const app::FwConfig& hsi_config = hsi_loaded.config;
  const app::FwConfig& top_config = top_loaded.config;
  if (hsi_config.lever.role != protocol::Role::hsi || top_config.lever.role != protocol::Role::top) {
    fmt::print(stderr, "lever-hil serve: {} must configure an HSI lever and {} a TOP lever (lever.role)\n",
               o.hsi_config, o.top_config);
    return std::nullopt;
  }
  if (hsi_config.lever.pair != top_config.lever.pair) {
    fmt::print(stderr, "lever-hil serve: the levers are of different pairs ({} and {}; lever.pair)\n",
               hsi_config.lever.pair, top_config.lever.pair);
    return std::nullopt;
  }
  return ServePair{hsi_config, top_config};
}

SimConfig serve_sim_config(const ServeOptions& o, const ServePair& pair) {
  SimConfig sim;
  sim.scenario = *lever_scenario(o.scenario);  // serve_command refused the sphere
  sim.duration_s = o.duration_s;
  sim.seed = o.seed;
  sim.velocity_codec = pair.hsi.lever.motion_codec;
  sim.force_codec = pair.top.lever.force_codec;
  sim.hsi_firmware = pair.hsi.lever;
  // The pair runs its own configurations' contact settings, not the ones the HIL designs for its own HSI's velocity.
  sim.hsi_contact_damping_nms = pair.hsi.lever.display.contact_damping_nms;
  sim.top_firmware = pair.top.lever;
  sim.top_reference_cutoff_hz = pair.top.lever.position.reference_velocity_cutoff_hz;
  return sim;
}

}  // namespace lever::hil
