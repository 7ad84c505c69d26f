// lever-bench-core: time per Lever::step() for each role in a running HSI/TOP pair, with passivity off (the
// paper's chain) and with tdpa, and the static memory of one lever instance. Prints one JSON object.
//
// Each step is timed on its own with steady_clock; the clock's own cost (the median of back-to-back reads)
// is reported and subtracted. Several repetitions; the figure of merit is the median across them.
#include <fmt/format.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <optional>
#include <vector>

#include "bench_pair.hpp"
#include "lever/fw/lever.hpp"

namespace {

using namespace lever;
using Clock = std::chrono::steady_clock;

double median(std::vector<double> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}
double percentile(std::vector<double> v, double q) {
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

double mean(const std::vector<double>& v) {
  double sum = 0;
  for (const double x : v) sum += x;
  return sum / static_cast<double>(v.size());
}

// Smallest nonzero difference between two clock reads: the resolution the per-step figures have.
double clock_granularity_ns() {
  double best = 1e9;
  for (int i = 0; i < 100000; ++i) {
    const auto a = Clock::now();
    auto b = Clock::now();
    while (b == a) b = Clock::now();
    best = std::min(best, std::chrono::duration<double, std::nano>(b - a).count());
  }
  return best;
}

double clock_overhead_ns() {
  std::vector<double> d(100000);
  for (auto& x : d) {
    const auto a = Clock::now();
    const auto b = Clock::now();
    x = std::chrono::duration<double, std::nano>(b - a).count();
  }
  return median(d);
}

struct RoleTimes {
  std::vector<double> hsi, top;
};

// One run of the pair (bench_pair.hpp), each role's step timed on its own.
RoleTimes run_pair(std::size_t ticks, fw::PassivityMode passivity) {
  const auto pair = std::make_unique<bench::BenchPair<>>(passivity);
  RoleTimes times;
  times.hsi.reserve(ticks);
  times.top.reserve(ticks);
  for (fw::Tick now = 1; now <= ticks + 100; ++now) {
    pair->before_step(now);
    const auto t0 = Clock::now();
    pair->hsi.step(now);
    const auto t1 = Clock::now();
    pair->top.step(now);
    const auto t2 = Clock::now();
    if (now > 100) {  // armed and running
      times.hsi.push_back(std::chrono::duration<double, std::nano>(t1 - t0).count());
      times.top.push_back(std::chrono::duration<double, std::nano>(t2 - t1).count());
    }
  }
  if (!pair->armed()) {
    fmt::print(stderr, "lever-bench-core: the pair did not stay armed (faults hsi {} top {})\n",
               pair->hsi.supervisor().latched(), pair->top.supervisor().latched());
    std::exit(1);
  }
  return times;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Time per Lever::step() for the HSI and TOP roles, and static memory per lever; prints JSON."};
  app.name("lever-bench-core");
  std::size_t ticks = 100000;
  int repetitions = 5;
  app.add_option("--ticks", ticks, "ticks per repetition")->check(CLI::Range(1000, 100000000))->default_str("100000");
  app.add_option("--repetitions", repetitions, "repetitions")->check(CLI::Range(1, 100))->default_str("5");
  CLI11_PARSE(app, argc, argv);

  const double overhead = clock_overhead_ns();
  // The two configurations alternate within one run, so that the machine's other load falls on both alike.
  struct Figures {
    std::vector<double> hsi_medians, top_medians, hsi_means, top_means, hsi_p99, top_p99;
    void add(const RoleTimes& times, double overhead) {
      hsi_medians.push_back(median(times.hsi) - overhead);
      top_medians.push_back(median(times.top) - overhead);
      hsi_means.push_back(mean(times.hsi) - overhead);
      top_means.push_back(mean(times.top) - overhead);
      hsi_p99.push_back(percentile(times.hsi, 0.99) - overhead);
      top_p99.push_back(percentile(times.top, 0.99) - overhead);
    }
    // Per repetition: median, mean and p99 of the per-step times less the clock's cost; across repetitions
    // the median of each. The mean is finer than the clock's granularity; the median is not.
    nlohmann::json json() const {
      return {{"hsi",
               {{"median", median(hsi_medians)},
                {"mean", median(hsi_means)},
                {"p99", median(hsi_p99)},
                {"means", hsi_means}}},
              {"top",
               {{"median", median(top_medians)},
                {"mean", median(top_means)},
                {"p99", median(top_p99)},
                {"means", top_means}}}};
    }
  } off, tdpa;
  for (int r = 0; r < repetitions; ++r) {
    off.add(run_pair(ticks, fw::PassivityMode::off), overhead);
    tdpa.add(run_pair(ticks, fw::PassivityMode::tdpa), overhead);
  }
  const nlohmann::json out{
      {"ticks_per_repetition", ticks},
      {"repetitions", repetitions},
      {"clock_overhead_ns", overhead},
      {"clock_granularity_ns", clock_granularity_ns()},
      {"step_ns", off.json()},
      {"step_ns_tdpa", tdpa.json()},
      {"tdpa_over_off_mean",
       {{"hsi", median(tdpa.hsi_means) / median(off.hsi_means)},
        {"top", median(tdpa.top_means) / median(off.top_means)}}},
      {"static_bytes_per_lever",
       {{"hsi", sizeof(fw::HsiLever<bench::BenchHal>)}, {"top", sizeof(fw::TopLever<bench::BenchHal>)}}},
      {"static_bytes_note", "sizeof(Lever<Hal, Role>): all state of one lever; the HAL it refers to is the board's"},
  };
  fmt::print("{}\n", out.dump(2));
  return 0;
}
