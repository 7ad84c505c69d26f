// lever-hil: the testbed in simulated time. `run` one scenario; `sweep` p for the paper's figures; `serve` the
// physical world on the wall clock to real lever-fw processes; `study` a session of the paper's user study on the
// simulated pair.
#include <fmt/format.h>

#include <algorithm>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>

#include "cli_choices.hpp"
#include "delay_sweep.hpp"
#include "latency_probe.hpp"
#include "lever/codec_cli/codec_options.hpp"
#include "lever/program/numbers.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/parse.hpp"
#include "report.hpp"
#include "run_options.hpp"
#include "serve.hpp"
#include "sphere.hpp"
#include "sphere_sweep.hpp"
#include "study.hpp"
#include "sweep.hpp"

namespace {

using namespace lever::hil;
namespace program = lever::program;
namespace codec_cli = lever::codec_cli;

std::atomic<bool> g_stop{false};
extern "C" void on_stop_signal(int) { g_stop.store(true); }

struct SweepCommand {
  CLI::App* app = nullptr;
  CLI::Option* delays = nullptr;  // --over delay's own options
  CLI::Option* p = nullptr;
  CLI::Option* topology = nullptr;  // the lever p sweeps' own options
  CLI::Option* force_loop = nullptr;
};

// The +floor variant must differ from the plain one: a floor of 0 is refused here, unlike in run. A cut-off of 0 is
// not: the force's is off in the filter variants (sweep.hpp says why).
constexpr codec_cli::Limits kVariantLimits{.floor_max = codec_cli::kOnWire.floor_max, .floor_zero = false};

void add_variant_options(CLI::App& cmd, SweepOptions& o) {
  using codec_cli::Param;
  codec_cli::add_options(cmd, o.velocity_variants, codec_cli::kVelocity, kVariantLimits, {Param::floor},
                         "of the +floor variant");
  codec_cli::add_options(cmd, o.force_variants, codec_cli::kForce, kVariantLimits, {Param::floor},
                         "of the +floor variant");
  codec_cli::add_options(cmd, o.velocity_variants, codec_cli::kVelocity, kVariantLimits, {Param::filter_hz},
                         "of the filter variants (30: beyond the 20-30 Hz of kinesthetic motion sensing)");
  codec_cli::add_options(cmd, o.force_variants, codec_cli::kForce, kVariantLimits, {Param::filter_hz},
                         "of the filter variants (off: force is felt up to about 1 kHz, beyond the loop's Nyquist)");
}

SweepCommand add_sweep_command(CLI::App& app, SweepOptions& o) {
  SweepCommand cmd;
  cmd.app = app.add_subcommand(
      "sweep", "sweep p for each mode, or the network delay with and without passivity; CSV and gnuplot PNG plots");
  cmd.app->add_option("--over", o.over, "what to sweep: p (the paper's figures) or delay (wall-tap only)")
      ->transform(program::one_of(kSweepAxes))
      ->default_str("p");
  cmd.delays = cmd.app->add_option("--delays-ms", o.delays_ms, "with --over delay: the one-way delays, comma-separated")
                   ->delimiter(',')
                   ->check(program::number({0.0, 1000.0, false, false, "a delay in ms"}))
                   ->default_str("0,10,25,50,100");
  codec_cli::add_options(*cmd.app, o.delay_codec, codec_cli::kBothDirections, codec_cli::kOnWire, {codec_cli::Param::p},
                         "with --over delay");
  cmd.p = cmd.app->get_option("--p");
  cmd.app->add_option("--scenario", o.scenario, "scenario")
      ->transform(program::one_of(kScenarios))
      ->default_str(std::string(name(ScenarioOption::wall_tap)));
  cmd.app->add_option("--out", o.out_dir, "output directory")->required()->check(program::path());
  cmd.app->add_option("--seeds", o.seeds, "seeds per point")->check(program::whole(1, 100))->default_str("3");
  cmd.app->add_option("--duration", o.duration_s, "simulated seconds per run")
      ->check(program::number({0.1, 3600.0, false, false, "a duration in seconds"}))
      ->default_str("20");
  cmd.app->add_option("--jobs", o.jobs, "parallel runs")->check(program::whole(1, 64))->default_str("2");
  add_variant_options(*cmd.app, o);
  cmd.topology = cmd.app
                     ->add_option("--topology", o.topology,
                                  "lever sweeps over p: one-controller (the paper's PC), one-site or two-sites")
                     ->transform(program::one_of(kTopologies))
                     ->default_str(std::string(name(Topology::one_controller)));
  cmd.force_loop = cmd.app
                       ->add_option("--hsi-force-loop", o.hsi_force_loop,
                                    "lever sweeps over p (on the dad141 gauge chain, whose contact holds): the HSI's "
                                    "force control loop on its own gauge (the paper's), on or off")
                       ->transform(program::one_of(kOnOff))
                       ->default_str("on");

  return cmd;
}

CLI::App* add_serve_command(CLI::App& app, ServeOptions& o) {
  auto* serve = app.add_subcommand(
      "serve",
      "play the physical world on the wall clock for real lever-fw processes: encoder lines on gpio-sim, strain "
      "gauges as Modbus servers, motors read back from the PWM sysfs tree, as the levers' configs wire them");
  serve->add_option("--hsi-config", o.hsi_config, "the HSI lever's lever-fw configuration")
      ->required()
      ->check(CLI::ExistingFile);
  serve->add_option("--top-config", o.top_config, "the TOP lever's lever-fw configuration")
      ->required()
      ->check(CLI::ExistingFile);
  serve->add_option("--scenario", o.scenario, "wall-tap (the paper's task), free-motion or press-hold")
      ->transform(program::one_of(kScenarios))
      ->default_str(std::string(name(ScenarioOption::wall_tap)));
  serve
      ->add_option("--duration", o.duration_s,
                   "seconds of scenario once both levers are armed (0: until SIGINT or SIGTERM)")
      ->check(program::number({0.0, 86400.0, false, false, "a duration in seconds"}))
      ->default_str("20");
  serve->add_option("--arm-timeout", o.arm_timeout_s, "seconds to wait for both levers to be armed")
      ->check(program::number({1.0, 86400.0, false, false, "a time in seconds"}))
      ->default_str("300");
  serve->add_option("--seed", o.seed, "random seed (power-up angles, operator, gauge noise)")
      ->check(program::seed())
      ->default_str("1");
  serve->add_option("--max-edge-rate", o.max_edge_rate_hz, "encoder edges per second at most, per lever")
      ->check(program::number({100.0, 1e6, false, false, "a rate in edges per second"}))
      ->default_str("20000");
  serve->add_flag("--hands-off", o.hands_off,
                  "the operator never takes the handle: the levers rest where their firmware puts them");
  serve->add_flag("--latency-probe", o.latency_probe,
                  "hands off; measure the pair's end-to-end latency with stimuli on the HSI's encoder and the TOP's "
                  "gauge (needs the kernel rig's PWM controllers: docs/hil-serve.md)");
  serve->add_flag("--json", o.json, "print the report as one JSON object");
  serve->add_option("--trace", o.trace, "write a per-tick CSV trace (lever-hil run's columns; '-': stdout)")
      ->check(program::path());

  return serve;
}

int run_command(const RunOptions& o) {
  SimConfig config = run_config(o);
  if (!lever_scenario(o.scenario)) return run_sphere_command(sphere_config_from(config, o), o.json, o.trace);
  // The trace streams to its file as the run goes: an hour of it is 1 GB, never held whole.
  std::optional<program::OutputFile> trace;
  if (!o.trace.empty()) {
    trace.emplace(o.trace, "--trace");
    trace->write(trace_csv_header());
    config.trace_sink = [&trace](const TraceRow& row) { trace->write(trace_csv_row(row)); };
  }
  const SimResult result = run_simulation(config);
  if (trace) trace->commit();
  std::FILE* out = trace && trace->is_stdout() ? stderr : stdout;  // the trace has stdout
  if (o.json) {
    fmt::print(out, "{}\n", report_json(config, result).dump());
  } else {
    print_report(out, config, result);
  }
  return 0;
}

int serve_command(const ServeOptions& o) {
  if (!lever_scenario(o.scenario))
    throw std::invalid_argument("serve plays the levers' world; sphere-3dof has no levers (use run)");
  std::signal(SIGINT, on_stop_signal);
  std::signal(SIGTERM, on_stop_signal);
  if (!o.latency_probe) return run_serve(o, g_stop);
  ServeOptions hands_off = o;
  hands_off.hands_off = true;
  LatencyProbe probe;
  return run_serve(hands_off, g_stop, &probe);
}

int sweep_command(const SweepOptions& o, const SweepCommand& cmd) {
  if (o.over == SweepAxis::delay) {
    if (cmd.topology->count() > 0 || cmd.force_loop->count() > 0)
      throw std::invalid_argument(
          "--topology and --hsi-force-loop belong to sweep --over p (--over delay runs two sites, open loop)");
    if (o.scenario != ScenarioOption::wall_tap)
      throw std::invalid_argument("sweep --over delay runs wall-tap only (the contact is what delay destabilizes)");
    auto sorted = o.delays_ms;
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
      throw std::invalid_argument("--delays-ms names a delay twice");
    return run_delay_sweep(o);
  }
  if (cmd.delays->count() > 0 || cmd.p->count() > 0)
    throw std::invalid_argument("--delays-ms and --p belong to sweep --over delay (--over p sweeps p itself)");
  if (!lever_scenario(o.scenario)) {
    if (cmd.topology->count() > 0 || cmd.force_loop->count() > 0)
      throw std::invalid_argument(
          "--topology and --hsi-force-loop belong to the lever scenarios (sphere-3dof has none)");
    return run_sphere_sweep(o);
  }
  return run_sweep(o);
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
  const SweepCommand sweep = add_sweep_command(app, sweep_options);
  ServeOptions serve_options;
  auto* serve = add_serve_command(app, serve_options);
  StudyOptions study_options;
  auto* study_cmd = app.add_subcommand("study",
                                       "one session of the paper's user study (3ifc or rating) on the simulated pair, "
                                       "answered by a simulated observer, to a session log for lever-study report");
  add_study_options(*study_cmd, study_options);
  if (const auto stop = program::parse(app, argc, argv)) return *stop;

  try {
    if (run->parsed()) return run_command(run_options);
    if (serve->parsed()) return serve_command(serve_options);
    if (study_cmd->parsed()) return run_study(study_options);
    return sweep_command(sweep_options, sweep);
  } catch (const std::invalid_argument& e) {
    fmt::print(stderr, "lever-hil: {}\n", program::printable(e.what(), 400));
    return program::kBadInput;
  } catch (const std::exception& e) {
    fmt::print(stderr, "lever-hil: {}\n", program::printable(e.what(), 400));
    return program::kRuntimeFailure;
  }
}
