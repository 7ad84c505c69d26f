#include "delay_sweep.hpp"

#include <fmt/format.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/program/text.hpp"
#include "sweep_plots.hpp"
#include "sweep_runner.hpp"
#include "sweep_table.hpp"

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

// Each metric in the plots' units, in both files: sweep.csv with two more decimals than summary.csv.
double armed_s(const SimResult& r) { return static_cast<double>(r.armed_ticks) * 1e-3; }
const SweepMetric<SimResult> kMetrics[] = {
    {{"velocity_rate_percent", "{:.4f}", "velocity_rate_percent", 1, 2},
     [](const SimResult& r) { return 100 * r.velocity_packet_rate; }},
    {{"force_rate_percent", "{:.4f}", "force_rate_percent", 1, 2},
     [](const SimResult& r) { return 100 * r.force_packet_rate; }},
    {{"energy_frames_per_s", "{:.3f}", "energy_frames_per_s", 1, 1},
     [](const SimResult& r) { return static_cast<double>(r.energy_frames) / armed_s(r); }},
    {{"datagrams_per_s", "{:.3f}", "datagrams_per_s", 1, 1},
     [](const SimResult& r) { return static_cast<double>(r.network_sent) / armed_s(r); }},
    {{"jnd_violation_percent", "{:.4f}", "jnd_violation_percent", 1, 2},
     [](const SimResult& r) { return 100 * r.force_jnd_violation; }},
    {{"force_rmse_n", "{:.6f}", "force_rmse_n", 1, 4}, [](const SimResult& r) { return r.force_rmse_n; }},
    {{"contact_onsets_per_s", "{:.5f}", "contact_onsets_per_s", 1, 3},
     [](const SimResult& r) { return r.contact_onsets_per_s; }},
    {{"protection_trips", "{:.4f}", "protection_trips", 1, 2},
     [](const SimResult& r) { return static_cast<double>(r.hsi_lever_faults.count + r.top_lever_faults.count); }},
    {{"hsi_dissipated_j", "{:.6f}", "hsi_dissipated_j", 1, 4},
     [](const SimResult& r) { return r.hsi_dissipated_energy_j; }},
    {{"top_dissipated_j", "{:.6f}", "top_dissipated_j", 1, 4},
     [](const SimResult& r) { return r.top_dissipated_energy_j; }},
    {{"hsi_min_observed_j", "{:.6f}", "hsi_min_observed_j", 1, 4},
     [](const SimResult& r) { return r.hsi_min_observed_energy_j; }},
    {{"top_min_observed_j", "{:.6f}", "top_min_observed_j", 1, 4},
     [](const SimResult& r) { return r.top_min_observed_energy_j; }},
    {{"position_rmse_mrad", "{:.4f}", "position_rmse_mrad", 1, 2},
     [](const SimResult& r) { return 1e3 * r.position_rmse_rad; }},
};

PlotPanel panel(const std::string& title, const std::string& ylabel, std::vector<PlotMetric> metrics,
                const std::string& yrange = "") {
  return {title, ylabel, yrange, "", std::move(metrics), ""};
}

PlotSpec plots(double p, int seeds) {
  const std::string spread =
      fmt::format("\\nwall-tap, p = {:g} %, mean of {} seed{}; bars: min to max; without = passivity observe", 100 * p,
                  seeds, seeds == 1 ? "" : "s");
  PlotSpec s{"lever-hil sweep --over delay",
             "delay_ms",
             "one-way delay [ms] (jitter a tenth of it, 1 % loss from 10 ms on)",
             "",
             "variant",
             {},
             "set offsets graph 0.03, graph 0.03, 0, 0\n",
             {}};
  for (const auto& v : kVariants) s.series.emplace_back(v.name);
  s.figures = {
      {"delay_packet_rates.png",
       "1200,520",
       "packet rates against delay" + spread,
       {panel("data frames", "packet rate [% of 1 kHz]",
              {{"velocity_rate_percent", "velocity"}, {"force_rate_percent", "force"}}, "[0:*]"),
        panel("on the link", "frames or datagrams per second",
              {{"energy_frames_per_s", "energy frames/s"}, {"datagrams_per_s", "datagrams/s"}})}},
      {"delay_force_error.png",
       "1200,520",
       "displayed force against delay" + spread,
       {panel("off by more than a JND", "share of time [%]", {{"jnd_violation_percent", ""}}),
        panel("RMS error against the TOP's measurement", "force RMSE [N]", {{"force_rmse_n", ""}})}},
      {"delay_chatter.png",
       "1200,520",
       "contact against delay" + spread,
       {panel("chatter: the TOP's wall contact beginning", "contact onsets per second", {{"contact_onsets_per_s", ""}}),
        panel("protection trips (TORQUE_LIMIT, POSITION_LIMIT, PEER_STATE)", "armed -> fault, both levers, per run",
              {{"protection_trips", ""}})}},
      {"delay_energy.png",
       "1200,520",
       "passivity against delay" + spread,
       {panel("energy the controllers dissipated", "energy [J]",
              {{"hsi_dissipated_j", "HSI"}, {"top_dissipated_j", "TOP"}}),
        panel("the observers' lowest energy (below 0: the channel made energy)", "",
              {{"hsi_min_observed_j", "HSI"}, {"top_min_observed_j", "TOP"}}, "[*:*]")}},
      {"delay_position.png",
       "900,650",
       "TOP position error (RMS against the HSI)" + spread,
       {panel("", "position RMSE [mrad]", {{"position_rmse_mrad", ""}}, "[0:*]")}},
  };
  return s;
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
        c.velocity_codec = c.force_codec = o.delay_codec;
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

  SweepTable table("variant,delay_ms", "variant,delay_ms", sweep_columns(kMetrics));
  for (const Job& job : jobs) {
    const std::string keys = fmt::format("{},{:g}", job.variant->name, job.delay_ms);
    table.add_run(keys, job.seed, sweep_values(kMetrics, job.result));
    if (job.seed == static_cast<std::uint64_t>(o.seeds)) table.end_point(keys);
  }
  write_sweep(dir, table, gnuplot_script(plots(o.delay_codec.p, o.seeds)));

  if (const int code = plot_sweep(dir); code != 0) return code;
  fmt::print(
      "sweep: {} runs of {} s ({} seeds per point) -> {}/summary.csv, sweep.csv, delay_packet_rates.png, "
      "delay_force_error.png, delay_chatter.png, delay_energy.png, delay_position.png\n",
      jobs.size(), o.duration_s, o.seeds, program::printable(dir.string()));
  return 0;
}

}  // namespace lever::hil
