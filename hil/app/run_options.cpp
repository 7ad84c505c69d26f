#include "run_options.hpp"

#include <fmt/format.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "cli_choices.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/parse.hpp"
#include "lever/program/text.hpp"

namespace lever::hil {
namespace {

// Ranges of the options, in their own units.
constexpr program::Bounds kRunSeconds{0.01, 86400.0, false, false, "a duration in seconds"};
constexpr program::Bounds kReserveJoules{0.0, 1000.0, false, true, "an energy in J"};
constexpr program::Bounds kSpendSeconds{0.0, 10.0, false, false, "a time in s"};
constexpr program::Bounds kDriftGain{0.0, 999.0, false, false, "a rate in 1/s"};
constexpr program::Bounds kShare{0.0, 1.0, false, false, "a share"};
// A one-way delay or jitter longer than a minute is no network the testbed's watchdogs would tolerate.
constexpr program::Bounds kNetworkMs{0.0, 60000.0, false, false, "a time in ms"};

// A number in [lo, hi], or exactly 0 when zero_ok (program::number has no "0 or" form).
CLI::Validator number_in(double lo, double hi, bool zero_ok = false) {
  return CLI::Validator(
      [=](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) ||
            !((v >= lo && v <= hi) || (zero_ok && v == 0.0)))
          return fmt::format("{} is not {}a number in [{}, {}]", text, zero_ok ? "0 or " : "", lo, hi);
        return {};
      },
      fmt::format("{}NUMBER in [{} - {}]", zero_ok ? "0 or " : "", lo, hi));
}

// The amplifier's output rates: its conversion rate over 2^UR, UR = 0..7 (docs/hil-model.md).
int averaging_for(double rate_hz) {
  const double adc = StrainGaugeParams{}.adc_rate_hz;
  for (int n = 1; n <= 128; n *= 2)
    if (std::fabs(adc / n - rate_hz) <= 1e-9 * adc) return n;
  return 0;
}

// The scenario, its length and seed.
void add_scenario_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--scenario", o.scenario,
                 "wall-tap (the paper's task), free-motion, press-hold or sphere-3dof (the paper's 3-DoF experiment)")
      ->transform(program::one_of(kScenarios))
      ->default_str(std::string(name(ScenarioOption::wall_tap)));
  cmd.add_option("--duration", o.config.duration_s, "simulated seconds")
      ->check(program::number(kRunSeconds))
      ->default_str("20");
  cmd.add_option("--seed", o.config.seed, "random seed (operator, gauge noise, network)")
      ->check(program::seed())
      ->default_str("1");
}

// Each direction's deadband codec, both at once or one by one; and what the HSI sends it.
void add_codec_options(CLI::App& cmd, RunOptions& o) {
  // Both directions' floors differ by unit: there is no --floor, only --floor-velocity and --floor-force.
  codec_cli::add_options(cmd, o.codec, codec_cli::kBothDirections, codec_cli::kOnWire,
                         codec_cli::kAll.without(codec_cli::Param::floor));
  codec_cli::add_overrides(cmd, o.velocity_codec, o.codec, codec_cli::kVelocity, codec_cli::kOnWire);
  codec_cli::add_overrides(cmd, o.force_codec, o.codec, codec_cli::kForce, codec_cli::kOnWire);
  cmd.add_option("--motion-velocity", o.config.hsi_firmware.motion_velocity,
                 "what the HSI sends: difference (the quantized position's backward difference over one tick, the "
                 "paper's), adaptive-window (the same over the longest window up to 20 ms that fits the counts "
                 "within one) or estimate (its smooth velocity estimate)")
      ->transform(program::one_of(kMotionVelocities))
      ->default_str("difference");
}

// The transport between the levers and the firmware's watchdog and rest repeat.
void add_link_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--topology", o.config.topology,
                 "one-controller (both levers in one controller, the paper's PC: a sample reaches the other lever in "
                 "its own tick), one-site (both levers on one CAN bus) or two-sites (each on its own bus, joined by "
                 "lever-bridges over the network)")
      ->transform(program::one_of(kTopologies))
      ->default_str("two-sites");
  cmd.add_option("--delay-ms", o.config.network.delay_ms, "one-way network delay")
      ->check(program::number(kNetworkMs))
      ->default_str("0");
  cmd.add_option("--jitter-ms", o.config.network.jitter_ms, "network jitter (uniform, added)")
      ->check(program::number(kNetworkMs))
      ->default_str("0");
  cmd.add_option("--loss", o.config.network.loss, "datagram loss probability")
      ->check(program::number({0.0, 1.0, false, false, "a probability"}))
      ->default_str("0");
  cmd.add_option("--comms-timeout-ms", o.comms_timeout_ms, "firmware watchdog timeout")
      ->check(program::whole(1, 10000, "a whole number of milliseconds"))
      ->default_str(std::to_string(fw::LeverConfig{}.comms_timeout));
  cmd.add_option("--rest-repeat-ms", o.rest_repeat_ms,
                 "a data frame that brings its stream to rest is sent again this much later (0: never)")
      ->check(program::whole(0, 30000, "a whole number of milliseconds"))
      ->default_str(std::to_string(fw::LeverConfig{}.rest_repeat));
}

// Time-domain passivity at both levers.
void add_passivity_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--passivity", o.passivity,
                 "time-domain passivity at both levers: off, observe (observer and energy frames only) or tdpa")
      ->transform(program::one_of(kPassivity))
      ->default_str("off");
  cmd.add_option("--passivity-reserve-j", o.passivity_reserve_j,
                 "of each port's own input energy, what it keeps for its own output (0: the literature's TDPA)")
      ->check(program::number(kReserveJoules))
      ->default_str(fmt::format("{}", fw::PassivityConfig{}.reserve_j));
  cmd.add_option("--passivity-reserve-share", o.passivity_reserve_share,
                 "of each joule a port takes in, the share that may go to its reserve (the rest goes to the peer at "
                 "once; 1: the reserve fills first)")
      ->check(program::number(kShare))
      ->default_str(fmt::format("{}", fw::PassivityConfig{}.reserve_share));
  cmd.add_option("--passivity-display-spend-s", o.passivity_display_spend_s,
                 "the HSI's display spends its port's energy over this time constant (0: all at once, the "
                 "literature's TDPA)")
      ->check(program::number(kSpendSeconds))
      ->default_str(fmt::format("{}", fw::PassivityConfig{}.display_spend_time_s));
  cmd.add_option("--passivity-drift-gain", o.passivity_drift_gain,
                 "under tdpa, the rate at which the TOP's reference is pulled toward the HSI's position, 1/s")
      ->check(program::number(kDriftGain))
      ->default_str(fmt::format("{}", fw::PassivityConfig{}.drift_gain_per_s));
}

// The HSI's force display: open loop (the firmware's default), or the paper's force control loop on its own gauge.
void add_display_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--hsi-force-loop", o.hsi_force_loop,
                 "the HSI's force control loop on its own strain gauge, the received force as its set value (the "
                 "paper's IV-A-1): on or off (open loop, the firmware's default); refused on the paper-adc chain, "
                 "where it makes the contact chatter")
      ->transform(program::one_of(kOnOff))
      ->default_str("off");
}

// The sphere's device: how its driver gives the velocity.
void add_device_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--device-velocity", o.device_velocity,
                 "sphere-3dof: the velocity the OP reads, driver (the PHANToM Omni ROS driver's chain: second-order "
                 "backward difference, third-order Butterworth low-pass) or difference (one tick of the quantized "
                 "position)")
      ->transform(program::one_of(kDeviceVelocities))
      ->default_str("driver");
  cmd.add_option(
         "--position-sensor", o.position_sensor,
         "sphere-3dof: how the OP reads the tip, joint-encoders (the Omni's three 15000-count encoders and its "
         "kinematics, in doubles), cartesian-grid (55 um cells, the model before issue 33) or exact (the simulated "
         "tip's unquantized position: a diagnostic, no device's chain)")
      ->transform(program::one_of(kPositionSensors))
      ->default_str(std::string(name(SphereConfig{}.position_sensor)));
  cmd.add_option("--device-encoder-counts", o.device_encoder_counts,
                 "sphere-3dof: each of the Omni's three joint encoders' counts per turn, with --position-sensor "
                 "joint-encoders (a diagnostic: the device has 15000)")
      ->check(program::number({100.0, 1e9, false, false, "a number of counts per turn"}))
      ->default_str(fmt::format("{}", OmniParams{}.encoder_counts_per_rev));
  cmd.add_option("--top-clock", o.top_clock,
                 "sphere-3dof: how the two PCs keep time, own (the TOP on its own 1 kHz clock at a phase and a drift "
                 "drawn per seed, packets applied as they arrive) or op-playout (the TOP on the OP's clock the link's "
                 "nominal delay late, play-out queues: the model before issue 39)")
      ->transform(program::one_of(kTopClocks))
      ->default_str(std::string(name(SphereConfig{}.top_clock)));
  cmd.add_option("--driver-cutoff-hz", o.driver_cutoff_hz, "sphere-3dof: the driver's low-pass cut-off, Hz")
      ->check(program::number({0.1, 499.0, false, false, "a cut-off in Hz"}))
      ->default_str(fmt::format("{}", SphereConfig{}.driver_cutoff_hz));
}

// The operator's motion on the lever scenarios' scripts.
void add_operator_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--operator-speed", o.operator_speed,
                 "lever scenarios: the operator's strokes this many times faster than the script's documented ranges "
                 "(every move's time divided by it; 1: as documented)")
      ->check(program::number({0.1, 10.0, false, false, "a factor"}))
      ->default_str("1");
  cmd.add_option("--operator-dwell", o.operator_dwell,
                 "lever scenarios: the operator's pauses at the end of each move times this factor (0: no pause; 1: "
                 "as documented)")
      ->check(program::number({0.0, 10.0, false, false, "a factor"}))
      ->default_str("1");
}

// Both levers' encoders.
void add_encoder_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--encoder-counts", o.encoder_counts,
                 "encoder counts per turn, both levers (16384: 4096 lines read x4; 205887.4: 16 bits over the "
                 "levers' 2 rad range)")
      ->check(program::number({1024.0, 1e7, false, false, "a number of counts per turn"}))
      ->default_str(fmt::format("{}", fw::LeverConfig{}.counts_per_rev));
  cmd.add_option("--encoder-interface", o.encoder_interface,
                 "how the controllers read their encoders: gpio-events (libgpiod's edge queues, the project's board) "
                 "or counter (a hardware counter, no queue)")
      ->transform(program::one_of(kEncoderInterfaces))
      ->default_str(std::string(name(EncoderInterface::gpio_events)));
}

// Homing and injected faults.
void add_homing_and_fault_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_flag("--no-homing", o.no_homing,
               "levers with absolute encoders at 0.1 rad, armed at once (default: incremental encoders at a "
               "random angle, homed against the end stop before the scenario)");
  cmd.add_option("--fault", o.faults,
                 "inject a fault: KIND@START[+DURATION][:ARG], kinds link-down, burst-loss, delay-step (:MS), "
                 "bus-off, encoder-glitch, gauge-stale, gauge-saturated, motor-fault, tick-late (the firmware not "
                 "stepped for DURATION), reboot (the controller restarts; +DURATION of boot time) (:hsi|:top); "
                 "repeatable");
}

// The TOP's force amplifier.
void add_gauge_options(CLI::App& cmd, RunOptions& o) {
  const StrainGaugeParams gauge;
  cmd.add_option(
         "--gauge-chain", o.config.gauge_chain,
         "what reads the levers' strain gauges: dad141 (the Modbus weighing amplifier, set by --gauge-*), "
         "paper-adc (an AD620 and a 16-bit ADC read at 1 kHz, assumed for the paper's PC), or topology (paper-adc "
         "in one controller, dad141 on one or two sites)")
      ->transform(program::one_of(kGaugeChains))
      ->default_str("topology");
  cmd.add_option("--gauge-filter-hz", o.config.gauge.filter_hz,
                 "the force amplifier's IIR cut-off, Hz (Flintec DAD 141.1: 18, 8, 4, 3, 2, 1, 0.5, 0.25; 0: off)")
      ->check(number_in(0.1, 100.0, true))
      ->default_str(fmt::format("{}", gauge.filter_hz));
  cmd.add_option("--gauge-rate-hz", o.gauge_rate_hz,
                 "the force amplifier's output rate, readings per second (600 / 2^k, k = 0..7)")
      ->check(CLI::Validator(
          [](std::string& text) -> std::string {
            double v = 0.0;
            if (!CLI::detail::lexical_cast(text, v) || averaging_for(v) == 0)
              return text + " is not 600 / 2^k for k = 0..7 (600, 300, 150, 75, 37.5, 18.75, 9.375, 4.6875)";
            return {};
          },
          "600 / 2^k"))
      ->default_str(fmt::format("{}", gauge.output_rate_hz()));
  cmd.add_option("--gauge-noise-n", o.config.gauge.noise_n, "the force amplifier's noise per conversion, N rms")
      ->check(program::number({0.0, 1.0, false, false, "a noise in N rms"}))
      ->default_str(fmt::format("{}", gauge.noise_n));
  cmd.add_option("--gauge-step-n", o.config.gauge.step_n, "the force amplifier's display step, N")
      ->check(program::number({1e-6, 1.0, false, false, "a step in N"}))
      ->default_str(fmt::format("{}", gauge.step_n));
}

// What is printed and traced.
void add_output_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_flag("--json", o.json, "print one JSON object");
  cmd.add_option("--trace", o.trace, "write a per-tick CSV trace, atomically, as the run goes ('-': stdout)")
      ->check(program::path());
}

}  // namespace

void add_run_options(CLI::App& cmd, RunOptions& o) {
  add_scenario_options(cmd, o);
  add_codec_options(cmd, o);
  add_link_options(cmd, o);
  add_passivity_options(cmd, o);
  add_encoder_options(cmd, o);
  add_operator_options(cmd, o);
  add_display_options(cmd, o);
  add_device_options(cmd, o);
  add_homing_and_fault_options(cmd, o);
  add_gauge_options(cmd, o);
  add_output_options(cmd, o);
}

std::string misplaced_options(const RunOptions& o) {
  const bool sphere = !lever_scenario(o.scenario);
  if (sphere && (o.encoder_counts || o.encoder_interface || o.hsi_force_loop))
    return "--encoder-counts, --encoder-interface and --hsi-force-loop belong to the lever scenarios (sphere-3dof has "
           "no levers)";
  if (sphere && (o.operator_speed || o.operator_dwell))
    return "--operator-speed and --operator-dwell belong to the lever scenarios (sphere-3dof's hand has its own "
           "model)";
  if (!sphere && (o.device_velocity || o.driver_cutoff_hz))
    return "--device-velocity and --driver-cutoff-hz belong to sphere-3dof (the levers read encoders)";
  if (!sphere && o.position_sensor) return "--position-sensor belongs to sphere-3dof (the levers read encoders)";
  if (!sphere && o.top_clock)
    return "--top-clock belongs to sphere-3dof (the lever scenarios' sites run on the simulation's clock)";
  if (!sphere && o.device_encoder_counts)
    return "--device-encoder-counts belongs to sphere-3dof (the levers' encoders: --encoder-counts)";
  if (o.device_encoder_counts &&
      o.position_sensor.value_or(SpherePositionSensor::joint_encoders) != SpherePositionSensor::joint_encoders)
    return "--device-encoder-counts sets the joint encoders: it needs --position-sensor joint-encoders";
  if (sphere && o.config.gauge_chain != GaugeChain::topology)
    return "--gauge-chain belongs to the lever scenarios (sphere-3dof computes its force, it reads no gauge)";
  return {};
}

SimConfig run_config(const RunOptions& o) {
  SimConfig c = o.config;
  c.scenario = lever_scenario(o.scenario).value_or(c.scenario);
  c.velocity_codec = codec_cli::resolve(o.codec, o.velocity_codec);
  c.force_codec = codec_cli::resolve(o.codec, o.force_codec);
  if (const auto m = misplaced_options(o); !m.empty()) throw std::invalid_argument(m);
  set_hsi_force_loop(c, o.hsi_force_loop.value_or(false));
  c.hsi_firmware.counts_per_rev = c.top_firmware.counts_per_rev =
      o.encoder_counts.value_or(c.hsi_firmware.counts_per_rev);
  c.encoder_interface = o.encoder_interface.value_or(c.encoder_interface);
  c.operator_params.speed_factor = o.operator_speed.value_or(c.operator_params.speed_factor);
  c.operator_params.dwell_factor = o.operator_dwell.value_or(c.operator_params.dwell_factor);
  c.hsi_firmware.comms_timeout = static_cast<fw::Tick>(o.comms_timeout_ms);
  c.top_firmware.comms_timeout = static_cast<fw::Tick>(o.comms_timeout_ms);
  c.hsi_firmware.rest_repeat = static_cast<fw::Tick>(o.rest_repeat_ms);
  c.top_firmware.rest_repeat = static_cast<fw::Tick>(o.rest_repeat_ms);
  c.hsi_firmware.passivity.mode = o.passivity;
  c.top_firmware.passivity.mode = o.passivity;
  c.hsi_firmware.passivity.reserve_j = o.passivity_reserve_j;
  c.top_firmware.passivity.reserve_j = o.passivity_reserve_j;
  c.hsi_firmware.passivity.reserve_share = o.passivity_reserve_share;
  c.top_firmware.passivity.reserve_share = o.passivity_reserve_share;
  c.hsi_firmware.passivity.display_spend_time_s = o.passivity_display_spend_s;
  c.top_firmware.passivity.display_spend_time_s = o.passivity_display_spend_s;
  c.hsi_firmware.passivity.drift_gain_per_s = o.passivity_drift_gain;
  c.top_firmware.passivity.drift_gain_per_s = o.passivity_drift_gain;
  for (const auto& f : o.faults) {
    c.faults.push_back(parse_fault_spec(f));
    if (c.faults.back().start_s >= c.duration_s)
      throw program::BadInput(fmt::format("fault '{}' starts at {} s, after the run's {} s (--duration)",
                                          program::printable(f), program::short_number(c.faults.back().start_s),
                                          program::short_number(c.duration_s)));
  }
  c.homing = !o.no_homing;
  c.gauge.averaging = averaging_for(o.gauge_rate_hz);
  if (reads_paper_gauge(c)) {
    const StrainGaugeParams dad;
    if (c.gauge.filter_hz != dad.filter_hz || c.gauge.averaging != dad.averaging || c.gauge.noise_n != dad.noise_n ||
        c.gauge.step_n != dad.step_n)
      throw std::invalid_argument(
          "--gauge-filter-hz, --gauge-rate-hz, --gauge-noise-n and --gauge-step-n set the DAD 141.1: the paper's ADC "
          "chain (--gauge-chain paper-adc, or one controller's default) has no such settings; add --gauge-chain "
          "dad141");
  }
  const auto& n = c.network;
  const char* no_network = c.topology == Topology::one_site         ? "one site has no network"
                           : c.topology == Topology::one_controller ? "one controller has no network"
                                                                    : nullptr;
  if (no_network && (n.delay_ms > 0 || n.jitter_ms > 0 || n.loss > 0))
    throw std::invalid_argument(
        fmt::format("--delay-ms, --jitter-ms and --loss need --topology two-sites: {}", no_network));
  if (c.topology == Topology::one_controller)
    for (const auto& f : c.faults)
      if (f.kind == FaultKind::link_down || f.kind == FaultKind::burst_loss || f.kind == FaultKind::delay_step ||
          f.kind == FaultKind::bus_off)
        throw std::invalid_argument(
            fmt::format("fault '{}' needs a bus or a link: one controller has neither", program::printable(f.text)));

  c.record_trace = !o.trace.empty();
  return c;
}

}  // namespace lever::hil
