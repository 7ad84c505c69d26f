// Fidelity to the paper, not change detection: each figure and each effect the paper's text gives for its two
// experiments (Fig. 8, section IV-A-3; Fig. 12, section IV-B-4) against the HIL's mean over seeds 1-10, written as one
// table, docs/fidelity-table.md, the one source of what the HIL reproduces (README.md and docs/hil-model.md quote it;
// tests/docs/fidelity_words.sh holds their words to it). The test fails when the table the HIL gives now differs
// from the committed one: rerun hil/experiments/fidelity-table and say in the commit which verdicts moved and why.
// A figure counts as reproduced within 25 % of the paper's own (relative; for "less than", at most 25 % above it),
// the smallest effect the paper reports as a finding (the linear predictor's 25 % fewer force packets at p = 5 %),
// fixed from the paper before the runs. An effect (prediction's or the prefilter's change in rate, the rates' fall
// with p) is judged by its direction, and by the same 25 % on its size where the paper gives one; since issue 39 its
// direction counts only if every seed's change has the paper's sign (the mean's change alone did before). Each row
// says its kind (docs/hil-model.md, "Fidelity to the paper"): direct, a figure the paper's text states for the setup;
// derived, computed from the paper's figures or one of them read as a named quantity; inferred, a figure the paper
// itself infers; variant, the HIL's run differs from the paper's setup; effect.
// Change detection is test_change_detection.cpp.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "contact_check.hpp"
#include "lever/hil/simulation.hpp"
#include "lever/hil/sphere3dof.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

constexpr double kTolerance = 0.25;  // relative, fixed from the paper before the runs (above)
constexpr int kSeeds = 10;

struct Rates {
  double velocity = 0, force = 0, velocity_contact = 0, force_contact = 0, contact = 0;
  std::vector<double> velocity_seeds, force_seeds;  // seed 1 first
};

enum class Kind { direct, derived, inferred, variant };
const char* name(Kind k) {
  switch (k) {
    case Kind::direct:
      return "direct";
    case Kind::derived:
      return "derived";
    case Kind::inferred:
      return "inferred";
    case Kind::variant:
      return "variant";
  }
  return "?";
}

// The paper's wall-tap on the lever in the paper's setup (docs/hil-model.md, "The paper's chain, choice by choice"):
// both levers in one controller (and so the assumed AD620 chain), the HSI's force loop on, its deadband rule on both
// directions, no floor, no prefilter; counted as the paper counts, the packets the deadband sends; 20 s per seed.
SimConfig lever_setup(double p, std::uint64_t seed) {
  SimConfig c;
  c.scenario = ScenarioKind::wall_tap;
  c.duration_s = 20.0;
  c.seed = seed;
  c.topology = Topology::one_controller;
  // The one setup in one controller whose contact holds (docs/hil-model.md, "The contact check"): the assumed AD620
  // chain chatters with the loop and without it.
  c.gauge_chain = GaugeChain::dad141;
  set_hsi_force_loop(c, true);
  c.velocity_codec = {codec::Mode::deadband, p, 0.0, 0.0};
  c.force_codec = {codec::Mode::deadband, p, 0.0, 0.0};
  return c;
}

Rates lever_rates(double p, fw::MotionVelocity velocity = fw::MotionVelocity::difference) {
  Rates m;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SimConfig c = lever_setup(p, static_cast<std::uint64_t>(seed));
    c.hsi_firmware.motion_velocity = velocity;
    const auto r = run_simulation(c);
    m.velocity += r.velocity_deadband_rate / kSeeds;
    m.force += r.force_deadband_rate / kSeeds;
    m.velocity_contact += r.velocity_deadband_contact_rate / kSeeds;
    m.force_contact += r.force_deadband_contact_rate / kSeeds;
    m.velocity_seeds.push_back(r.velocity_deadband_rate);
    m.force_seeds.push_back(r.force_deadband_rate);
  }
  return m;
}

// The 3-DoF sphere: the deadband on one direction, every change sent on the other, as in the paper's runs; the
// paper's 30 s interval per seed.
Rates sphere(SphereDirection direction, codec::Mode mode, bool filter, double p) {
  Rates m;
  for (int seed = 1; seed <= kSeeds; ++seed) {
    SphereConfig c = sphere_variant(direction, mode, filter, p);
    c.duration_s = 30.0;
    c.seed = static_cast<std::uint64_t>(seed);
    const auto r = run_sphere(c);
    m.velocity += r.velocity_packet_rate / kSeeds;
    m.force += r.force_packet_rate / kSeeds;
    m.velocity_contact += r.velocity_contact_rate / kSeeds;
    m.force_contact += r.force_contact_rate / kSeeds;
    m.contact += r.contact_share / kSeeds;
    m.velocity_seeds.push_back(r.velocity_packet_rate);
    m.force_seeds.push_back(r.force_packet_rate);
  }
  return m;
}

std::string percent(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f %%", 100.0 * x);
  return b;
}
std::string split(double all, double contact) { return percent(contact) + " / " + percent(all - contact); }

class Table {
 public:
  // A figure: the paper's value (at_most: "less than"), the HIL's, its contact / free-space split ("" if none).
  void figure(Kind kind, const std::string& id, const std::string& what, double paper, const std::string& paper_text,
              double hil, const std::string& where, bool at_most = false) {
    const bool within =
        at_most ? hil <= paper * (1.0 + kTolerance) : std::fabs(hil - paper) <= kTolerance * std::fabs(paper);
    add(id, what, paper_text, percent(hil), where, within ? "yes" : "no", "-", name(kind));
    Count& c = figures_[kind];
    ++c.all;
    if (within) {
      c.ids.push_back(id);
    }
  }
  // An effect: a change from one rate to another, seed by seed (from[i] and to[i] the same seed); paper_change the
  // paper's relative change (NaN: direction only, the sign of `paper_sign`). Its size is the means' change; its
  // direction counts only if every seed's change has the paper's sign.
  void effect(const std::string& id, const std::string& what, double paper_change, double paper_sign,
              const std::string& paper_text, const std::vector<double>& from, const std::vector<double>& to) {
    REQUIRE(from.size() == to.size());
    REQUIRE(!from.empty());
    double mean_from = 0, mean_to = 0;
    int seeds_right = 0;
    for (std::size_t i = 0; i < from.size(); ++i) {
      mean_from += from[i] / static_cast<double>(from.size());
      mean_to += to[i] / static_cast<double>(to.size());
      const double seed_change = to[i] - from[i];
      seeds_right += (seed_change < 0) == (paper_sign < 0) && seed_change != 0.0 ? 1 : 0;
    }
    const int seeds = static_cast<int>(from.size());
    const double change = (mean_to - mean_from) / mean_from;
    const bool direction = seeds_right == seeds;
    const bool level =
        !std::isnan(paper_change) && std::fabs(change - paper_change) <= kTolerance * std::fabs(paper_change);
    char b[128];
    std::snprintf(b, sizeof b, "%s -> %s (%+.0f %%; the paper's way in %d of %d seeds)", percent(mean_from).c_str(),
                  percent(mean_to).c_str(), 100.0 * change, seeds_right, seeds);
    add(id, what, paper_text, b, "",
        std::isnan(paper_change) ? "-"
        : level                  ? "yes"
                                 : "no",
        direction ? "yes" : "no", "effect");
    ++effects_.all;
    if (direction) {
      effects_.ids.push_back(id);
    }
  }
  std::string markdown() const {
    std::ostringstream o;
    o << "| id | figure or effect | paper | HIL, seeds 1-10 | contact / free space | within 25 % | direction | kind |\n"
         "|---|---|---|---|---|---|---|---|\n"
      << rows_.str() << "\nDirect figures (the paper states them for this setup; the HIL's default chain) within 25 % "
      << "of the paper's: " << count(Kind::direct) << ". Apart from them, derived figures: " << count(Kind::derived)
      << "; inferred: " << count(Kind::inferred) << "; variants: " << count(Kind::variant)
      << ". Effects in the paper's direction in every seed 1-10: " << listed(effects_) << ".\n\n"
      << "Kinds: direct, a figure the paper's text states for the setup (a reduction read as its complement); "
         "derived, computed from the paper's figures, or one of them read as a quantity the paper does not name, by "
         "the reading the row states; inferred, a figure the paper infers itself; variant, the HIL's run differs from "
         "the paper's setup; effect, a change from one rate to another, its direction counted only if every seed's "
         "change has the paper's sign (its size is the means' change).\n\nThe lever's rows (F8) are measured in one "
         "controller on the DAD 141.1 gauge chain with the HSI's force loop on, a setup that passes the contact check "
         "at p = 0: the paper's HSI closes that loop, and on the assumed AD620 chain (an AD620 and a 16-bit ADC, "
         "`paper-adc`) the loop makes the contact chatter and is refused.\n";
    return o.str();
  }

 private:
  struct Count {
    int all = 0;
    std::vector<std::string> ids;  // the rows that hold, in the table's order
  };
  static std::string listed(const Count& c) {
    std::string s = std::to_string(c.ids.size()) + " of " + std::to_string(c.all);
    for (std::size_t i = 0; i < c.ids.size(); ++i) {
      s += (i == 0 ? " (`" : ", `") + c.ids[i] + "`";
    }
    return c.ids.empty() ? s : s + ")";
  }
  std::string count(Kind k) const {
    const auto it = figures_.find(k);
    return it == figures_.end() ? "0 of 0" : listed(it->second);
  }
  void add(const std::string& id, const std::string& what, const std::string& paper, const std::string& hil,
           const std::string& where, const std::string& within, const std::string& direction, const char* kind) {
    rows_ << "| `" << id << "` | " << what << " | " << paper << " | " << hil << " | " << (where.empty() ? "-" : where)
          << " | " << within << " | " << direction << " | " << kind << " |\n";
  }
  std::ostringstream rows_;
  std::map<Kind, Count> figures_;
  Count effects_;
};

std::string read(const char* path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

constexpr auto dz = codec::Mode::deadband;
constexpr auto lp = codec::Mode::predictive;
constexpr auto v = SphereDirection::velocity;
constexpr auto f = SphereDirection::force;

}  // namespace

TEST_CASE("paper fidelity: the table of what the HIL reproduces is current (docs/fidelity-table.md)",
          "[hil][paper-fidelity]") {
  // Fig. 8's rows count only on a setup whose contact holds: the contact check's bounds at p = 0, its seeds.
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const auto r = run_simulation(lever_setup(0.0, seed));
    CAPTURE(seed, r.contact_onsets, r.contact_rebounds_of_rebounds);
    REQUIRE(test::contact_verdict(r).holds());
  }
  Table t;
  // Fig. 8: "The traffic volume induced by velocity packets is already at 25% at a deadband size of p=10% and keeps
  // falling with increasing deadband size. ... Already at p=2.5% the network traffic volume in the backward path is
  // less than 10% of the standard approach. At p=10% only 15% of the original number of packets is transmitted. This
  // means an average network traffic reduction by 85%."
  const Rates l25 = lever_rates(0.025), l10 = lever_rates(0.10), l20 = lever_rates(0.20);
  const Rates aw10 = lever_rates(0.10, fw::MotionVelocity::adaptive_window);
  t.figure(Kind::direct, "F8-velocity-10", "lever, velocity packets, p = 10 %", 0.25, "25 %", l10.velocity,
           split(l10.velocity, l10.velocity_contact));
  t.figure(Kind::variant, "F8-velocity-10-aw",
           "lever, velocity packets, p = 10 %, adaptive-window velocity (a variant)", 0.25, "25 %", aw10.velocity,
           split(aw10.velocity, aw10.velocity_contact));
  t.figure(Kind::direct, "F8-force-2.5", "lever, force packets, p = 2.5 %", 0.10, "under 10 %", l25.force,
           split(l25.force, l25.force_contact), true);
  t.figure(Kind::derived, "F8-15-as-force", "lever, \"15 %\" read as the force packets, p = 10 %", 0.15, "15 %",
           l10.force, split(l10.force, l10.force_contact));
  t.figure(Kind::derived, "F8-15-as-mean", "lever, \"15 %\" read as the two paths' mean, p = 10 % (the reading picked)",
           0.15, "15 %", 0.5 * (l10.velocity + l10.force), "");
  t.figure(Kind::derived, "F8-force-10-by-mean",
           "lever, force packets, p = 10 %, under the mean reading (2 x 15 % - 25 %)", 0.05, "5 % (derived)", l10.force,
           split(l10.force, l10.force_contact));
  t.effect("F8-velocity-falls", "lever, velocity packets from p = 10 % to 20 %", std::nan(""), -1.0,
           "falls (\"keeps falling\")", l10.velocity_seeds, l20.velocity_seeds);
  t.effect("F8-force-falls", "lever, force packets from p = 2.5 % to 10 %", std::nan(""), -1.0,
           "falls (\"higher deadband parameters lead to higher traffic reduction\")", l25.force_seeds, l10.force_seeds);

  // Fig. 12, IV-B-4: the points its text gives (docs/hil-model.md, the table of the paper's points).
  const Rates f0 = sphere(f, dz, false, 0.0);
  const Rates v20 = sphere(v, dz, false, 0.20), v20lp = sphere(v, lp, false, 0.20);
  const Rates v75lp = sphere(v, lp, false, 0.075), v75lpf = sphere(v, lp, true, 0.075);
  const Rates f5 = sphere(f, dz, false, 0.05), f5lp = sphere(f, lp, false, 0.05);
  const Rates f25lp = sphere(f, lp, false, 0.025), f25lpf = sphere(f, lp, true, 0.025);
  t.figure(Kind::derived, "F12-force-0",
           "sphere, force packets, p = 0 (the paper's contact share, read back as the force rate it was inferred from)",
           0.87, "87 %", f0.force, split(f0.force, f0.force_contact));
  t.figure(Kind::inferred, "F12-contact", "sphere, contact share (inferred by the paper from the row above)", 0.87,
           "about 87 %", f0.contact, "");
  t.figure(Kind::direct, "F12-velocity-20", "sphere, velocity packets, 3-DoF, p = 20 %", 0.25, "25 %", v20.velocity,
           split(v20.velocity, v20.velocity_contact));
  t.figure(Kind::direct, "F12-force-5", "sphere, force packets, 3-DoF, p = 5 %", 0.10, "10 %", f5.force,
           split(f5.force, f5.force_contact));
  t.figure(Kind::direct, "F12-velocity-20-lp", "sphere, velocity packets, LP, p = 20 %", 0.17, "17 %", v20lp.velocity,
           split(v20lp.velocity, v20lp.velocity_contact));
  t.figure(Kind::direct, "F12-force-5-lp", "sphere, force packets, LP, p = 5 %", 0.07, "7 %", f5lp.force,
           split(f5lp.force, f5lp.force_contact));
  t.figure(Kind::derived, "F12-force-2.5-lp", "sphere, force packets, LP, p = 2.5 % (7.4 % / 0.45)", 0.074 / 0.45,
           "16.4 % (derived)", f25lp.force, split(f25lp.force, f25lp.force_contact));
  t.figure(Kind::direct, "F12-velocity-7.5-lpf", "sphere, velocity packets, LP + 10 Hz prefilter, p = 7.5 %", 0.087,
           "8.7 %", v75lpf.velocity, split(v75lpf.velocity, v75lpf.velocity_contact));
  t.figure(Kind::direct, "F12-force-2.5-lpf", "sphere, force packets, LP + 30 Hz prefilter, p = 2.5 %", 0.074, "7.4 %",
           f25lpf.force, split(f25lpf.force, f25lpf.force_contact));
  // "In Fig. 12, we observe for a 20% velocity deadband and a 5% force deadband an improvent of 28% and 25%"; "a
  // significant improvement (55%) in packet rate at 2.5% deadband in comparison to the LP case"; "a drastic decrease in
  // velocity packet rates, especially for small deadband values".
  t.effect("E12-prediction-velocity-20", "sphere, prediction's change in velocity packets, p = 20 %", -0.28, -1.0,
           "-28 %", v20.velocity_seeds, v20lp.velocity_seeds);
  t.effect("E12-prediction-force-5", "sphere, prediction's change in force packets, p = 5 %", -0.25, -1.0, "-25 %",
           f5.force_seeds, f5lp.force_seeds);
  t.effect("E12-prefilter-force-2.5", "sphere, the prefilter's change in predicted force packets, p = 2.5 %", -0.55,
           -1.0, "-55 %", f25lp.force_seeds, f25lpf.force_seeds);
  t.effect("E12-prefilter-velocity-7.5", "sphere, the prefilter's change in predicted velocity packets, p = 7.5 %",
           std::nan(""), -1.0, "falls (\"a drastic decrease\")", v75lp.velocity_seeds, v75lpf.velocity_seeds);

  const std::string now =
      "<!-- Generated by tests/hil/test_paper_fidelity.cpp (hil/experiments/fidelity-table); do not edit. -->\n" +
      t.markdown();
  if (std::getenv("LEVER_FIDELITY_TABLE_UPDATE") != nullptr) {
    std::ofstream(LEVER_FIDELITY_TABLE) << now;
  }
  const std::string committed = read(LEVER_FIDELITY_TABLE);
  INFO("the HIL now gives:\n" << now << "docs/fidelity-table.md is stale: run hil/experiments/fidelity-table");
  CHECK(committed == now);
}
