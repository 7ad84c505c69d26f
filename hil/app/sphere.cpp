#include "sphere.hpp"

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <optional>
#include <stdexcept>

#include "lever/program/output_file.hpp"
#include "lever/program/text.hpp"
#include "report.hpp"

namespace lever::hil {
namespace {

constexpr const char* kTraceHeader =
    "t,x,y,z,measured_x,measured_y,measured_z,velocity_x,velocity_y,velocity_z,velocity_sent,"
    "top_x,top_y,top_z,env_force_x,env_force_y,env_force_z,force_sent,displayed_x,displayed_y,"
    "displayed_z,reference_x,reference_y,reference_z\n";

std::string trace_csv_row(const SphereTraceRow& row) {
  fmt::memory_buffer out;
  auto vec = [&](const Vec3& v) { fmt::format_to(std::back_inserter(out), ",{:.9g},{:.9g},{:.9g}", v[0], v[1], v[2]); };
  fmt::format_to(std::back_inserter(out), "{:.3f}", row.t);
  vec(row.position);
  vec(row.measured);
  vec(row.velocity);
  fmt::format_to(std::back_inserter(out), ",{:d}", row.velocity_sent ? 1 : 0);
  vec(row.top_position);
  vec(row.environment_force);
  fmt::format_to(std::back_inserter(out), ",{:d}", row.force_sent ? 1 : 0);
  vec(row.displayed_force);
  vec(row.reference_force);
  out.push_back('\n');
  return fmt::to_string(out);
}

}  // namespace

SphereConfig sphere_config_from(const SimConfig& run, const RunOptions& options) {
  if (!run.faults.empty())
    throw std::invalid_argument("sphere-3dof has no levers: --fault applies to the lever scenarios only");
  if (run.topology != Topology::two_sites)
    throw std::invalid_argument("sphere-3dof has no CAN sites: its two PCs talk over a LAN (--delay-ms, --jitter-ms)");
  SphereConfig c;
  c.duration_s = run.duration_s;
  c.seed = run.seed;
  c.velocity_codec = run.velocity_codec;
  c.force_codec = run.force_codec;
  c.network.delay_ms = run.network.delay_ms;
  c.network.jitter_ms = run.network.jitter_ms;
  c.network.loss = run.network.loss;
  c.record_trace = run.record_trace;
  c.velocity_chain = options.device_velocity.value_or(c.velocity_chain);
  c.driver_cutoff_hz = options.driver_cutoff_hz.value_or(c.driver_cutoff_hz);
  c.position_sensor = options.position_sensor.value_or(c.position_sensor);
  c.top_clock = options.top_clock.value_or(c.top_clock);
  c.device.encoder_counts_per_rev = options.device_encoder_counts.value_or(c.device.encoder_counts_per_rev);
  return c;
}

nlohmann::json sphere_report_json(const SphereConfig& c, const SphereResult& r) {
  return {
      {"scenario", "sphere-3dof"},
      {"duration_s", c.duration_s},
      {"seed", c.seed},
      {"velocity_packet_rate", r.velocity_packet_rate},
      {"force_packet_rate", r.force_packet_rate},
      {"velocity_contact_rate", r.velocity_contact_rate},
      {"velocity_free_rate", r.velocity_packet_rate - r.velocity_contact_rate},
      {"force_contact_rate", r.force_contact_rate},
      {"force_free_rate", r.force_packet_rate - r.force_contact_rate},
      {"contact_share", r.contact_share},
      {"mean_contact_force_n", r.mean_contact_force_n},
      {"saturated_share", r.saturated_share},
      {"force_jnd_violation", r.force_jnd_violation},
      {"downlink_jnd_violation", r.downlink_jnd_violation},
      {"force_rmse", r.force_rmse_n},
      {"position_rmse_m", r.position_rmse_m},
      {"position_max_error_m", r.position_max_error_m},
      {"zero_velocity_share", r.zero_velocity_share},
      {"mean_speed_mps", r.mean_speed_mps},
      {"packets", {{"velocity", r.velocity_packets}, {"force", r.force_packets}, {"stale", r.stale_packets}}},
      {"nominal_delay_ticks", {{"op_to_top", r.uplink_delay_ticks}, {"top_to_op", r.downlink_delay_ticks}}},
      {"top_clock", {{"phase_ms", r.top_clock_phase_ms}, {"drift_ppm", r.top_clock_drift_ppm}, {"ticks", r.top_ticks}}},
      {"parameters",
       {{"velocity", codec_json(c.velocity_codec)},
        {"force", codec_json(c.force_codec)},
        {"delay_ms", c.network.delay_ms},
        {"jitter_ms", c.network.jitter_ms},
        {"loss", c.network.loss},
        {"device_velocity", name(c.velocity_chain)},
        {"driver_cutoff_hz", c.driver_cutoff_hz},
        {"position_sensor", name(c.position_sensor)},
        {"top_clock", name(c.top_clock)},
        {"top_clock_drift_ppm_max", c.top_clock_drift_ppm_max},
        {"jnd", c.jnd},
        {"jnd_absolute_n", c.jnd_absolute_n},
        {"substeps", c.substeps},
        {"device",
         {{"resolution_m", c.device.resolution_m},
          {"encoder_counts_per_rev", c.device.encoder_counts_per_rev},
          {"link_m", c.device.link_m},
          {"max_force_n", c.device.max_force_n},
          {"mass_kg", c.device.mass_kg},
          {"friction_n", c.device.friction_n}}},
        {"hand",
         {{"mass_kg", c.hand.mass_kg},
          {"stiffness", c.hand.stiffness},
          {"damping", c.hand.damping},
          {"tremor_rms_m", c.hand.tremor_rms_m},
          {"tremor_band_hz", {c.hand.tremor_low_hz, c.hand.tremor_high_hz}}}},
        {"sphere", {{"radius_m", c.sphere.radius_m}, {"stiffness", c.sphere.stiffness}}}}},
      {"realtime_factor", r.realtime_factor},
      {"wall_time_s", r.wall_time_s},
  };
}

int run_sphere_command(const SphereConfig& config, bool json, const std::string& trace_path) {
  SphereConfig c = config;
  c.record_trace = !trace_path.empty();
  std::optional<program::OutputFile> trace;  // checked before the run, streamed as it goes
  if (!trace_path.empty()) {
    trace.emplace(trace_path, "--trace");
    trace->write(kTraceHeader);
    c.trace_sink = [&trace](const SphereTraceRow& row) { trace->write(trace_csv_row(row)); };
  }
  const SphereResult r = run_sphere(c);
  if (trace) trace->commit();
  std::FILE* out = trace && trace->is_stdout() ? stderr : stdout;  // the trace has stdout
  if (json) {
    fmt::print(out, "{}\n", sphere_report_json(c, r).dump());
    return 0;
  }
  fmt::print(out, "sphere-3dof for {} s (seed {}), velocity {} p={} filter={} Hz, force {} p={} filter={} Hz\n",
             c.duration_s, c.seed, codec::name(c.velocity_codec.mode), c.velocity_codec.p, c.velocity_codec.filter_hz,
             codec::name(c.force_codec.mode), c.force_codec.p, c.force_codec.filter_hz);
  fmt::print(out, "  packets: velocity {:.1f} %, force {:.1f} % of 1 kHz\n", 100 * r.velocity_packet_rate,
             100 * r.force_packet_rate);
  fmt::print(out, "    in contact / in free space: velocity {:.1f} % / {:.1f} %, force {:.1f} % / {:.1f} %\n",
             100 * r.velocity_contact_rate, 100 * (r.velocity_packet_rate - r.velocity_contact_rate),
             100 * r.force_contact_rate, 100 * (r.force_packet_rate - r.force_contact_rate));
  fmt::print(out, "  in contact {:.0f} % of the time at {:.2f} N on average (above the device's peak {:.1f} %)\n",
             100 * r.contact_share, r.mean_contact_force_n, 100 * r.saturated_share);
  fmt::print(
      out,
      "  force off the undistorted system's by more than a JND {:.1f} % of the time (off the TOP's own {:.1f} %), rmse "
      "{:.3f} N; TOP position rmse {:.0f} um, max {:.0f} um\n",
      100 * r.force_jnd_violation, 100 * r.downlink_jnd_violation, r.force_rmse_n, 1e6 * r.position_rmse_m,
      1e6 * r.position_max_error_m);
  fmt::print(out, "  velocity exactly zero in {:.0f} % of samples; mean speed {:.0f} mm/s; {:.0f}x real time\n",
             100 * r.zero_velocity_share, 1000 * r.mean_speed_mps, r.realtime_factor);
  return 0;
}

}  // namespace lever::hil
