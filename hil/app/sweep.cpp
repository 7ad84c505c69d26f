#include "sweep.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "report.hpp"

namespace lever::hil {
namespace {

constexpr double kPValues[] = {0.0, 0.025, 0.05, 0.075, 0.10, 0.125, 0.15, 0.20, 0.25};

struct Variant {
  const char* name;
  codec::Mode mode;
  bool filter;
  bool floor;
};
// The paper's three modes with its rule (floor 0), then the same with the absolute floor.
constexpr Variant kVariants[] = {
    {"deadband", codec::Mode::deadband, false, false},
    {"predictive", codec::Mode::predictive, false, false},
    {"predictive+filter", codec::Mode::predictive, true, false},
    {"deadband+floor", codec::Mode::deadband, false, true},
    {"predictive+filter+floor", codec::Mode::predictive, true, true},
};

struct Job {
  const Variant* variant;
  double p;
  std::uint64_t seed;
  SimResult result;
};

std::string gnuplot_script(const std::filesystem::path& dir, const std::string& scenario) {
  // Rates and distortion are means over seeds, from summary.csv (one block per variant).
  return fmt::format(R"gp(set terminal pngcairo size 900,600 font ",11"
set datafile separator ","
set key top right
set grid
set xlabel "deadband parameter p [%]"
set xrange [0:25]
variants = "deadband predictive predictive+filter deadband+floor predictive+filter+floor"
file = "{0}/summary.csv"
set output "{0}/packet_rate_velocity.png"
set title "{1}: velocity packets HSI -> TOP (cf. the paper's Fig. 8)"
set ylabel "packet rate [% of 1 kHz]"
set yrange [0:100]
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $3 : 1/0) with linespoints title word(variants,i), \
     "-" using 1:2 with points pt 7 ps 1.5 lc rgb "black" title "paper, Fig. 8"
10,25
e
set output "{0}/packet_rate_force.png"
set title "{1}: force packets TOP -> HSI (cf. the paper's Fig. 8)"
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $4 : 1/0) with linespoints title word(variants,i), \
     "-" using 1:2 with points pt 7 ps 1.5 lc rgb "black" title "paper, Fig. 8"
2.5,10
10,15
e
set output "{0}/distortion.png"
set title "{1}: displayed force off by more than a JND"
set ylabel "share of time [%]"
set yrange [0:*]
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $5 : 1/0) with linespoints title word(variants,i)
set output "{0}/position_error.png"
set title "{1}: TOP position error (RMS against the HSI)"
set ylabel "position RMSE [mrad]"
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $6 : 1/0) with linespoints title word(variants,i)
)gp",
                     dir.string(), scenario);
}

}  // namespace

int run_sweep(const SweepOptions& o) {
  namespace fs = std::filesystem;
  const fs::path dir(o.out_dir);
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) throw std::runtime_error(fmt::format("cannot create {}: {}", o.out_dir, ec.message()));

  std::vector<Job> jobs;
  for (const auto& v : kVariants)
    for (const double p : kPValues)
      for (int s = 1; s <= o.seeds; ++s) jobs.push_back({&v, p, static_cast<std::uint64_t>(s), {}});

  std::atomic<std::size_t> next{0}, done{0};
  std::mutex print;
  const bool tty = isatty(fileno(stderr));
  auto worker = [&] {
    for (std::size_t i = next++; i < jobs.size(); i = next++) {
      Job& job = jobs[i];
      SimConfig c;
      c.scenario = o.scenario;
      c.duration_s = o.duration_s;
      c.seed = job.seed;
      const bool filter = job.variant->filter;
      c.velocity_codec = {job.variant->mode, job.p, job.variant->floor ? o.floor_velocity : 0.0,
                          filter ? o.filter_hz_velocity : 0.0};
      c.force_codec = {job.variant->mode, job.p, job.variant->floor ? o.floor_force : 0.0,
                       filter ? o.filter_hz_force : 0.0};
      job.result = run_simulation(c);
      const std::size_t finished = ++done;
      std::lock_guard lock(print);
      if (tty || finished == jobs.size() || finished % 20 == 0)
        fmt::print(stderr, "{}sweep: {}/{} runs ({} p={:.1f} % seed {}){}", tty ? "\r" : "", finished, jobs.size(),
                   job.variant->name, 100 * job.p, job.seed, tty ? "   " : "\n");
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < o.jobs; ++j) threads.emplace_back(worker);
  for (auto& t : threads) t.join();
  if (tty) fmt::print(stderr, "\n");

  std::string runs =
      "variant,p,seed,velocity_packet_rate,force_packet_rate,force_jnd_violation,position_rmse,"
      "force_rmse,bus_load,realtime_factor\n";
  std::string summary =
      "variant,p_percent,velocity_rate_percent,force_rate_percent,jnd_violation_percent,"
      "position_rmse_mrad,force_rmse_n\n";
  for (std::size_t i = 0; i < jobs.size(); i += static_cast<std::size_t>(o.seeds)) {
    double v = 0, f = 0, jnd = 0, pos = 0, frms = 0;
    for (int s = 0; s < o.seeds; ++s) {
      const Job& job = jobs[i + static_cast<std::size_t>(s)];
      const SimResult& r = job.result;
      runs +=
          fmt::format("{},{},{},{:.6f},{:.6f},{:.6f},{:.6g},{:.6g},{:.6f},{:.0f}\n", job.variant->name, job.p, job.seed,
                      r.velocity_packet_rate, r.force_packet_rate, r.force_jnd_violation, r.position_rmse_rad,
                      r.force_rmse_n, std::max(r.bus_load_hsi, r.bus_load_top), r.realtime_factor);
      v += r.velocity_packet_rate;
      f += r.force_packet_rate;
      jnd += r.force_jnd_violation;
      pos += r.position_rmse_rad;
      frms += r.force_rmse_n;
    }
    const double n = o.seeds;
    summary += fmt::format("{},{},{:.2f},{:.2f},{:.2f},{:.3f},{:.4f}\n", jobs[i].variant->name, 100 * jobs[i].p,
                           100 * v / n, 100 * f / n, 100 * jnd / n, 1000 * pos / n, frms / n);
  }
  std::ofstream(dir / "sweep.csv") << runs;
  std::ofstream(dir / "summary.csv") << summary;
  std::ofstream(dir / "plots.gp") << gnuplot_script(dir, scenario_name(o.scenario));

  const std::string command = fmt::format("gnuplot '{}' 2>&1", (dir / "plots.gp").string());
  if (std::system(command.c_str()) != 0) {
    fmt::print(stderr, "lever-hil: gnuplot failed; the CSV files are in {} (install gnuplot-nox for plots)\n",
               dir.string());
    return 1;
  }
  fmt::print(
      "sweep: {} runs of {} s ({} seeds per point) -> {}/summary.csv, sweep.csv, packet_rate_velocity.png, "
      "packet_rate_force.png, distortion.png, position_error.png\n",
      jobs.size(), o.duration_s, o.seeds, dir.string());
  return 0;
}

}  // namespace lever::hil
