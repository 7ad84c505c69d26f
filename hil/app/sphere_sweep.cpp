#include "sphere_sweep.hpp"

#include <fmt/format.h>

#include <filesystem>
#include <vector>

#include "lever/hil/sphere3dof.hpp"
#include "lever/program/output_file.hpp"
#include "lever/program/text.hpp"
#include "sweep_plots.hpp"
#include "sweep_runner.hpp"
#include "sweep_table.hpp"

namespace lever::hil {
namespace {

// The paper's deadband values in IV-B-3.
constexpr double kPValues[] = {0.0, 0.025, 0.05, 0.075, 0.10, 0.125, 0.15, 0.20, 0.25, 0.30, 0.35, 0.40};

struct Variant {
  const char* name;
  codec::Mode mode;
  bool filter;
};
constexpr Variant kVariants[] = {
    {"3-DoF", codec::Mode::deadband, false},
    {"3-DoF LP", codec::Mode::predictive, false},
    {"3-DoF LP+filter", codec::Mode::predictive, true},
};
constexpr SphereDirection kDirections[] = {SphereDirection::velocity, SphereDirection::force};
const char* direction_name(SphereDirection d) { return d == SphereDirection::velocity ? "velocity" : "force"; }

// The velocity the OP reads (docs/hil-model.md): the driver's chain at its 20 Hz, the default, then for the
// velocity direction the one-tick difference and the driver at half and twice the cut-off.
struct Chain {
  const char* name;
  SphereVelocityChain chain;
  double cutoff_hz;
};
constexpr Chain kChains[] = {
    {"driver 20 Hz", SphereVelocityChain::driver, 20.0},
    {"difference", SphereVelocityChain::difference, 20.0},
    {"driver 10 Hz", SphereVelocityChain::driver, 10.0},
    {"driver 40 Hz", SphereVelocityChain::driver, 40.0},
};

struct Job {
  const Variant* variant;
  SphereDirection direction;
  const Chain* chain;
  double p;
  std::uint64_t seed;
  SphereResult result;
};

// The paper's Fig. 12 points, read off its text (docs/hil-model.md gives the sentence for each).
constexpr char kPaperPoints[] =
    "direction,variant,p_percent,rate_percent,source\n"
    "force,3-DoF,0,87,contact about 87 % of the time at 0 % deadband\n"
    "velocity,3-DoF,20,25,reduced by almost 75 % at 20 %\n"
    "force,3-DoF,5,10,reduction by almost 90 % at 5 %\n"
    "velocity,3-DoF LP,20,17,total savings 83 %\n"
    "force,3-DoF LP,5,7,total savings 93 %\n"
    "force,3-DoF LP,2.5,16,derived: LP+filter improves on it by 55 % and reaches 7 %\n"
    "force,3-DoF LP+filter,2.5,7.4,7.4 % for force at 2.5 %\n"
    "velocity,3-DoF LP+filter,7.5,8.7,8.7 % for velocity at 7.5 %\n";

const SweepMetric<SphereResult> kMetrics[] = {
    {{"velocity_packet_rate", "{:.6f}", "velocity_rate_percent", 100, 2},
     [](const SphereResult& r) { return r.velocity_packet_rate; }},
    {{"force_packet_rate", "{:.6f}", "force_rate_percent", 100, 2},
     [](const SphereResult& r) { return r.force_packet_rate; }},
    {{"velocity_contact_rate", "{:.6f}", "velocity_contact_percent", 100, 2},
     [](const SphereResult& r) { return r.velocity_contact_rate; }},
    {{"velocity_free_rate", "{:.6f}", "velocity_free_percent", 100, 2},
     [](const SphereResult& r) { return r.velocity_packet_rate - r.velocity_contact_rate; }},
    {{"force_contact_rate", "{:.6f}", "force_contact_percent", 100, 2},
     [](const SphereResult& r) { return r.force_contact_rate; }},
    {{"force_free_rate", "{:.6f}", "force_free_percent", 100, 2},
     [](const SphereResult& r) { return r.force_packet_rate - r.force_contact_rate; }},
    {{"force_jnd_violation", "{:.6f}", "jnd_violation_percent", 100, 2},
     [](const SphereResult& r) { return r.force_jnd_violation; }},
    {{"downlink_jnd_violation", "{:.6f}", "downlink_jnd_violation_percent", 100, 2},
     [](const SphereResult& r) { return r.downlink_jnd_violation; }},
    {{"contact_share", "{:.6f}", "contact_percent", 100, 1}, [](const SphereResult& r) { return r.contact_share; }},
    {{"position_rmse_m", "{:.6g}", "position_rmse_um", 1e6, 1},
     [](const SphereResult& r) { return r.position_rmse_m; }},
    {{"force_rmse_n", "{:.6g}", "force_rmse_n", 1, 4}, [](const SphereResult& r) { return r.force_rmse_n; }},
    {{"realtime_factor", "{:.0f}", nullptr, 1, 0}, [](const SphereResult& r) { return r.realtime_factor; }},
};

// One direction's deadband with one velocity chain: its rows, and in the packet rates the paper's points.
PlotPanel panel(const char* direction, const std::string& title, const std::string& metric, bool paper = false,
                const char* chain = kChains[0].name) {
  const std::string direction_row = fmt::format("strcol(\"direction\") eq \"{}\"", direction);
  const std::string row = fmt::format("{} && strcol(\"velocity_chain\") eq \"{}\"", direction_row, chain);
  PlotPanel p{title, "", "", row, {{metric, ""}}, ""};
  if (paper)
    p.extra = fmt::format(
        "for [i=1:3] paper using \"p_percent\":(({} && strcol(\"variant\") eq series(i)) ? column(\"rate_percent\") "
        ": 1/0) with points pt 7 ps 1.6 lc i title \"paper \".series(i)",
        direction_row);
  return p;
}

PlotSpec plots(int seeds) {
  const std::string spread = fmt::format("\\nmean of {} seed{}; bars: min to max", seeds, seeds == 1 ? "" : "s");
  PlotSpec s{"lever-hil sweep --scenario sphere-3dof", "p_percent", "deadband parameter p [%]", "[0:40]", "variant", {},
             "paper = dir . \"paper_fig12.csv\"\n",    {}};
  for (const auto& v : kVariants) s.series.emplace_back(v.name);
  PlotPanel velocity_rate =
      panel("velocity", "velocity OP -> TOP (deadband on velocity)", "velocity_rate_percent", true);
  velocity_rate.ylabel = "packet rate [% of 1 kHz]";
  velocity_rate.yrange = "[0:100]";
  PlotPanel velocity_distortion = panel("velocity", "deadband on velocity", "jnd_violation_percent");
  velocity_distortion.ylabel = "share of time [%]";
  velocity_distortion.yrange = "[0:*]";
  PlotPanel position = panel("velocity", "", "position_rmse_um");
  position.ylabel = "position RMSE [um]";
  PlotFigure chains{
      "velocity_chains.png",
      "1600,520",
      "sphere-3dof: velocity packets OP -> TOP (deadband on velocity) by the velocity the OP reads" + spread,
      {}};
  for (const auto& chain : kChains) {
    PlotPanel p = panel("velocity", chain.name, "velocity_rate_percent", true, chain.name);
    p.ylabel = "packet rate [% of 1 kHz]";
    p.yrange = "[0:100]";
    chains.panels.push_back(p);
  }
  s.figures = {
      {"fig12_packet_rates.png",
       "1200,520",
       "sphere-3dof: packet rates (cf. the paper's Fig. 12; points: the paper's text); the driver's velocity at 20 Hz" +
           spread,
       {velocity_rate, panel("force", "force TOP -> OP (deadband on force)", "force_rate_percent", true)}},
      chains,
      {"distortion.png",
       "1200,520",
       "sphere-3dof: displayed force off the undistorted system's by more than a JND" + spread,
       {velocity_distortion, panel("force", "deadband on force", "jnd_violation_percent")}},
      {"position_error.png", "900,600", "sphere-3dof: TOP position error, deadband on velocity" + spread, {position}},
  };
  return s;
}

}  // namespace

int run_sphere_sweep(const SweepOptions& o) {
  namespace fs = std::filesystem;
  const fs::path dir(o.out_dir);
  prepare_sweep_dir(o.out_dir, {"sweep.csv", "summary.csv", "paper_fig12.csv", "plots.gp"});

  std::vector<Job> jobs;
  for (const auto direction : kDirections)
    for (const auto& chain : kChains) {
      if (direction == SphereDirection::force && &chain != &kChains[0]) continue;
      for (const auto& v : kVariants)
        for (const double p : kPValues)
          for (int s = 1; s <= o.seeds; ++s)
            jobs.push_back({&v, direction, &chain, p, static_cast<std::uint64_t>(s), {}});
    }

  run_in_parallel(
      jobs.size(), o.jobs, 50,
      [&](std::size_t i) {
        Job& job = jobs[i];
        SphereConfig c = sphere_variant(job.direction, job.variant->mode, job.variant->filter, job.p);
        c.velocity_chain = job.chain->chain;
        c.driver_cutoff_hz = job.chain->cutoff_hz;
        c.duration_s = o.duration_s;
        c.seed = job.seed;
        job.result = run_sphere(c);
      },
      [&](std::size_t i) {
        const Job& job = jobs[i];
        return fmt::format("{} {} ({}) p={:.1f} % seed {}", direction_name(job.direction), job.variant->name,
                           job.chain->name, 100 * job.p, job.seed);
      });

  SweepTable table("direction,velocity_chain,variant,p", "direction,velocity_chain,variant,p_percent",
                   sweep_columns(kMetrics));
  for (const Job& job : jobs) {
    const char* direction = direction_name(job.direction);
    table.add_run(fmt::format("{},{},{},{}", direction, job.chain->name, job.variant->name, job.p), job.seed,
                  sweep_values(kMetrics, job.result));
    if (job.seed == static_cast<std::uint64_t>(o.seeds))
      table.end_point(fmt::format("{},{},{},{}", direction, job.chain->name, job.variant->name, 100 * job.p));
  }
  write_sweep(dir, table, gnuplot_script(plots(o.seeds)));
  program::OutputFile::write_all((dir / "paper_fig12.csv").string(), kPaperPoints, "--out");

  if (const int code = plot_sweep(dir); code != 0) return code;
  fmt::print(
      "sweep: {} runs of {} s ({} seeds per point) -> {}/summary.csv, sweep.csv, paper_fig12.csv, "
      "fig12_packet_rates.png, velocity_chains.png, distortion.png, position_error.png\n",
      jobs.size(), o.duration_s, o.seeds, dir.string());
  return 0;
}

}  // namespace lever::hil
