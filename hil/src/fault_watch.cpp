#include "fault_watch.hpp"

#include <algorithm>
#include <cmath>

namespace lever::hil {
namespace {

template <typename LeverT>
void track_reaction(FaultReport::LeverReaction& r, const LeverSite<LeverT>& site, double t, double injected) {
  if (t < injected) return;
  const auto& lever = *site.lever;
  const auto state = lever.supervisor().state();
  if (!r.rearmed_at_s)
    r.max_torque_nm_during = std::max(r.max_torque_nm_during, std::fabs(site.hal.motor_.last.torque_nm));
  if (!r.fault_at_s && state == fw::LeverState::fault) {
    r.fault_at_s = t;
    r.latched = lever.supervisor().latched();
  }
  if (r.fault_at_s && !r.safe_at_s && site.safe_now()) r.safe_at_s = t;
  if (r.fault_at_s && !r.rearmed_at_s && state == fw::LeverState::armed) r.rearmed_at_s = t;
}

// Armed again after a fault with no re-arm sent since the fault began: what the safety rules forbid.
template <typename LeverT>
bool armed_without_rearm(LeverSite<LeverT>& site) {
  const auto state = site.state();
  bool violated = false;
  if (state == fw::LeverState::fault && site.previous_state != fw::LeverState::fault)
    site.rearms_at_fault = site.rearms_sent;
  if (site.previous_state == fw::LeverState::fault && state == fw::LeverState::armed &&
      site.rearms_sent == site.rearms_at_fault)
    violated = true;
  site.previous_state = state;
  return violated;
}

}  // namespace

void FaultWatch::step(double t, SimLevers& levers) {
  for (auto& r : reports_) {
    track_reaction(r.hsi, levers.hsi(), t, r.spec.start_s);
    track_reaction(r.top, levers.top(), t, r.spec.start_s);
  }
  const bool hsi_bad = armed_without_rearm(levers.hsi());
  const bool top_bad = armed_without_rearm(levers.top());
  for (auto& r : reports_) {
    r.hsi.armed_without_rearm = r.hsi.armed_without_rearm || hsi_bad;
    r.top.armed_without_rearm = r.top.armed_without_rearm || top_bad;
  }
}

}  // namespace lever::hil
