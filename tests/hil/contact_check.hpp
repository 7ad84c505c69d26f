#pragma once
// The contact check's bounds (docs/hil-model.md, "The contact check"), for the check itself and for the tests whose
// figures count only on a setup whose contact holds (the fidelity table's Fig. 8 rows).
#include <cstdint>
#include <optional>

#include "lever/hil/simulation.hpp"

namespace lever::test {

// The wall-tap script's most contacts per second over whole cycles (a reach, 3 taps and a press at their shortest:
// 4 contacts in 1.96 s) and the most a cycle cut by the run's end adds.
constexpr double kScriptContactsPerS = 4.0 / 1.96;
constexpr double kScriptContactsCutCycle = 1.23;
// Each of the script's contacts may rebound once.
constexpr double kReboundsPerContact = 1.0;
// A bounce of a bounce is never the script's (its contacts are 100 ms or more apart); one per run is the margin.
constexpr std::uint64_t kReboundsOfReboundsPerRun = 1;

struct ContactVerdict {
  double onsets_bound = 0.0;  // contact onsets the run may have
  bool onsets_ok = false, rebounds_ok = false;
  bool holds() const { return onsets_ok && rebounds_ok; }
};

// The check's setting: wall-tap at p = 0, both directions sending every change.
inline hil::SimConfig contact_check_setting(hil::Topology topology, hil::GaugeChain chain, bool force_loop,
                                            std::uint64_t seed) {
  hil::SimConfig c;
  c.scenario = hil::ScenarioKind::wall_tap;
  c.seed = seed;
  c.topology = topology;
  c.gauge_chain = chain;
  c.velocity_codec = {codec::Mode::deadband, 0.0, 0.0, 0.0};
  c.force_codec = {codec::Mode::deadband, 0.0, 0.0, 0.0};
  hil::set_hsi_force_loop(c, force_loop);
  return c;
}

// A wall-tap run at p = 0 (the check's setting).
inline ContactVerdict contact_verdict(const hil::SimResult& r) {
  ContactVerdict v;
  const double armed_s = static_cast<double>(r.armed_ticks) * 1e-3;
  v.onsets_bound = (1.0 + kReboundsPerContact) * (kScriptContactsPerS * armed_s + kScriptContactsCutCycle);
  v.onsets_ok = static_cast<double>(r.contact_onsets) <= v.onsets_bound;
  v.rebounds_ok = r.contact_rebounds_of_rebounds <= kReboundsOfReboundsPerRun;
  return v;
}

// The designs' pick of a damping on an ascending grid (docs/hil-model.md, "The contact designed on seeds of its
// own"): the least force_jnd_violation in points, a later damping within 0.01 points of the best taking it (the tie
// goes to the larger).
struct LeastJndPick {
  std::optional<double> damping_nms;
  double jnd_percent = 0.0;  // the picked damping's
  void offer(double damping, double jnd) {
    if (damping_nms && jnd > best_ + 0.01) return;
    if (!damping_nms || jnd < best_) best_ = jnd;
    damping_nms = damping;
    jnd_percent = jnd;
  }

 private:
  double best_ = 0.0;
};

}  // namespace lever::test
