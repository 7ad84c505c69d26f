#include "sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <limits>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/program/exit_codes.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/text.hpp"
#include "report.hpp"
#include "sweep_runner.hpp"

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

// The plot script names no path: it finds its data beside itself (ARG0, set however gnuplot is started), so
// a directory's name is data and never gnuplot code, and the script runs from any directory.
std::string gnuplot_script(const std::string& scenario, int seeds) {
  return fmt::format(R"gp(# lever-hil sweep: plots from summary.csv beside this script; run it as `gnuplot plots.gp`.
{2}file = dir . "summary.csv"
set terminal pngcairo size 900,650 font ",11"
set datafile separator ","
# The legend below the plot, never over the curves.
set key below horizontal
set grid
set xlabel "deadband parameter p [%]"
set xrange [0:25]
spread = "mean of {1} seed{3}; bars: min to max"
variants = "deadband predictive predictive+filter deadband+floor predictive+filter+floor"
# columns: variant,p_percent,seeds, then mean,min,max of each metric
set output dir . "packet_rate_velocity.png"
set title "{0}: velocity packets HSI -> TOP (cf. the paper's Fig. 8)\n" . spread
set ylabel "packet rate [% of 1 kHz]"
set yrange [0:100]
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $4 : 1/0):5:6 with yerrorlines title word(variants,i), \
     "-" using 1:2 with points pt 7 ps 1.5 lc rgb "black" title "paper, Fig. 8"
10,25
e
set output dir . "packet_rate_force.png"
set title "{0}: force packets TOP -> HSI (cf. the paper's Fig. 8)\n" . spread
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $7 : 1/0):8:9 with yerrorlines title word(variants,i), \
     "-" using 1:2 with points pt 7 ps 1.5 lc rgb "black" title "paper, Fig. 8"
2.5,10
10,15
e
set output dir . "distortion.png"
set title "{0}: displayed force off by more than a JND\n" . spread
set ylabel "share of time [%]"
set yrange [0:*]
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $10 : 1/0):11:12 with yerrorlines title word(variants,i)
set output dir . "position_error.png"
set title "{0}: TOP position error (RMS against the HSI)\n" . spread
set ylabel "position RMSE [mrad]"
plot for [i=1:5] file using 2:(strcol(1) eq word(variants,i) ? $13 : 1/0):14:15 with yerrorlines title word(variants,i)
)gp",
                     scenario, seeds, kGnuplotScriptDir, seeds == 1 ? "" : "s");
}

}  // namespace

int run_sweep(const SweepOptions& o) {
  namespace fs = std::filesystem;
  const fs::path dir(o.out_dir);
  prepare_sweep_dir(o.out_dir, {"sweep.csv", "summary.csv", "plots.gp"});

  std::vector<Job> jobs;
  for (const auto& v : kVariants)
    for (const double p : kPValues)
      for (int s = 1; s <= o.seeds; ++s) jobs.push_back({&v, p, static_cast<std::uint64_t>(s), {}});

  run_in_parallel(
      jobs.size(), o.jobs, 20,
      [&](std::size_t i) {
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
      },
      [&](std::size_t i) {
        return fmt::format("{} p={:.1f} % seed {}", jobs[i].variant->name, 100 * jobs[i].p, jobs[i].seed);
      });

  std::string runs =
      "variant,p,seed,velocity_packet_rate,force_packet_rate,force_jnd_violation,position_rmse,"
      "force_rmse,bus_load,realtime_factor\n";

  std::string summary = "variant,p_percent,seeds";
  for (const char* m :
       {"velocity_rate_percent", "force_rate_percent", "jnd_violation_percent", "position_rmse_mrad", "force_rmse_n"})
    summary += fmt::format(",{0},{0}_min,{0}_max", m);
  summary += "\n";
  for (std::size_t i = 0; i < jobs.size(); i += static_cast<std::size_t>(o.seeds)) {
    Spread v, f, jnd, pos, frms;
    for (int s = 0; s < o.seeds; ++s) {
      const Job& job = jobs[i + static_cast<std::size_t>(s)];
      const SimResult& r = job.result;
      runs +=
          fmt::format("{},{},{},{:.6f},{:.6f},{:.6f},{:.6g},{:.6g},{:.6f},{:.0f}\n", job.variant->name, job.p, job.seed,
                      r.velocity_packet_rate, r.force_packet_rate, r.force_jnd_violation, r.position_rmse_rad,
                      r.force_rmse_n, std::max(r.bus_load_hsi, r.bus_load_top), r.realtime_factor);
      v.add(r.velocity_packet_rate);
      f.add(r.force_packet_rate);
      jnd.add(r.force_jnd_violation);
      pos.add(r.position_rmse_rad);
      frms.add(r.force_rmse_n);
    }
    const int n = o.seeds;
    summary += fmt::format("{},{},{}{}{}{}{}{}\n", jobs[i].variant->name, 100 * jobs[i].p, n, v.csv(n, 100, 2),
                           f.csv(n, 100, 2), jnd.csv(n, 100, 2), pos.csv(n, 1000, 3), frms.csv(n, 1, 4));
  }
  program::OutputFile::write_all((dir / "sweep.csv").string(), runs, "--out");
  program::OutputFile::write_all((dir / "summary.csv").string(), summary, "--out");
  program::OutputFile::write_all((dir / "plots.gp").string(), gnuplot_script(scenario_name(o.scenario), o.seeds),
                                 "--out");

  if (const int code = plot_sweep(dir); code != 0) return code;
  fmt::print(
      "sweep: {} runs of {} s ({} seeds per point) -> {}/summary.csv, sweep.csv, packet_rate_velocity.png, "
      "packet_rate_force.png, distortion.png, position_error.png\n",
      jobs.size(), o.duration_s, o.seeds, program::printable(dir.string()));
  return 0;
}

}  // namespace lever::hil
