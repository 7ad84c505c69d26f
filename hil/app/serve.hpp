#pragma once
// `lever-hil serve`: the physical world for real lever-fw processes, on the wall clock, through the very
// interfaces a board has: each lever's encoder lines on a gpio-sim chip, its strain gauge as a Modbus server
// (TCP, or RTU on a pseudo-terminal), its motor as the PWM sysfs tree and driver lines it writes. The levers'
// own lever-fw configuration files say where each of those is.
#include <atomic>
#include <cstdint>
#include <string>

#include "lever/hil/human_operator.hpp"
#include "scenario_option.hpp"
#include "serve_probe.hpp"

namespace lever::hil {

struct ServeOptions {
  std::string hsi_config, top_config;                  // the levers' lever-fw configuration files
  ScenarioOption scenario = ScenarioOption::wall_tap;  // a lever scenario: serve refuses the sphere
  double duration_s = 20.0;      // scenario seconds from the moment the pair is armed; 0: until a signal
  double arm_timeout_s = 300.0;  // wall seconds to wait for the pair to be armed
  std::uint64_t seed = 1;        // power-up angles, operator, gauge noise
  double max_edge_rate_hz = 20000.0;
  bool hands_off = false;      // the operator never takes the handle: the levers go where their firmware puts them
  bool latency_probe = false;  // hands off, stimuli on the sensors, the pair's latency in the report
  bool json = false;           // the report as one JSON object on stdout
  std::string trace;           // a per-tick CSV with lever-hil run's columns, written as the run goes
};

// Exit code: 0 done (duration or signal), 1 runtime failure (a device that cannot be opened, the pair never
// armed), 2 bad input (a configuration). `probe`, when given, sees every tick (serve_probe.hpp).
int run_serve(const ServeOptions& options, const std::atomic<bool>& stop, ServeProbe* probe = nullptr);

}  // namespace lever::hil
