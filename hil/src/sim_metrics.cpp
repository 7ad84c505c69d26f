#include "sim_metrics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace lever::hil {

SimMetrics::SimMetrics(const SimConfig& config)
    : metrics_(config.jnd, config.jnd_absolute_n),
      nominal_delay_ticks_(nominal_one_way_delay_ticks(config)),
      prefilter_delay_ms_(
          config.force_codec.filter_hz > 0.0 ? 1e3 / (2.0 * std::numbers::pi * config.force_codec.filter_hz) : 0.0),
      measured_history_(static_cast<std::size_t>(nominal_delay_ticks_) + 1),
      jnd_(config.jnd),
      jnd_absolute_n_(config.jnd_absolute_n) {}

void SimMetrics::step(fw::Tick tick, const TickForces& forces, const World& world, const SimLevers& levers) {
  const bool both_armed = levers.both_armed();
  measured_history_[static_cast<std::size_t>(tick) % measured_history_.size()] =
      both_armed ? levers.top().lever->telemetry().force_n : std::nullopt;
  count_lever_faults(levers);
  // The controllers' dissipated energy counts from each lever's arming; the run adds it up across re-arms.
  // It is read from the ports themselves: the telemetry holds it only on the ticks the controllers run.
  dissipated_[0].add(levers.hsi().lever->role().passivity().state().dissipated_j);
  dissipated_[1].add(levers.top().lever->role().passivity().state().dissipated_j);
  if (both_armed) add_armed(tick, forces, world, levers);
}

// Every fault a lever latched while the scenario ran, injected or not: a delayed loop that trips a lever's own
// protection (TORQUE_LIMIT, POSITION_LIMIT) has not survived the delay, whatever else it did.
void SimMetrics::count_lever_faults(const SimLevers& levers) {
  for (int i = 0; i < 2; ++i) {
    const auto& supervisor = i == 0 ? levers.hsi().lever->supervisor() : levers.top().lever->supervisor();
    const bool armed = supervisor.armed();
    if (was_armed_[i] && !armed && supervisor.state() == fw::LeverState::fault) {
      ++lever_faults_[i].count;
      lever_faults_[i].bits |= supervisor.latched();
    }
    was_armed_[i] = armed;
  }
}

void SimMetrics::add_armed(fw::Tick tick, const TickForces& forces, const World& world, const SimLevers& levers) {
  const auto& ht = levers.hsi().lever->telemetry();
  const auto& tt = levers.top().lever->telemetry();
  refresh_frames_ += ht.sent_refresh + tt.sent_refresh;
  const double hand_error = forces.hand - forces.measured;
  hand_sq_ += hand_error * hand_error;
  hand_violations_ += std::fabs(hand_error) > std::max(jnd_ * std::fabs(forces.measured), jnd_absolute_n_);
  if (ht.sent_data) ++by_cause_[0][static_cast<std::size_t>(ht.sent_cause)];
  if (tt.sent_data) ++by_cause_[1][static_cast<std::size_t>(tt.sent_cause)];
  if (forces.contact > 0.0) {
    if (ht.sent_data && ht.sent_cause == fw::SendCause::deadband) ++deadband_in_contact_[0];
    if (tt.sent_data && tt.sent_cause == fw::SendCause::deadband) ++deadband_in_contact_[1];
  }
  min_observed_energy_j_[0] = std::min(min_observed_energy_j_[0], ht.observed_energy_j);
  min_observed_energy_j_[1] = std::min(min_observed_energy_j_[1], tt.observed_energy_j);
  metrics_.add_armed_tick(ht.sent_data, tt.sent_data, world.top().angle() - world.hsi().angle(), forces.displayed,
                          forces.measured, forces.contact);
  const auto& sender = levers.top().lever->role().sender().codec_sender();
  // The oldest entry: nominal_delay_ticks ago.
  const auto& delayed = measured_history_[static_cast<std::size_t>(tick + 1) % measured_history_.size()];
  if (tt.force_n && delayed && ht.remote && !sender.model().empty()) {
    const double lossless = sender.model().at(static_cast<double>(tick - levers.top().boot_tick))[0];
    const double filtered = sender.prefilter().enabled() ? sender.prefilter().output()[0] : forces.measured;
    metrics_.add_force_causes(forces.displayed, *delayed, lossless, filtered, forces.measured);
  }
}

void SimMetrics::finish(SimResult& result, const SimLevers& levers) const {
  const auto& hl = *levers.hsi().lever;
  const auto& tl = *levers.top().lever;
  metrics_.finish(result);
  result.contact_onsets = metrics_.contact_onsets();
  result.contact_rebounds = metrics_.contact_rebounds();
  result.contact_rebounds_of_rebounds = metrics_.contact_rebounds_of_rebounds();
  result.nominal_delay_ticks = nominal_delay_ticks_;
  result.prefilter_delay_ms = prefilter_delay_ms_;
  result.hsi_lever_faults = lever_faults_[0];
  result.top_lever_faults = lever_faults_[1];
  result.refresh_frames = refresh_frames_;
  const double ticks = result.armed_ticks > 0 ? static_cast<double>(result.armed_ticks) : 1.0;
  auto rate = [&](int direction, fw::SendCause cause) {
    return static_cast<double>(by_cause_[direction][static_cast<std::size_t>(cause)]) / ticks;
  };
  result.hand_force_rmse_n = std::sqrt(hand_sq_ / ticks);
  result.hand_jnd_violation = static_cast<double>(hand_violations_) / ticks;
  result.velocity_deadband_rate = rate(0, fw::SendCause::deadband);
  result.velocity_refresh_rate = rate(0, fw::SendCause::refresh);
  result.velocity_rest_repeat_rate = rate(0, fw::SendCause::rest_repeat);
  result.force_deadband_rate = rate(1, fw::SendCause::deadband);
  result.force_refresh_rate = rate(1, fw::SendCause::refresh);
  result.force_rest_repeat_rate = rate(1, fw::SendCause::rest_repeat);
  result.velocity_deadband_contact_rate = static_cast<double>(deadband_in_contact_[0]) / ticks;
  result.force_deadband_contact_rate = static_cast<double>(deadband_in_contact_[1]) / ticks;
  result.hsi_min_observed_energy_j = min_observed_energy_j_[0];
  result.top_min_observed_energy_j = min_observed_energy_j_[1];
  result.hsi_dissipated_energy_j = dissipated_[0].total_j;
  result.top_dissipated_energy_j = dissipated_[1].total_j;
  result.energy_frames = hl.counters().energy_sent + tl.counters().energy_sent;
  result.hsi_seq_gaps = hl.role().receiver().sequence().missing();
  result.top_seq_gaps = tl.role().receiver().sequence().missing();
  result.hsi_overruns = hl.timing().stats().overruns;
  result.top_overruns = tl.timing().stats().overruns;
  result.hsi_edges_lost = levers.hsi().hal.encoder_.overflowed();
  result.top_edges_lost = levers.top().hal.encoder_.overflowed();
}

}  // namespace lever::hil
