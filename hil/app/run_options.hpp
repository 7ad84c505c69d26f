#pragma once
// `lever-hil run`'s options: declared on the command line, then made into the simulation's configuration.
#include <CLI/CLI.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lever/codec/config.hpp"
#include "lever/codec_cli/codec_options.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "lever/hil/strain_gauge_model.hpp"
#include "scenario_option.hpp"

namespace lever::hil {

struct RunOptions {
  ScenarioOption scenario = ScenarioOption::wall_tap;  // the lever scenarios' goes into config
  SimConfig config;
  codec::Config<double> codec;                       // --mode, --p, --filter-hz: both directions
  codec_cli::Overrides velocity_codec, force_codec;  // --*-velocity, --*-force: one direction each
  double comms_timeout_ms = static_cast<double>(fw::LeverConfig{}.comms_timeout);
  // Lever-only and sphere-only options, empty unless given: the other kind of scenario refuses them.
  std::optional<double> encoder_counts;
  std::optional<EncoderInterface> encoder_interface;
  std::optional<bool> hsi_force_loop;
  std::optional<double> operator_speed, operator_dwell;
  std::optional<SphereVelocityChain> device_velocity;
  std::optional<SpherePositionSensor> position_sensor;
  std::optional<SphereTopClock> top_clock;
  std::optional<double> driver_cutoff_hz;
  std::optional<double> device_encoder_counts;
  double rest_repeat_ms = static_cast<double>(fw::LeverConfig{}.rest_repeat);
  bool no_homing = false;
  fw::PassivityMode passivity = fw::PassivityMode::off;
  double passivity_reserve_j = fw::PassivityConfig{}.reserve_j;
  double passivity_reserve_share = fw::PassivityConfig{}.reserve_share;
  double passivity_display_spend_s = fw::PassivityConfig{}.display_spend_time_s;
  double passivity_drift_gain = fw::PassivityConfig{}.drift_gain_per_s;
  std::vector<std::string> faults;
  bool json = false;
  std::string trace;
  double gauge_rate_hz = StrainGaugeParams{}.output_rate_hz();
};

void add_run_options(CLI::App& cmd, RunOptions& o);
// Throws program::BadInput or std::invalid_argument for options that do not go together.
SimConfig run_config(const RunOptions& o);
// The lever-only options a sphere-3dof run was given, or the sphere-only ones a lever run was: empty if none.
std::string misplaced_options(const RunOptions& o);

}  // namespace lever::hil
