#include "sweep.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>
#include <numbers>
#include <vector>

#include "lever/hil/simulation.hpp"
#include "lever/program/text.hpp"
#include "report.hpp"
#include "sweep_plots.hpp"
#include "sweep_runner.hpp"
#include "sweep_table.hpp"

namespace lever::hil {
namespace {

constexpr double kPValues[] = {0.0, 0.025, 0.05, 0.075, 0.10, 0.125, 0.15, 0.20, 0.25};

// 16 bits over the levers' range: 65536 counts over the firmware's position limits, -1 to 1 rad.
constexpr double kSixteenBitsOverRange = 65536.0 / 2.0 * 2.0 * std::numbers::pi;

struct Variant {
  const char* name;
  codec::Mode mode;
  bool filter;
  bool floor;
  fw::MotionVelocity velocity = fw::MotionVelocity::difference;  // what the HSI sends
  double counts_per_rev = 16384.0;                               // both levers' encoders
};
// The paper's three modes with its rule (floor 0), the same with the absolute floor, then the paper's rule with the
// two other velocities of docs/hil-model.md: the adaptive-window difference, and the one-tick difference of an
// encoder of 16 bits over the range (read by a hardware counter).
constexpr Variant kVariants[] = {
    {"deadband", codec::Mode::deadband, false, false},
    {"predictive", codec::Mode::predictive, false, false},
    {"predictive+filter", codec::Mode::predictive, true, false},
    {"deadband+floor", codec::Mode::deadband, false, true},
    {"predictive+filter+floor", codec::Mode::predictive, true, true},
    {"deadband+adaptive-window", codec::Mode::deadband, false, false, fw::MotionVelocity::adaptive_window},
    {"deadband+16-bit-encoder", codec::Mode::deadband, false, false, fw::MotionVelocity::difference,
     kSixteenBitsOverRange},
};

struct Job {
  const Variant* variant;
  double p;
  std::uint64_t seed;
  SimResult result;
};

// Each run's metrics: sweep.csv's in the run's units, summary.csv's scaled (percent, mrad).
// The packet rates: every data frame, then by cause (the deadband's are what the paper counts).
const SweepMetric<SimResult> kMetrics[] = {
    {{"velocity_packet_rate", "{:.6f}", "velocity_rate_percent", 100, 2},
     [](const SimResult& r) { return r.velocity_packet_rate; }},
    {{"force_packet_rate", "{:.6f}", "force_rate_percent", 100, 2},
     [](const SimResult& r) { return r.force_packet_rate; }},
    {{"velocity_deadband_rate", "{:.6f}", "velocity_deadband_percent", 100, 2},
     [](const SimResult& r) { return r.velocity_deadband_rate; }},
    {{"velocity_refresh_rate", "{:.6f}", "velocity_refresh_percent", 100, 2},
     [](const SimResult& r) { return r.velocity_refresh_rate; }},
    {{"velocity_rest_repeat_rate", "{:.6f}", "velocity_rest_repeat_percent", 100, 2},
     [](const SimResult& r) { return r.velocity_rest_repeat_rate; }},
    {{"force_deadband_rate", "{:.6f}", "force_deadband_percent", 100, 2},
     [](const SimResult& r) { return r.force_deadband_rate; }},
    {{"velocity_deadband_contact_rate", "{:.6f}", "velocity_deadband_contact_percent", 100, 2},
     [](const SimResult& r) { return r.velocity_deadband_contact_rate; }},
    {{"velocity_deadband_free_rate", "{:.6f}", "velocity_deadband_free_percent", 100, 2},
     [](const SimResult& r) { return r.velocity_deadband_rate - r.velocity_deadband_contact_rate; }},
    {{"force_deadband_contact_rate", "{:.6f}", "force_deadband_contact_percent", 100, 2},
     [](const SimResult& r) { return r.force_deadband_contact_rate; }},
    {{"force_deadband_free_rate", "{:.6f}", "force_deadband_free_percent", 100, 2},
     [](const SimResult& r) { return r.force_deadband_rate - r.force_deadband_contact_rate; }},
    {{"force_refresh_rate", "{:.6f}", "force_refresh_percent", 100, 2},
     [](const SimResult& r) { return r.force_refresh_rate; }},
    {{"force_rest_repeat_rate", "{:.6f}", "force_rest_repeat_percent", 100, 2},
     [](const SimResult& r) { return r.force_rest_repeat_rate; }},
    {{"force_jnd_violation", "{:.6f}", "jnd_violation_percent", 100, 2},
     [](const SimResult& r) { return r.force_jnd_violation; }},
    {{"hand_jnd_violation", "{:.6f}", "hand_jnd_violation_percent", 100, 2},
     [](const SimResult& r) { return r.hand_jnd_violation; }},
    {{"hand_force_rmse", "{:.6g}", "hand_force_rmse_n", 1, 4}, [](const SimResult& r) { return r.hand_force_rmse_n; }},
    {{"position_rmse", "{:.6g}", "position_rmse_mrad", 1000, 3},
     [](const SimResult& r) { return r.position_rmse_rad; }},
    {{"force_rmse", "{:.6g}", "force_rmse_n", 1, 4}, [](const SimResult& r) { return r.force_rmse_n; }},
    {{"bus_load", "{:.6f}", nullptr, 1, 0},
     [](const SimResult& r) { return std::max(r.bus_load_hsi, r.bus_load_top); }},
    {{"realtime_factor", "{:.0f}", nullptr, 1, 0}, [](const SimResult& r) { return r.realtime_factor; }},
};

PlotPanel panel(const std::string& metric, const std::string& ylabel = "", const std::string& yrange = "",
                const std::string& paper = "") {
  return {"", ylabel, yrange, "", {{metric, ""}}, paper};
}

PlotSpec plots(const std::string& scenario, const std::string& setup, int seeds) {
  const std::string spread =
      fmt::format("\\n{}; mean of {} seed{}; bars: min to max", setup, seeds, seeds == 1 ? "" : "s");
  const std::string paper = "\"-\" using 1:2 with points pt 7 ps 1.5 lc rgb \"black\" title \"paper, Fig. 8\"\n";
  PlotSpec p{"lever-hil sweep", "p_percent", "deadband parameter p [%]", "[0:25]", "variant", {}, "", {}};
  for (const auto& v : kVariants) p.series.emplace_back(v.name);
  p.figures = {
      {"packet_rate_velocity.png",
       "900,650",
       scenario + ": velocity packets HSI -> TOP, the deadband's (cf. the paper's Fig. 8)" + spread,
       {panel("velocity_deadband_percent", "packet rate [% of 1 kHz]", "[0:100]", paper + "10,25\ne\n")}},
      {"packet_rate_force.png",
       "900,650",
       scenario + ": force packets TOP -> HSI, the deadband's (cf. the paper's Fig. 8)" + spread,
       {panel("force_deadband_percent", "", "", paper + "2.5,10\n10,15\ne\n")}},
      {"distortion.png",
       "1200,600",
       scenario + ": force off the measured one by more than a JND" + spread,
       {{"displayed (the HSI's reconstruction)", "share of time [%]", "[0:*]", "", {{"jnd_violation_percent", ""}}, ""},
        {"on the hand (its force on the handle)", "", "", "", {{"hand_jnd_violation_percent", ""}}, ""}}},
      {"position_error.png",
       "900,650",
       scenario + ": TOP position error (RMS against the HSI)" + spread,
       {panel("position_rmse_mrad", "position RMSE [mrad]")}},
  };
  return p;
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
        c.scenario = *lever_scenario(o.scenario);  // the sphere is sphere_sweep.cpp's
        c.duration_s = o.duration_s;
        c.seed = job.seed;
        const bool filter = job.variant->filter;
        c.velocity_codec = {job.variant->mode, job.p, job.variant->floor ? o.velocity_variants.floor : 0.0,
                            filter ? o.velocity_variants.filter_hz : 0.0};
        c.force_codec = {job.variant->mode, job.p, job.variant->floor ? o.force_variants.floor : 0.0,
                         filter ? o.force_variants.filter_hz : 0.0};
        c.topology = o.topology;
        c.gauge_chain = o.gauge_chain;
        set_hsi_force_loop(c, o.hsi_force_loop);
        c.hsi_firmware.motion_velocity = job.variant->velocity;
        c.hsi_firmware.counts_per_rev = c.top_firmware.counts_per_rev = job.variant->counts_per_rev;
        if (job.variant->counts_per_rev > 16384.0) c.encoder_interface = EncoderInterface::counter;
        job.result = run_simulation(c);
      },
      [&](std::size_t i) {
        return fmt::format("{} p={:.1f} % seed {}", jobs[i].variant->name, 100 * jobs[i].p, jobs[i].seed);
      });

  SweepTable table("variant,p", "variant,p_percent", sweep_columns(kMetrics));
  for (const Job& job : jobs) {
    table.add_run(fmt::format("{},{}", job.variant->name, job.p), job.seed, sweep_values(kMetrics, job.result));
    if (job.seed == static_cast<std::uint64_t>(o.seeds))
      table.end_point(fmt::format("{},{}", job.variant->name, 100 * job.p));
  }
  const std::string setup = fmt::format("{}, {} gauge chain, HSI force loop {}", name(o.topology),
                                        o.gauge_chain == GaugeChain::paper_adc ? "the paper's" : "DAD 141.1",
                                        o.hsi_force_loop ? "on" : "off");
  write_sweep(dir, table, gnuplot_script(plots(std::string(name(o.scenario)), setup, o.seeds)));

  if (const int code = plot_sweep(dir); code != 0) return code;
  fmt::print(
      "sweep: {} runs of {} s ({} seeds per point) -> {}/summary.csv, sweep.csv, packet_rate_velocity.png, "
      "packet_rate_force.png, distortion.png, position_error.png\n",
      jobs.size(), o.duration_s, o.seeds, program::printable(dir.string()));
  return 0;
}

}  // namespace lever::hil
