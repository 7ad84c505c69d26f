// lever-hil: the testbed in simulated time. `run` one scenario; `sweep` p for the paper's figures; `serve` the
// physical world on the wall clock to real lever-fw processes.
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "delay_sweep.hpp"
#include "lever/program/choices.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/parse.hpp"
#include "report.hpp"
#include "serve.hpp"
#include "sphere.hpp"
#include "sweep.hpp"

namespace {

using namespace lever::hil;
using lever::codec::Mode;

namespace program = lever::program;
constexpr int kBadInput = program::kBadInput;

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop.store(true); }

const program::Choices<ScenarioKind> kScenarios{{"wall-tap", ScenarioKind::wall_tap},
                                                {"free-motion", ScenarioKind::free_motion},
                                                {"press-hold", ScenarioKind::press_hold},
                                                {"sphere-3dof", ScenarioKind::sphere_3dof}};
const program::Choices<Topology> kTopologies{{"one-site", Topology::one_site}, {"two-sites", Topology::two_sites}};
const program::Choices<lever::fw::MotionVelocity> kMotionVelocities{
    {"difference", lever::fw::MotionVelocity::difference}, {"estimate", lever::fw::MotionVelocity::estimate}};
const program::Choices<lever::hil::SweepAxis> kSweepAxes{{"p", lever::hil::SweepAxis::p},
                                                         {"delay", lever::hil::SweepAxis::delay}};
const program::Choices<lever::fw::PassivityMode> kPassivity{{"off", lever::fw::PassivityMode::off},
                                                            {"observe", lever::fw::PassivityMode::observe},
                                                            {"tdpa", lever::fw::PassivityMode::tdpa}};
const program::Choices<Mode> kModes{{"deadband", Mode::deadband}, {"predictive", Mode::predictive}};
// Ranges of the options, in their own units. Floors: the largest the CAN protocol carries (kFloorLsb x 65535).
constexpr program::Bounds kRunSeconds{0.01, 86400.0, false, false, "a duration in seconds"};
constexpr program::Bounds kReserveJoules{0.0, 1000.0, false, true, "an energy in J"};
constexpr program::Bounds kSpendSeconds{0.0, 10.0, false, false, "a time in s"};
constexpr program::Bounds kDriftGain{0.0, 999.0, false, false, "a rate in 1/s"};
constexpr program::Bounds kShare{0.0, 1.0, false, false, "a share"};
constexpr program::Bounds kFloorVelocity{0.0, 65.535, false, false, "a floor in rad/s"};
constexpr program::Bounds kFloorForce{0.0, 65.535, false, false, "a floor in N"};
// A one-way delay or jitter longer than a minute is no network the testbed's watchdogs would tolerate.
constexpr program::Bounds kNetworkMs{0.0, 60000.0, false, false, "a time in ms"};

struct RunOptions {
  SimConfig config;
  Mode mode = Mode::deadband;
  std::optional<Mode> mode_velocity, mode_force;
  double p = 0.1;
  std::optional<double> p_velocity, p_force;
  double floor_velocity = 0.0, floor_force = 0.0, filter_hz = 0.0;
  double comms_timeout_ms = static_cast<double>(lever::fw::LeverConfig{}.comms_timeout);
  double rest_repeat_ms = static_cast<double>(lever::fw::LeverConfig{}.rest_repeat);
  bool no_homing = false;
  lever::fw::PassivityMode passivity = lever::fw::PassivityMode::off;
  double passivity_reserve_j = lever::fw::PassivityConfig{}.reserve_j;
  double passivity_reserve_share = lever::fw::PassivityConfig{}.reserve_share;
  double passivity_display_spend_s = lever::fw::PassivityConfig{}.display_spend_time_s;
  double passivity_drift_gain = lever::fw::PassivityConfig{}.drift_gain_per_s;
  std::optional<double> filter_hz_velocity, filter_hz_force;
  std::vector<std::string> faults;
  bool json = false;
  std::string trace;
  double gauge_rate_hz = StrainGaugeParams{}.output_rate_hz();
};

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

void add_run_options(CLI::App& cmd, RunOptions& o) {
  cmd.add_option("--scenario", o.config.scenario,
                 "wall-tap (the paper's task), free-motion, press-hold or sphere-3dof (the paper's 3-DoF experiment)")
      ->transform(program::one_of(kScenarios))
      ->default_str("wall-tap");
  cmd.add_option("--duration", o.config.duration_s, "simulated seconds")
      ->check(program::number(kRunSeconds))
      ->default_str("20");
  cmd.add_option("--seed", o.config.seed, "random seed (operator, gauge noise, network)")
      ->check(program::seed())
      ->default_str("1");
  cmd.add_option("--mode", o.mode, "deadband or predictive, both directions")
      ->transform(program::one_of(kModes))
      ->default_str("deadband");
  cmd.add_option("--mode-velocity", o.mode_velocity, "mode for HSI->TOP velocity (overrides --mode)")
      ->transform(program::one_of(kModes));
  cmd.add_option("--mode-force", o.mode_force, "mode for TOP->HSI force (overrides --mode)")
      ->transform(program::one_of(kModes));
  cmd.add_option("--p", o.p, "deadband p for both directions (0.1 = 10 %)")
      ->check(program::number(program::kWeberFraction))
      ->default_str("0.1");
  cmd.add_option("--p-velocity", o.p_velocity, "p for HSI->TOP velocity (overrides --p)")
      ->check(program::number(program::kWeberFraction));
  cmd.add_option("--p-force", o.p_force, "p for TOP->HSI force (overrides --p)")
      ->check(program::number(program::kWeberFraction));
  cmd.add_option("--motion-velocity", o.config.hsi_firmware.motion_velocity,
                 "what the HSI sends: difference (the quantized position's backward difference, the paper's) or "
                 "estimate (its smooth velocity estimate)")
      ->transform(program::one_of(kMotionVelocities))
      ->default_str("difference");
  cmd.add_option("--floor-velocity", o.floor_velocity, "velocity deadband floor, rad/s (0: the paper's rule)")
      ->check(program::number(kFloorVelocity))
      ->default_str("0");
  cmd.add_option("--floor-force", o.floor_force, "force deadband floor, N (0: the paper's rule)")
      ->check(program::number(kFloorForce))
      ->default_str("0");
  cmd.add_option("--filter-hz", o.filter_hz, "prefilter cut-off for both directions (0: off)")
      ->check(program::number(program::kCutoffAt1kHz))
      ->default_str("0");
  cmd.add_option("--filter-hz-velocity", o.filter_hz_velocity, "prefilter cut-off for velocity (overrides --filter-hz)")
      ->check(program::number(program::kCutoffAt1kHz));
  cmd.add_option("--filter-hz-force", o.filter_hz_force, "prefilter cut-off for force (overrides --filter-hz)")
      ->check(program::number(program::kCutoffAt1kHz));
  cmd.add_option("--topology", o.config.topology,
                 "one-site (both levers on one CAN bus) or two-sites (each on its own bus, joined by lever-bridges "
                 "over the network)")
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
      ->default_str(std::to_string(lever::fw::LeverConfig{}.comms_timeout));
  cmd.add_option("--rest-repeat-ms", o.rest_repeat_ms,
                 "a data frame that brings its stream to rest is sent again this much later (0: never)")
      ->check(program::whole(0, 30000, "a whole number of milliseconds"))
      ->default_str(std::to_string(lever::fw::LeverConfig{}.rest_repeat));
  cmd.add_option("--passivity", o.passivity,
                 "time-domain passivity at both levers: off, observe (observer and energy frames only) or tdpa")
      ->transform(program::one_of(kPassivity))
      ->default_str("off");
  cmd.add_option("--passivity-reserve-j", o.passivity_reserve_j,
                 "of each port's own input energy, what it keeps for its own output (0: the literature's TDPA)")
      ->check(program::number(kReserveJoules))
      ->default_str(fmt::format("{}", lever::fw::PassivityConfig{}.reserve_j));
  cmd.add_option("--passivity-reserve-share", o.passivity_reserve_share,
                 "of each joule a port takes in, the share that may go to its reserve (the rest goes to the peer at "
                 "once; 1: the reserve fills first)")
      ->check(program::number(kShare))
      ->default_str(fmt::format("{}", lever::fw::PassivityConfig{}.reserve_share));
  cmd.add_option("--passivity-display-spend-s", o.passivity_display_spend_s,
                 "the HSI's display spends its port's energy over this time constant (0: all at once, the "
                 "literature's TDPA)")
      ->check(program::number(kSpendSeconds))
      ->default_str(fmt::format("{}", lever::fw::PassivityConfig{}.display_spend_time_s));
  cmd.add_option("--passivity-drift-gain", o.passivity_drift_gain,
                 "under tdpa, the rate at which the TOP's reference is pulled toward the HSI's position, 1/s")
      ->check(program::number(kDriftGain))
      ->default_str(fmt::format("{}", lever::fw::PassivityConfig{}.drift_gain_per_s));
  cmd.add_flag("--no-homing", o.no_homing,
               "levers with absolute encoders at 0.1 rad, armed at once (default: incremental encoders at a "
               "random angle, homed against the end stop before the scenario)");
  cmd.add_option("--fault", o.faults,
                 "inject a fault: KIND@START[+DURATION][:ARG], kinds link-down, burst-loss, delay-step (:MS), "
                 "bus-off, encoder-glitch, gauge-stale, gauge-saturated, motor-fault, tick-late (the firmware not "
                 "stepped for DURATION), reboot (the controller restarts; +DURATION of boot time) (:hsi|:top); "
                 "repeatable");
  const StrainGaugeParams gauge;
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
  cmd.add_flag("--json", o.json, "print one JSON object");
  cmd.add_option("--trace", o.trace, "write a per-tick CSV trace, atomically, as the run goes ('-': stdout)")
      ->check(program::path());
}

SimConfig finish(RunOptions& o) {
  SimConfig c = o.config;
  c.velocity_codec = {o.mode_velocity.value_or(o.mode), o.p_velocity.value_or(o.p), o.floor_velocity,
                      o.filter_hz_velocity.value_or(o.filter_hz)};
  c.force_codec = {o.mode_force.value_or(o.mode), o.p_force.value_or(o.p), o.floor_force,
                   o.filter_hz_force.value_or(o.filter_hz)};
  c.hsi_firmware.comms_timeout = static_cast<lever::fw::Tick>(o.comms_timeout_ms);
  c.top_firmware.comms_timeout = static_cast<lever::fw::Tick>(o.comms_timeout_ms);
  c.hsi_firmware.rest_repeat = static_cast<lever::fw::Tick>(o.rest_repeat_ms);
  c.top_firmware.rest_repeat = static_cast<lever::fw::Tick>(o.rest_repeat_ms);
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
  const auto& n = c.network;
  if (c.topology == Topology::one_site && (n.delay_ms > 0 || n.jitter_ms > 0 || n.loss > 0))
    throw std::invalid_argument(
        "--delay-ms, --jitter-ms and --loss need --topology two-sites: one site has no network");

  c.record_trace = !o.trace.empty();
  return c;
}

void print_human(std::FILE* out, const SimConfig& c, const SimResult& r) {
  fmt::print(out, "{} for {} s (seed {}), velocity {} p={} floor={}, force {} p={} floor={}\n",
             scenario_name(c.scenario), c.duration_s, c.seed,
             c.velocity_codec.mode == Mode::predictive ? "predictive" : "deadband", c.velocity_codec.p,
             c.velocity_codec.floor, c.force_codec.mode == Mode::predictive ? "predictive" : "deadband",
             c.force_codec.p, c.force_codec.floor);
  fmt::print(out, "  packets: velocity {:.1f} %, force {:.1f} % of 1 kHz\n", 100 * r.velocity_packet_rate,
             100 * r.force_packet_rate);
  fmt::print(out,
             "  position rmse {:.2f} mrad, force rmse {:.3f} N, force off by more than a JND {:.1f} % of the time\n",
             1000 * r.position_rmse_rad, r.force_rmse_n, 100 * r.force_jnd_violation);
  fmt::print(
      out,
      "  by cause: {:.1f} % beside the measurement {} tick(s) earlier (codec, filter, loss, jitter); codec alone "
      "{:.1f} %; prefilter alone {:.1f} % (its lag {:.1f} ms)\n",
      100 * r.force_jnd_violation_link, r.nominal_delay_ticks, 100 * r.force_jnd_violation_codec,
      100 * r.force_jnd_violation_filter, r.prefilter_delay_ms);
  fmt::print(out, "  in contact {:.0f} % of the time at {:.2f} N on average; bus load {:.1f} %; {:.0f}x real time\n",
             100 * r.contact_share, r.mean_contact_force_n, 100 * std::max(r.bus_load_hsi, r.bus_load_top),
             r.realtime_factor);
  if (c.homing)
    fmt::print(out, "  before the scenario: both levers powered up at random angles, homed and armed after {:.2f} s\n",
               r.homed_at_s);
  if (r.hsi_overruns + r.top_overruns + r.hsi_edges_lost + r.top_edges_lost > 0)
    fmt::print(out, "  late steps: HSI {}, TOP {}; encoder edges lost: HSI {}, TOP {}\n", r.hsi_overruns,
               r.top_overruns, r.hsi_edges_lost, r.top_edges_lost);
  for (const auto& f : r.faults) {
    auto say = [](const FaultReport::LeverReaction& x) {
      if (!x.fault_at_s) return std::string("no fault raised");
      std::string names;
      for (const auto bit : lever::protocol::kAllFaults)
        if (lever::protocol::has(x.latched, bit)) names += (names.empty() ? "" : "+") + std::string(name(bit));
      return fmt::format("fault at {:.3f} s ({}), safe at {:.3f} s, max torque {:.2f} N m, re-armed {}", *x.fault_at_s,
                         names, x.safe_at_s.value_or(-1), x.max_torque_nm_during,
                         x.rearmed_at_s ? fmt::format("at {:.3f} s", *x.rearmed_at_s) : "never");
    };
    fmt::print(out, "  fault {}: HSI {}; TOP {}\n", f.spec.text, say(f.hsi), say(f.top));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Hardware-in-the-loop simulator of the lever teleoperation testbed: the real firmware core, two "
      "levers, a stiff wall, a human operator, CAN buses and an IP link, in deterministic simulated time."};
  program::describe(app, "lever-hil");
  app.require_subcommand(1);
  RunOptions run_options;
  auto* run = app.add_subcommand("run", "simulate one scenario and report packet rates, distortion and faults");
  add_run_options(*run, run_options);

  SweepOptions sweep_options;
  auto* sweep = app.add_subcommand(
      "sweep", "sweep p for each mode, or the network delay with and without passivity; CSV and gnuplot PNG plots");
  sweep->add_option("--over", sweep_options.over, "what to sweep: p (the paper's figures) or delay (wall-tap only)")
      ->transform(program::one_of(kSweepAxes))
      ->default_str("p");
  auto* delays =
      sweep
          ->add_option("--delays-ms", sweep_options.delays_ms, "with --over delay: the one-way delays, comma-separated")
          ->delimiter(',')
          ->check(program::number({0.0, 1000.0, false, false, "a delay in ms"}))
          ->default_str("0,10,25,50,100");
  auto* sweep_p = sweep->add_option("--p", sweep_options.p, "with --over delay: deadband p for both directions")
                      ->check(program::number(program::kWeberFraction))
                      ->default_str("0.1");
  sweep->add_option("--scenario", sweep_options.scenario, "scenario")
      ->transform(program::one_of(kScenarios))
      ->default_str("wall-tap");
  sweep->add_option("--out", sweep_options.out_dir, "output directory")->required()->check(program::path());
  sweep->add_option("--seeds", sweep_options.seeds, "seeds per point")->check(program::whole(1, 100))->default_str("3");
  sweep->add_option("--duration", sweep_options.duration_s, "simulated seconds per run")
      ->check(program::number({0.1, 3600.0, false, false, "a duration in seconds"}))
      ->default_str("20");
  sweep->add_option("--jobs", sweep_options.jobs, "parallel runs")->check(program::whole(1, 64))->default_str("2");
  // The +floor and +filter variants must differ from the ones without: 0 is refused here, unlike in run.
  sweep->add_option("--floor-velocity", sweep_options.floor_velocity, "velocity floor of the +floor variant, rad/s")
      ->check(program::number({0.0, 65.535, true, false, "a floor in rad/s"}))
      ->default_str("0.02");
  sweep->add_option("--floor-force", sweep_options.floor_force, "force floor of the +floor variant, N")
      ->check(program::number({0.0, 65.535, true, false, "a floor in N"}))
      ->default_str("0.05");
  sweep
      ->add_option("--filter-hz-velocity", sweep_options.filter_hz_velocity,
                   "velocity prefilter cut-off of the filter variants, Hz (0: off); 30: beyond the 20-30 Hz of "
                   "kinesthetic motion sensing")
      ->check(program::number(program::kCutoffAt1kHz))
      ->default_str("30");
  sweep
      ->add_option("--filter-hz-force", sweep_options.filter_hz_force,
                   "force prefilter cut-off of the filter variants, Hz (0: off); off: force is felt up to about "
                   "1 kHz, beyond the loop's Nyquist")
      ->check(program::number(program::kCutoffAt1kHz))
      ->default_str("0");

  ServeOptions serve_options;
  auto* serve = app.add_subcommand(
      "serve",
      "play the physical world on the wall clock for real lever-fw processes: encoder lines on gpio-sim, strain "
      "gauges as Modbus servers, motors read back from the PWM sysfs tree, as the levers' configs wire them");
  serve->add_option("--hsi-config", serve_options.hsi_config, "the HSI lever's lever-fw configuration")
      ->required()
      ->check(CLI::ExistingFile);
  serve->add_option("--top-config", serve_options.top_config, "the TOP lever's lever-fw configuration")
      ->required()
      ->check(CLI::ExistingFile);
  serve->add_option("--scenario", serve_options.scenario, "wall-tap (the paper's task), free-motion or press-hold")
      ->transform(program::one_of(kScenarios))
      ->default_str("wall-tap");
  serve
      ->add_option("--duration", serve_options.duration_s,
                   "seconds of scenario once both levers are armed (0: until SIGINT or SIGTERM)")
      ->check(program::number({0.0, 86400.0, false, false, "a duration in seconds"}))
      ->default_str("20");
  serve->add_option("--arm-timeout", serve_options.arm_timeout_s, "seconds to wait for both levers to be armed")
      ->check(program::number({1.0, 86400.0, false, false, "a time in seconds"}))
      ->default_str("300");
  serve->add_option("--seed", serve_options.seed, "random seed (power-up angles, operator, gauge noise)")
      ->check(program::seed())
      ->default_str("1");
  serve->add_option("--max-edge-rate", serve_options.max_edge_rate_hz, "encoder edges per second at most, per lever")
      ->check(program::number({100.0, 1e6, false, false, "a rate in edges per second"}))
      ->default_str("20000");
  serve->add_flag("--hands-off", serve_options.hands_off,
                  "the operator never takes the handle: the levers rest where their firmware puts them");
  serve->add_flag("--json", serve_options.json, "print the report as one JSON object");
  serve->add_option("--trace", serve_options.trace, "write a per-tick CSV trace (lever-hil run's columns; '-': stdout)")
      ->check(program::path());

  if (const auto stop = lever::program::parse(app, argc, argv)) return *stop;

  try {
    if (run->parsed()) {
      SimConfig config = finish(run_options);
      if (config.scenario == ScenarioKind::sphere_3dof)
        return run_sphere_command(sphere_config_from(config), run_options.json, run_options.trace);
      // The trace streams to its file as the run goes: an hour of it is 1 GB, never held whole.
      std::optional<program::OutputFile> trace;
      if (!run_options.trace.empty()) {
        trace.emplace(run_options.trace, "--trace");
        trace->write(trace_csv_header());
        config.trace_sink = [&trace](const TraceRow& row) { trace->write(trace_csv_row(row)); };
      }
      const SimResult result = run_simulation(config);
      if (trace) trace->commit();
      std::FILE* out = trace && trace->is_stdout() ? stderr : stdout;  // the trace has stdout
      if (run_options.json) {
        fmt::print(out, "{}\n", report_json(config, result).dump());
      } else {
        print_human(out, config, result);
      }
      return 0;
    }
    if (serve->parsed()) {
      if (serve_options.scenario == ScenarioKind::sphere_3dof)
        throw std::invalid_argument("serve plays the levers' world; sphere-3dof has no levers (use run)");
      std::signal(SIGINT, on_stop_signal);
      std::signal(SIGTERM, on_stop_signal);
      return run_serve(serve_options, g_stop);
    }
    if (sweep_options.over == SweepAxis::delay) {
      if (sweep_options.scenario != ScenarioKind::wall_tap)
        throw std::invalid_argument("sweep --over delay runs wall-tap only (the contact is what delay destabilizes)");
      auto sorted = sweep_options.delays_ms;
      std::sort(sorted.begin(), sorted.end());
      if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
        throw std::invalid_argument("--delays-ms names a delay twice");
      return run_delay_sweep(sweep_options);
    }
    if (delays->count() > 0 || sweep_p->count() > 0)
      throw std::invalid_argument("--delays-ms and --p belong to sweep --over delay (--over p sweeps p itself)");
    if (sweep_options.scenario == ScenarioKind::sphere_3dof) return run_sphere_sweep(sweep_options);
    return run_sweep(sweep_options);
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "lever-hil: {}\n", program::printable(e.what(), 400));
    return kBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "lever-hil: {}\n", program::printable(e.what(), 400));
    return program::kRuntimeFailure;
  }
}
