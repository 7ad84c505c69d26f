#include "report.hpp"

#include <fmt/format.h>

#include "lever/protocol/fault_names.hpp"

namespace lever::hil {
nlohmann::json codec_json(const codec::Config<double>& c) {
  return {{"mode", std::string(codec::name(c.mode))}, {"p", c.p}, {"floor", c.floor}, {"filter_hz", c.filter_hz}};
}

namespace {

nlohmann::json optional_json(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(); }

nlohmann::json reaction_json(const FaultReport::LeverReaction& r, double injected) {
  nlohmann::json j{{"fault_at_s", optional_json(r.fault_at_s)},
                   {"latched_faults", r.latched},
                   {"safe_at_s", optional_json(r.safe_at_s)},
                   {"max_torque_nm", r.max_torque_nm_during},
                   {"rearmed_at_s", optional_json(r.rearmed_at_s)}};
  j["reaction"] = !r.fault_at_s ? "no fault raised"
                  : r.safe_at_s ? "safe behaviour " + std::to_string(std::lround((*r.safe_at_s - injected) * 1000)) +
                                      " ms after injection"
                                : "never reached its safe behaviour";
  return j;
}

}  // namespace

std::string trace_csv_header() {
  return "t,hsi_angle,top_angle,hsi_velocity,top_position_ref,contact_force,measured_force,displayed_force,"
         "hsi_torque,top_torque,hand_force,motion_sent,force_sent,hsi_state,top_state\n";
}

std::string trace_csv_row(const TraceRow& r) {
  return fmt::format("{:.3f},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{:.6g},{},{},{},{}\n", r.t,
                     r.hsi_angle, r.top_angle, r.hsi_velocity, r.top_position_ref, r.contact_force, r.measured_force,
                     r.displayed_force, r.hsi_torque, r.top_torque, r.hand_force, r.motion_sent, r.force_sent,
                     r.hsi_state, r.top_state);
}

nlohmann::json lever_faults_json(const SimResult::LeverFaults& f) {
  return {{"count", f.count}, {"faults", protocol::fault_name_list(f.bits)}};
}

// What the run was configured with.
nlohmann::json parameters_json(const SimConfig& config) {
  return {{"velocity", codec_json(config.velocity_codec)},
          {"force", codec_json(config.force_codec)},
          {"topology", name(config.topology)},
          {"delay_ms", config.network.delay_ms},
          {"jitter_ms", config.network.jitter_ms},
          {"loss", config.network.loss},
          {"comms_timeout_ms", config.top_firmware.comms_timeout},
          {"rest_repeat_ms", config.top_firmware.rest_repeat},
          {"passivity", fw::name(config.top_firmware.passivity.mode)},
          {"passivity_reserve_j", config.top_firmware.passivity.reserve_j},
          {"passivity_reserve_share", config.top_firmware.passivity.reserve_share},
          {"passivity_display_spend_s", config.hsi_firmware.passivity.display_spend_time_s},
          {"passivity_drift_gain_per_s", config.top_firmware.passivity.drift_gain_per_s},
          {"homing", config.homing},
          {"hsi_force_loop", config.hsi_firmware.display.closed_loop && config.hsi_firmware.use_force_sensor},
          {"encoder_counts_per_turn", config.hsi_firmware.counts_per_rev},
          {"encoder_interface", name(config.encoder_interface)},
          {"motion_velocity", fw::name(config.hsi_firmware.motion_velocity)},
          {"operator_speed", config.operator_params.speed_factor},
          {"operator_dwell", config.operator_params.dwell_factor},
          {"jnd", config.jnd},
          {"jnd_absolute_n", config.jnd_absolute_n},
          {"substeps", config.substeps},
          {"wall_stiffness", config.wall.stiffness},
          {"gauge_chain", name(reads_paper_gauge(config) ? GaugeChain::paper_adc : GaugeChain::dad141)},
          {"gauge_noise_n", effective_gauge(config).noise_n},
          {"gauge_filter_hz", effective_gauge(config).filter_hz},
          {"gauge_rate_hz", effective_gauge(config).output_rate_hz()},
          {"gauge_step_n", effective_gauge(config).step_n}};
}

// Each injected fault and each lever's reaction to it.
nlohmann::json faults_json(const SimResult& r) {
  nlohmann::json faults = nlohmann::json::array();
  for (const auto& f : r.faults) {
    faults.push_back(
        {{"spec", f.spec.text},
         {"kind", std::string(to_string(f.spec.kind))},
         {"injected_at_s", f.spec.start_s},
         {"ends_at_s",
          std::isfinite(f.spec.duration_s) ? nlohmann::json(f.spec.start_s + f.spec.duration_s) : nlohmann::json()},
         {"hsi", reaction_json(f.hsi, f.spec.start_s)},
         {"top", reaction_json(f.top, f.spec.start_s)}});
  }
  return faults;
}

nlohmann::json report_json(const SimConfig& config, const SimResult& r) {
  return {
      {"scenario", name(config.scenario)},
      {"duration_s", config.duration_s},
      {"seed", config.seed},
      {"velocity_packet_rate", r.velocity_packet_rate},
      {"force_packet_rate", r.force_packet_rate},
      {"velocity_deadband_rate", r.velocity_deadband_rate},
      {"velocity_refresh_rate", r.velocity_refresh_rate},
      {"velocity_rest_repeat_rate", r.velocity_rest_repeat_rate},
      {"force_deadband_rate", r.force_deadband_rate},
      {"force_refresh_rate", r.force_refresh_rate},
      {"force_rest_repeat_rate", r.force_rest_repeat_rate},
      {"velocity_deadband_contact_rate", r.velocity_deadband_contact_rate},
      {"velocity_deadband_free_rate", r.velocity_deadband_rate - r.velocity_deadband_contact_rate},
      {"force_deadband_contact_rate", r.force_deadband_contact_rate},
      {"force_deadband_free_rate", r.force_deadband_rate - r.force_deadband_contact_rate},
      {"position_rmse", r.position_rmse_rad},
      {"force_rmse", r.force_rmse_n},
      {"force_jnd_violation", r.force_jnd_violation},
      {"hand_force_rmse", r.hand_force_rmse_n},
      {"hand_jnd_violation", r.hand_jnd_violation},
      {"force_distortion_by_cause",
       {{"link", r.force_jnd_violation_link},
        {"codec", r.force_jnd_violation_codec},
        {"filter", r.force_jnd_violation_filter},
        {"nominal_delay_ticks", r.nominal_delay_ticks},
        {"prefilter_delay_ms", r.prefilter_delay_ms}}},
      {"deadband_frames", r.motion_frames + r.force_frames - r.refresh_frames},
      {"bus_load", std::max(r.bus_load_hsi, r.bus_load_top)},
      {"bus_load_hsi", r.bus_load_hsi},
      {"bus_load_top", r.bus_load_top},
      {"contact_share", r.contact_share},
      {"mean_contact_force_n", r.mean_contact_force_n},
      {"contact_onsets_per_s", r.contact_onsets_per_s},
      {"contact_rebounds", r.contact_rebounds},
      {"contact_rebounds_of_rebounds", r.contact_rebounds_of_rebounds},
      {"passivity",
       {{"hsi",
         {{"dissipated_energy_j", r.hsi_dissipated_energy_j}, {"min_observed_energy_j", r.hsi_min_observed_energy_j}}},
        {"top",
         {{"dissipated_energy_j", r.top_dissipated_energy_j}, {"min_observed_energy_j", r.top_min_observed_energy_j}}},
        {"energy_frames", r.energy_frames}}},
      {"armed_s", static_cast<double>(r.armed_ticks) * 1e-3},
      {"frames", {{"motion", r.motion_frames}, {"force", r.force_frames}}},
      {"network", {{"datagrams", r.network_sent}, {"lost", r.network_lost}, {"reordered", r.network_reordered}}},
      {"sequence_gaps", {{"at_hsi", r.hsi_seq_gaps}, {"at_top", r.top_seq_gaps}}},
      {"refresh_frames", r.refresh_frames},
      {"homed_at_s", r.homed_at_s},
      {"overruns", {{"hsi", r.hsi_overruns}, {"top", r.top_overruns}}},
      {"encoder_edges_lost", {{"hsi", r.hsi_edges_lost}, {"top", r.top_edges_lost}}},
      {"faults", faults_json(r)},
      {"lever_faults",
       {{"hsi", lever_faults_json(r.hsi_lever_faults)}, {"top", lever_faults_json(r.top_lever_faults)}}},
      {"parameters", parameters_json(config)},
      {"realtime_factor", r.realtime_factor},
      {"wall_time_s", r.wall_time_s},
  };
}

void print_report(std::FILE* out, const SimConfig& c, const SimResult& r) {
  fmt::print(out, "{} for {} s (seed {}), velocity {} p={} floor={}, force {} p={} floor={}\n", name(c.scenario),
             c.duration_s, c.seed, codec::name(c.velocity_codec.mode), c.velocity_codec.p, c.velocity_codec.floor,
             codec::name(c.force_codec.mode), c.force_codec.p, c.force_codec.floor);
  fmt::print(out, "  packets: velocity {:.1f} %, force {:.1f} % of 1 kHz\n", 100 * r.velocity_packet_rate,
             100 * r.force_packet_rate);
  fmt::print(out,
             "    of which the deadband's (the paper's count): velocity {:.1f} %, force {:.1f} %; refresh {:.1f} % and "
             "{:.1f} %; rest repeat {:.1f} % and {:.1f} %\n",
             100 * r.velocity_deadband_rate, 100 * r.force_deadband_rate, 100 * r.velocity_refresh_rate,
             100 * r.force_refresh_rate, 100 * r.velocity_rest_repeat_rate, 100 * r.force_rest_repeat_rate);
  fmt::print(
      out, "    the deadband's in contact / in free space: velocity {:.1f} % / {:.1f} %, force {:.1f} % / {:.1f} %\n",
      100 * r.velocity_deadband_contact_rate, 100 * (r.velocity_deadband_rate - r.velocity_deadband_contact_rate),
      100 * r.force_deadband_contact_rate, 100 * (r.force_deadband_rate - r.force_deadband_contact_rate));
  fmt::print(out,
             "  position rmse {:.2f} mrad, force rmse {:.3f} N, force off by more than a JND {:.1f} % of the time\n",
             1000 * r.position_rmse_rad, r.force_rmse_n, 100 * r.force_jnd_violation);
  fmt::print(
      out,
      "  by cause: {:.1f} % beside the measurement {} tick(s) earlier (codec, filter, loss, jitter); codec alone "
      "{:.1f} %; prefilter alone {:.1f} % (its lag {:.1f} ms)\n",
      100 * r.force_jnd_violation_link, r.nominal_delay_ticks, 100 * r.force_jnd_violation_codec,
      100 * r.force_jnd_violation_filter, r.prefilter_delay_ms);
  fmt::print(out,
             "  the hand's force against the measured: rmse {:.3f} N, off by more than a JND {:.1f} % of the time\n",
             r.hand_force_rmse_n, 100 * r.hand_jnd_violation);
  fmt::print(out, "  in contact {:.0f} % of the time at {:.2f} N on average; bus load {:.1f} %; {:.0f}x real time\n",
             100 * r.contact_share, r.mean_contact_force_n, 100 * std::max(r.bus_load_hsi, r.bus_load_top),
             r.realtime_factor);
  if (c.homing)
    fmt::print(out, "  before the scenario: both levers powered up at random angles, homed and armed after {:.2f} s\n",
               r.homed_at_s);
  if (r.hsi_overruns + r.top_overruns + r.hsi_edges_lost + r.top_edges_lost > 0)
    fmt::print(out, "  late steps: HSI {}, TOP {}; encoder edges lost: HSI {}, TOP {}\n", r.hsi_overruns,
               r.top_overruns, r.hsi_edges_lost, r.top_edges_lost);
  for (const auto& f : r.faults) {
    auto say = [](const FaultReport::LeverReaction& x) {
      if (!x.fault_at_s) return std::string("no fault raised");
      return fmt::format("fault at {:.3f} s ({}), safe at {:.3f} s, max torque {:.2f} N m, re-armed {}", *x.fault_at_s,
                         protocol::fault_names(x.latched, "+"), x.safe_at_s.value_or(-1), x.max_torque_nm_during,
                         x.rearmed_at_s ? fmt::format("at {:.3f} s", *x.rearmed_at_s) : "never");
    };
    fmt::print(out, "  fault {}: HSI {}; TOP {}\n", f.spec.text, say(f.hsi), say(f.top));
  }
}

}  // namespace lever::hil
