// lever-bench-hil: the HIL's realtime factor on one core: simulated seconds per wall-clock second for the
// wall-tap scenario with both levers, both buses and the network (the paper's p = 10 %, floors on), and for
// sphere-3dof, the paper's 3-DoF experiment (its recommended 7.5 % on velocity, prediction and prefilter).
// Run with --benchmark_repetitions=N for medians; the realtime_factor counter is the figure of merit.
#include <benchmark/benchmark.h>

#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"

namespace {

using namespace lever;

void bench_scenario(benchmark::State& state, hil::ScenarioKind scenario, double delay_ms) {
  hil::SimConfig c;
  c.scenario = scenario;
  c.duration_s = 20.0;
  c.velocity_codec = {codec::Mode::deadband, 0.1, 0.02, 0.0};
  c.force_codec = {codec::Mode::deadband, 0.1, 0.05, 0.0};
  c.network.delay_ms = delay_ms;
  double packets = 0;
  for (auto _ : state) {
    const auto r = hil::run_simulation(c);
    packets = r.velocity_packet_rate + r.force_packet_rate;
    benchmark::DoNotOptimize(packets);
  }
  // Simulated seconds per second of wall time.
  state.counters["realtime_factor"] =
      benchmark::Counter(c.duration_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

void bench_sphere(benchmark::State& state) {
  hil::SphereConfig c = hil::sphere_variant(hil::SphereDirection::velocity, codec::Mode::predictive, true, 0.075);
  c.duration_s = 20.0;
  double packets = 0;
  for (auto _ : state) {
    const auto r = hil::run_sphere(c);
    packets = r.velocity_packet_rate + r.force_packet_rate;
    benchmark::DoNotOptimize(packets);
  }
  state.counters["realtime_factor"] =
      benchmark::Counter(c.duration_s * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::RegisterBenchmark("wall_tap/20s", bench_scenario, hil::ScenarioKind::wall_tap, 0.0)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark("wall_tap_delay20ms/20s", bench_scenario, hil::ScenarioKind::wall_tap, 20.0)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark("free_motion/20s", bench_scenario, hil::ScenarioKind::free_motion, 0.0)
      ->Unit(benchmark::kMillisecond)
      ->UseRealTime();
  benchmark::RegisterBenchmark("sphere_3dof/20s", bench_sphere)->Unit(benchmark::kMillisecond)->UseRealTime();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
