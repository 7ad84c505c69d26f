// ns per sample of the deadband sender on realistic traces (the generator's lever force and sphere contact).
// Run with --benchmark_repetitions=N to get medians; the time_per_sample counter is the figure of merit.
#include <benchmark/benchmark.h>

#include <vector>

#include "lever/codec/codec.hpp"
#include "trace_generator.hpp"

namespace {

using lever::Vec;
using namespace lever::codec;

template <std::size_t N>
std::vector<Vec<double, N>> samples_of(lever::tool::TraceKind kind) {
  const auto trace = lever::tool::generate_trace({kind, 1, 10.0});
  std::vector<Vec<double, N>> out(trace.samples());
  for (std::size_t i = 0; i < trace.samples(); ++i)
    for (std::size_t d = 0; d < N; ++d) out[i][d] = trace.row(i)[d];
  return out;
}

template <std::size_t N>
void bench_sender(benchmark::State& state, Config<double> config, lever::tool::TraceKind kind) {
  const auto samples = samples_of<N>(kind);
  DeadbandSender<double, N> sender(config);
  double t = 0.0;
  std::int64_t sent = 0;
  for (auto _ : state) {
    for (const auto& x : samples) {
      const auto decision = sender.offer(t, x);
      sent += decision.send;
      benchmark::DoNotOptimize(decision);
      t += 1e-3;
    }
  }
  const auto per_iteration = static_cast<double>(samples.size());
  // Seconds per sample (printed with an SI prefix, e.g. 2.9ns; JSON holds seconds).
  state.counters["time_per_sample"] =
      benchmark::Counter(per_iteration, benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
  state.counters["send_ratio"] = static_cast<double>(sent) / (per_iteration * static_cast<double>(state.iterations()));
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(samples.size()));
}

const Config<double> kDeadband{Mode::deadband, 0.1, 0.0, 0.0};
const Config<double> kPredictiveFilter{Mode::predictive, 0.1, 0.0, 30.0};

}  // namespace

// Registered by name so the report reads mode/DoF, as the issue asks.
int main(int argc, char** argv) {
  using lever::tool::TraceKind;
  benchmark::RegisterBenchmark("deadband/1dof", bench_sender<1>, kDeadband, TraceKind::force);
  benchmark::RegisterBenchmark("predictive_filter/1dof", bench_sender<1>, kPredictiveFilter, TraceKind::force);
  benchmark::RegisterBenchmark("deadband/3dof", bench_sender<3>, kDeadband, TraceKind::force3);
  benchmark::RegisterBenchmark("predictive_filter/3dof", bench_sender<3>, kPredictiveFilter, TraceKind::force3);
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
