// lever-fw-sim: one lever's firmware, configured as lever-fw is, against the in-process HIL (the other lever, the
// wall, the operator, the buses and the link simulated), paced to the wall clock. The simulated board lives here,
// on the HIL's side, so that lever-fw ships without the simulator (docs/architecture.md).
#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <optional>
#include <string>
#include <thread>

#include "lever/app/fw_config.hpp"
#include "lever/app/stats_line.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/program/choices.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"

namespace {

using namespace lever;

std::atomic<bool> g_stop{false};
extern "C" void on_signal(int) { g_stop.store(true); }

struct Stop {};  // unwinds the simulation when a signal asks to stop

// This lever's configuration in the HIL's testbed, the other lever at its defaults.
int run_sim(const app::FwConfig& config, double duration_s, bool stats_json, bool fast) {
  hil::SimConfig sim;
  sim.duration_s = duration_s;
  const bool hsi = config.lever.role == protocol::Role::hsi;
  auto& simulated = hsi ? sim.hsi_firmware : sim.top_firmware;
  simulated = config.lever;
  // The simulated gauge is the HIL's ADC, not the board's Modbus amplifier (which reports newtons): it keeps
  // the calibration the HIL's gauge model is made for.
  simulated.gauge = hil::SimConfig::default_firmware(config.lever.role).gauge;
  // The contact settings a board runs (its configuration's, the other lever's a board's defaults), not the ones the
  // HIL designs for its own HSI's velocity (hil::contact_settings).
  const fw::LeverConfig& hsi_lever = hsi ? config.lever : fw::LeverConfig{};
  const fw::LeverConfig& top_lever = hsi ? fw::LeverConfig{} : config.lever;
  sim.hsi_contact_damping_nms = hsi_lever.display.contact_damping_nms;
  sim.top_reference_cutoff_hz = top_lever.position.reference_velocity_cutoff_hz;
  sim.velocity_codec = (hsi ? config.lever : sim.hsi_firmware).motion_codec;
  sim.force_codec = (hsi ? sim.top_firmware : config.lever).force_codec;
  const auto wall_start = std::chrono::steady_clock::now();
  sim.observer = [&](const hil::SimView& v) {
    if (g_stop.load()) throw Stop{};
    if (!fast) std::this_thread::sleep_until(wall_start + std::chrono::milliseconds(v.tick));
    if (v.tick % 1000 != 0) return;
    const auto line = app::stats_json(hsi ? app::snapshot(v.hsi, v.tick) : app::snapshot(v.top, v.tick), {});
    if (stats_json) {
      fmt::print("{}\n", line.dump());
    } else {
      fmt::print(
          "t={:6.1f} s  {:8s} position {:+.3f} rad{}  velocity {:+.3f} rad/s  torque {:+.3f} N m  "
          "sent {}  faults {}\n",
          static_cast<double>(v.tick) * 1e-3, line["state"].get<std::string>(), line["position_rad"].get<double>(),
          line["position_valid"].get<bool>() ? "" : " (not homed)", line["velocity_rad_s"].get<double>(),
          line["torque_nm"].get<double>(), line["data_sent"].get<std::uint64_t>(), line["faults"].dump());
    }
    std::fflush(stdout);
  };
  try {
    const auto r = hil::run_simulation(sim);
    fmt::print(stderr, "lever-fw-sim: simulated {:.1f} s: velocity packets {:.1f} %, force packets {:.1f} %\n",
               duration_s, 100 * r.velocity_packet_rate, 100 * r.force_packet_rate);
  } catch (const Stop&) {
    fmt::print(stderr, "lever-fw-sim: stopped by a signal; the simulated lever's motor is off with the simulation\n");
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "lever-fw-sim: the firmware of one lever (HSI or TOP), configured as lever-fw is, against the simulated "
      "testbed."};
  program::describe(app, "lever-fw-sim");
  std::string config_path;
  std::optional<protocol::Role> role;
  bool stats_json = false, fast = false;
  double duration_s = 10.0;
  app.add_option("--config", config_path, "lever-fw's TOML configuration (docs/lever-fw.md lists every key)")
      ->required()
      ->check(program::path());
  app.add_option("--role", role, "override lever.role: hsi or top")
      ->transform(program::one_of(
          program::Choices<protocol::Role>{{"hsi", protocol::Role::hsi}, {"top", protocol::Role::top}}));
  app.add_flag("--stats-json", stats_json, "one JSON status object per line, once a simulated second");
  app.add_option("--duration", duration_s, "simulated seconds")
      ->check(program::number({0.1, 86400.0, false, false, "a duration in seconds"}));
  app.add_flag("--fast", fast, "as fast as the machine goes, not paced to the wall clock");
  if (const auto exit_code = program::parse(app, argc, argv)) return *exit_code;

  auto loaded = app::load_fw_config(config_path);
  if (!loaded.error.empty()) {
    fmt::print(stderr, "lever-fw-sim: {}\n", loaded.error);
    return program::kBadInput;
  }
  auto& config = loaded.config;
  if (role) config.lever.role = *role;
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  return run_sim(config, duration_s, stats_json, fast);
}
