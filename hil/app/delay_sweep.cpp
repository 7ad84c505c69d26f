#include "delay_sweep.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/text.hpp"
#include "sweep_runner.hpp"

namespace lever::hil {
namespace {

struct Variant {
  const char* name;
  fw::PassivityMode mode;
};
constexpr Variant kVariants[] = {{"without", fw::PassivityMode::observe}, {"tdpa", fw::PassivityMode::tdpa}};

struct Job {
  const Variant* variant;
  double delay_ms;
  std::uint64_t seed;
  SimResult result;
};

// Each metric: its CSV name, its value in the plots' units, and the digits written.
struct Metric {
  const char* name;
  double (*value)(const SimResult&);
  int digits;
};
double armed_s(const SimResult& r) { return static_cast<double>(r.armed_ticks) * 1e-3; }
const Metric kMetrics[] = {
    {"velocity_rate_percent", [](const SimResult& r) { return 100 * r.velocity_packet_rate; }, 2},
    {"force_rate_percent", [](const SimResult& r) { return 100 * r.force_packet_rate; }, 2},
    {"energy_frames_per_s", [](const SimResult& r) { return static_cast<double>(r.energy_frames) / armed_s(r); }, 1},
    {"datagrams_per_s", [](const SimResult& r) { return static_cast<double>(r.network_sent) / armed_s(r); }, 1},
    {"jnd_violation_percent", [](const SimResult& r) { return 100 * r.force_jnd_violation; }, 2},
    {"force_rmse_n", [](const SimResult& r) { return r.force_rmse_n; }, 4},
    {"contact_onsets_per_s", [](const SimResult& r) { return r.contact_onsets_per_s; }, 3},
    {"protection_trips",
     [](const SimResult& r) { return static_cast<double>(r.hsi_lever_faults.count + r.top_lever_faults.count); }, 2},
    {"hsi_dissipated_j", [](const SimResult& r) { return r.hsi_dissipated_energy_j; }, 4},
    {"top_dissipated_j", [](const SimResult& r) { return r.top_dissipated_energy_j; }, 4},
    {"hsi_min_observed_j", [](const SimResult& r) { return r.hsi_min_observed_energy_j; }, 4},
    {"top_min_observed_j", [](const SimResult& r) { return r.top_min_observed_energy_j; }, 4},
    {"position_rmse_mrad", [](const SimResult& r) { return 1e3 * r.position_rmse_rad; }, 2},
};
constexpr std::size_t kMetricCount = std::size(kMetrics);

// The summary's column of metric k's mean (gnuplot counts from 1; variant, delay and seeds come first);
// min and max follow it.
constexpr int column(int k) { return 4 + 3 * k; }

std::string gnuplot_script(double p, int seeds) {
  auto series = [](int k, const char* label) {
    return fmt::format(
        "for [i=1:2] file using 2:(strcol(1) eq word(variants,i) ? ${0} : 1/0):{1}:{2} with yerrorlines lc i dt {3} "
        "title word(variants,i) . \" {4}\"",
        column(k), column(k) + 1, column(k) + 2, 1 + (k % 2), label);
  };
  return fmt::format(
      R"gp(# lever-hil sweep --over delay: plots from summary.csv beside this script; `gnuplot plots.gp` redraws them.
{0}file = dir . "summary.csv"
set terminal pngcairo size 1200,520 font ",11" noenhanced
set datafile separator ","
set offsets graph 0.03, graph 0.03, 0, 0
set key below horizontal
set grid
set xlabel "one-way delay [ms] (jitter a tenth of it, 1 % loss from 10 ms on)"
variants = "without tdpa"
spread = "wall-tap, p = {1:g} %, mean of {2} seed{3}; bars: min to max; without = passivity observe"
set output dir . "delay_packet_rates.png"
set multiplot layout 1,2 title "packet rates against delay\n" . spread
set title "data frames"
set ylabel "packet rate [% of 1 kHz]"
set yrange [0:*]
plot {4}, {5}
set title "on the link"
set ylabel "frames or datagrams per second"
plot {6}, {7}
unset multiplot
set output dir . "delay_force_error.png"
set multiplot layout 1,2 title "displayed force against delay\n" . spread
set title "off by more than a JND"
set ylabel "share of time [%]"
plot {8}
set title "RMS error against the TOP's measurement"
set ylabel "force RMSE [N]"
plot {9}
unset multiplot
set output dir . "delay_chatter.png"
set multiplot layout 1,2 title "contact against delay\n" . spread
set title "chatter: the TOP's wall contact beginning"
set ylabel "contact onsets per second"
plot {10}
set title "protection trips (TORQUE_LIMIT, POSITION_LIMIT, PEER_STATE)"
set ylabel "armed -> fault, both levers, per run"
plot {11}
unset multiplot
set output dir . "delay_energy.png"
set multiplot layout 1,2 title "passivity against delay\n" . spread
set title "energy the controllers dissipated"
set ylabel "energy [J]"
plot {12}, {13}
set title "the observers' lowest energy (below 0: the channel made energy)"
set yrange [*:*]
plot {14}, {15}
unset multiplot
set terminal pngcairo size 900,650 font ",11" noenhanced
set output dir . "delay_position.png"
set title "TOP position error (RMS against the HSI)\n" . spread
set ylabel "position RMSE [mrad]"
set yrange [0:*]
plot {16}
)gp",
      kGnuplotScriptDir, 100 * p, seeds, seeds == 1 ? "" : "s", series(0, "velocity"), series(1, "force"),
      series(2, "energy frames/s"), series(3, "datagrams/s"), series(4, ""), series(5, ""), series(6, ""),
      series(7, ""), series(8, "HSI"), series(9, "TOP"), series(10, "HSI"), series(11, "TOP"), series(12, ""));
}

}  // namespace

int run_delay_sweep(const SweepOptions& o) {
  namespace fs = std::filesystem;
  const fs::path dir(o.out_dir);
  prepare_sweep_dir(o.out_dir, {"sweep.csv", "summary.csv", "plots.gp"});

  std::vector<Job> jobs;
  for (const auto& v : kVariants)
    for (const double delay_ms : o.delays_ms)
      for (int s = 1; s <= o.seeds; ++s) jobs.push_back({&v, delay_ms, static_cast<std::uint64_t>(s), {}});

  run_in_parallel(
      jobs.size(), o.jobs, 5,
      [&](std::size_t i) {
        Job& job = jobs[i];
        SimConfig c;
        c.scenario = ScenarioKind::wall_tap;
        c.topology = Topology::two_sites;
        c.duration_s = o.duration_s;
        c.seed = job.seed;
        c.velocity_codec = {codec::Mode::deadband, o.p, 0.0, 0.0};
        c.force_codec = {codec::Mode::deadband, o.p, 0.0, 0.0};
        c.network.delay_ms = job.delay_ms;
        c.network.jitter_ms = job.delay_ms / 10.0;
        c.network.loss = job.delay_ms > 0.0 ? 0.01 : 0.0;
        for (auto* fw : {&c.hsi_firmware, &c.top_firmware}) {
          // The watchdog stays out of it: what is measured is the loop under delay, not the timeout.
          fw->comms_timeout = 300;
          fw->passivity.mode = job.variant->mode;
        }
        job.result = run_simulation(c);
      },
      [&](std::size_t i) {
        return fmt::format("{} {:g} ms seed {}", jobs[i].variant->name, jobs[i].delay_ms, jobs[i].seed);
      });

  std::string runs = "variant,delay_ms,seed";
  std::string summary = "variant,delay_ms,seeds";
  for (const auto& m : kMetrics) {
    runs += fmt::format(",{}", m.name);
    summary += fmt::format(",{0},{0}_min,{0}_max", m.name);
  }
  runs += "\n";
  summary += "\n";
  for (std::size_t i = 0; i < jobs.size(); i += static_cast<std::size_t>(o.seeds)) {
    Spread spread[kMetricCount];
    for (int s = 0; s < o.seeds; ++s) {
      const Job& job = jobs[i + static_cast<std::size_t>(s)];
      runs += fmt::format("{},{:g},{}", job.variant->name, job.delay_ms, job.seed);
      for (std::size_t k = 0; k < kMetricCount; ++k) {
        const double x = kMetrics[k].value(job.result);
        runs += fmt::format(",{:.{}f}", x, kMetrics[k].digits + 2);
        spread[k].add(x);
      }
      runs += "\n";
    }
    summary += fmt::format("{},{:g},{}", jobs[i].variant->name, jobs[i].delay_ms, o.seeds);
    for (std::size_t k = 0; k < kMetricCount; ++k) summary += spread[k].csv(o.seeds, 1.0, kMetrics[k].digits);
    summary += "\n";
  }
  program::OutputFile::write_all((dir / "sweep.csv").string(), runs, "--out");
  program::OutputFile::write_all((dir / "summary.csv").string(), summary, "--out");
  program::OutputFile::write_all((dir / "plots.gp").string(), gnuplot_script(o.p, o.seeds), "--out");

  if (const int code = plot_sweep(dir); code != 0) return code;
  fmt::print(
      "sweep: {} runs of {} s ({} seeds per point) -> {}/summary.csv, sweep.csv, delay_packet_rates.png, "
      "delay_force_error.png, delay_chatter.png, delay_energy.png, delay_position.png\n",
      jobs.size(), o.duration_s, o.seeds, program::printable(dir.string()));
  return 0;
}

}  // namespace lever::hil
