// Time-domain passivity in the closed loop (docs/firmware.md, "Passivity under delay"): wall-tap over two sites
// at 10, 25, 50 and 100 ms one-way delay, jitter a tenth of the delay, 1 % loss; with tdpa and without (observe:
// the same control as off, with the observer running so that its energy can be read).
//
// Bounds, each fixed before the delayed runs were looked at:
// - energy: after the controller acts, each port's observed energy is at least -1 uJ (one count of the energy
//   field) at every armed tick; without tdpa, below -10 mJ somewhere (a tenth of the ~0.1 J a tap puts through
//   a port);
// - protection: no lever trips its own protection (TORQUE_LIMIT: the demand above the 1 N m limit for 250 ms;
//   POSITION_LIMIT) while the scenario runs. The bound is on what the controllers demand: the torque sent to the
//   motor is clamped to the limit whatever they demand;
// - position: once neither lever has felt a contact force for 1 s, the TOP is within 10 mrad (1 mm at the 0.1 m
//   tip) of where the HSI was one nominal delay earlier; wall-tap has such windows only before its first contact,
//   so the same bound is judged again 0.5 s after each contact, at rest (docs/firmware.md says why both);
// - chatter: contact onsets per second at most twice the zero-delay run's, the same controller's (each tap may
//   bounce once).
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>

#include "lever/hil/simulation.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

struct Outcome {
  double min_observed_j[2] = {0.0, 0.0};  // HSI, TOP
  std::uint32_t lever_faults = 0;
  double onsets_per_s = 0.0;
  double max_drift_rad = 0.0;  // after the transient (above)
  std::size_t drift_ticks = 0;
  // The same, only while both levers are at rest (the HSI then and one delay earlier, the TOP over the last
  // 10 ms, all below 0.05 rad/s): the offset the passivity controller leaves, without free motion's tracking.
  double max_rest_offset_rad = 0.0;
  // The drift the controller leaves after a contact: 0.5 s after the last felt force, both levers armed; and the
  // same at rest. (The windows above come only before the first contact: wall-tap never rests a second after it.)
  double max_drift_after_contact_rad = 0.0;
  std::size_t after_contact_ticks = 0;
  double max_rest_offset_after_contact_rad = 0.0;
  double force_rmse_n = 0.0;
};

Outcome run(double delay_ms, fw::PassivityMode mode, double reserve_j = fw::PassivityConfig{}.reserve_j,
            std::uint64_t seed = 3, double display_spend_s = fw::PassivityConfig{}.display_spend_time_s,
            double reserve_share = fw::PassivityConfig{}.reserve_share) {
  SimConfig c;
  c.scenario = ScenarioKind::wall_tap;
  c.seed = seed;
  c.duration_s = 20.0;
  c.velocity_codec = {codec::Mode::deadband, 0.1, 0.0, 0.0};
  c.force_codec = {codec::Mode::deadband, 0.1, 0.0, 0.0};
  c.network.delay_ms = delay_ms;
  c.network.jitter_ms = delay_ms / 10.0;
  c.network.loss = delay_ms > 0.0 ? 0.01 : 0.0;
  for (auto* fw : {&c.hsi_firmware, &c.top_firmware}) {
    fw->comms_timeout = 300;  // the watchdog stays out of it: the delay, not the timeout, is under test
    fw->passivity.mode = mode;
    fw->passivity.reserve_j = reserve_j;
    fw->passivity.display_spend_time_s = display_spend_s;
    fw->passivity.reserve_share = reserve_share;
  }
  // Every run here, at zero delay and observing too, with the tdpa controller's contact settings: the bounds ask
  // what delay and tdpa do to one controller (docs/hil-model.md, "The design applied where its low-pass may run").
  SimConfig with_tdpa = c;
  with_tdpa.top_firmware.passivity.mode = fw::PassivityMode::tdpa;
  const ContactSettings contact = contact_settings(with_tdpa);
  c.top_reference_cutoff_hz = contact.top_reference_cutoff_hz;
  c.hsi_contact_damping_nms = contact.hsi_contact_damping_nms;
  c.record_trace = true;
  Outcome o;
  c.observer = [&](const SimView& v) {
    if (v.t < 0.0) return;
    if (!v.hsi.supervisor().armed() || !v.top.supervisor().armed()) return;
    o.min_observed_j[0] = std::min(o.min_observed_j[0], v.hsi.telemetry().observed_energy_j);
    o.min_observed_j[1] = std::min(o.min_observed_j[1], v.top.telemetry().observed_energy_j);
  };
  const auto r = run_simulation(c);
  o.onsets_per_s = r.contact_onsets_per_s;
  o.force_rmse_n = r.force_rmse_n;
  o.lever_faults = r.hsi_lever_faults.count + r.top_lever_faults.count;
  const auto lag = static_cast<std::size_t>(r.nominal_delay_ticks);
  constexpr int kArmed = static_cast<int>(protocol::LeverState::armed);
  std::size_t quiet = 0;
  bool touched = false;
  for (std::size_t k = 0; k < r.trace.size(); ++k) {
    const auto& row = r.trace[k];
    const bool felt = row.contact_force > 0.0 || std::fabs(row.displayed_force) > 0.1;
    quiet = felt ? 0 : quiet + 1;
    touched = touched || felt;
    if (quiet <= 500 || k < lag || k < 10) continue;
    const double offset = std::fabs(row.top_angle - r.trace[k - lag].hsi_angle);
    const bool at_rest = std::fabs(row.hsi_velocity) < 0.05 && std::fabs(r.trace[k - lag].hsi_velocity) < 0.05 &&
                         std::fabs(row.top_angle - r.trace[k - 10].top_angle) < 0.05 * 0.010;
    if (touched && row.hsi_state == kArmed && row.top_state == kArmed) {
      ++o.after_contact_ticks;
      o.max_drift_after_contact_rad = std::max(o.max_drift_after_contact_rad, offset);
      if (at_rest) o.max_rest_offset_after_contact_rad = std::max(o.max_rest_offset_after_contact_rad, offset);
    }
    if (quiet <= 1000) continue;
    ++o.drift_ticks;
    o.max_drift_rad = std::max(o.max_drift_rad, offset);
    if (at_rest) o.max_rest_offset_rad = std::max(o.max_rest_offset_rad, offset);
  }
  return o;
}

}  // namespace

TEST_CASE("tdpa keeps each port passive under delay; without it the channel makes energy", "[hil][passivity]") {
  for (const double delay_ms : {10.0, 25.0, 50.0, 100.0}) {
    CAPTURE(delay_ms);
    const auto with = run(delay_ms, fw::PassivityMode::tdpa);
    const auto without = run(delay_ms, fw::PassivityMode::observe);
    CAPTURE(with.min_observed_j[0], with.min_observed_j[1], without.min_observed_j[0], without.min_observed_j[1]);
    CAPTURE(with.max_drift_rad, with.drift_ticks, without.max_drift_rad, with.onsets_per_s, without.onsets_per_s);
    for (int port = 0; port < 2; ++port) {
      CHECK(with.min_observed_j[port] >= -1e-6);
    }
    // What tdpa buys: without it the channel puts out energy nobody put in.
    CHECK(std::min(without.min_observed_j[0], without.min_observed_j[1]) < -0.010);
  }
}

// Each bound counts as met at a delay only when it holds for every one of seeds 1-5, so that another trajectory
// (another seed, another CPU's libm) does not meet it by chance. A bound not met is one test per delay carrying
// Catch's shouldfail: it fails once the bound is met, and the test moves over. Measurements: docs/firmware.md,
// "Passivity under delay".
constexpr std::uint64_t kSeeds[] = {1, 2, 3, 4, 5};
constexpr double kDelaysMs[] = {10.0, 25.0, 50.0, 100.0};
const double kReserveJ = fw::PassivityConfig{}.reserve_j;

Outcome tdpa_run(double delay_ms, std::uint64_t seed) {
  return run(delay_ms, fw::PassivityMode::tdpa, kReserveJ, seed);
}

TEST_CASE("with tdpa no lever trips its protection at 10, 25, 50 and 100 ms", "[hil][passivity]") {
  for (const double delay_ms : kDelaysMs) {
    for (const auto seed : kSeeds) {
      CAPTURE(delay_ms, seed);
      CHECK(tdpa_run(delay_ms, seed).lever_faults == 0);
    }
  }
}

// What tdpa buys at 100 ms, against the loop without it.
TEST_CASE("at 100 ms tdpa trips the protection far less often than the loop without it", "[hil][passivity]") {
  std::uint32_t with = 0, without = 0;
  for (const auto seed : kSeeds) {
    with += tdpa_run(100.0, seed).lever_faults;
    without += run(100.0, fw::PassivityMode::observe, 0.0, seed).lever_faults;
  }
  CAPTURE(with, without);
  CHECK(without > 0);
  CHECK(4 * with <= without);
}

TEST_CASE("the baseline: without tdpa the levers trip their protection from 25 ms of delay on", "[hil][passivity]") {
  for (const auto seed : kSeeds) {
    CAPTURE(seed);
    CHECK(run(0.0, fw::PassivityMode::off, 0.0, seed).lever_faults == 0);
  }
  for (const double delay_ms : {25.0, 50.0, 100.0}) {
    CAPTURE(delay_ms);
    std::uint32_t trips = 0;
    for (const auto seed : kSeeds) trips += run(delay_ms, fw::PassivityMode::observe, 0.0, seed).lever_faults;
    CHECK(trips > 0);
  }
}

// The drift measures judge something in every run. After a contact the windows can be short (at 100 ms the contact
// chatters, and a window needs both levers armed), so that bound is on each delay's five runs together.
TEST_CASE("every delayed tdpa run has quiet stretches to judge the drift in", "[hil][passivity]") {
  for (const double delay_ms : kDelaysMs) {
    std::size_t after_contact = 0;
    for (const auto seed : kSeeds) {
      CAPTURE(delay_ms, seed);
      const auto o = tdpa_run(delay_ms, seed);
      CHECK(o.drift_ticks > 100);
      CHECK(o.after_contact_ticks > 0);
      after_contact += o.after_contact_ticks;
    }
    CAPTURE(delay_ms, after_contact);
    CHECK(after_contact > 500);
  }
}

// The drift and chatter bounds at one delay, for seeds 1-5; each failure names its seed and values.
void check_drift_and_chatter(double delay_ms, bool drift, bool chatter) {
  for (const auto seed : kSeeds) {
    const double reference = run(0.0, fw::PassivityMode::off, 0.0, seed).onsets_per_s;
    const auto o = tdpa_run(delay_ms, seed);
    CAPTURE(delay_ms, seed, o.max_drift_rad, o.onsets_per_s, reference);
    if (drift) CHECK(o.max_drift_rad <= 0.010);
    if (chatter) CHECK(o.onsets_per_s <= 2.0 * reference);
  }
}

TEST_CASE("at 25 ms tdpa keeps the TOP within 10 mrad of the delayed HSI before the first contact",
          "[hil][passivity]") {
  check_drift_and_chatter(25.0, true, false);
}

// Met since the TOP's pull acts in contact too, aimed no further past the lever than the motor can press
// (top_role.hpp); without it a shallow press bounced off the wall (docs/firmware.md).
TEST_CASE("at 10, 25, 50 and 100 ms tdpa keeps contact onsets within twice the zero-delay run's", "[hil][passivity]") {
  for (const double delay_ms : kDelaysMs) check_drift_and_chatter(delay_ms, false, true);
}

// Met at 10 ms, on every architecture alike (the HIL runs the same bits everywhere: tests/cross/hil_same_bytes.sh).
TEST_CASE("at 10 ms tdpa keeps the TOP within 10 mrad of the delayed HSI before the first contact",
          "[hil][passivity]") {
  check_drift_and_chatter(10.0, true, false);
}

// Not met at 50 and 100 ms: the measure includes free motion, where the jitter alone puts a fast reach several
// milliseconds off the nominal delay, and the loop without tdpa shows the same excursions (docs/firmware.md).
TEST_CASE("at 50 ms tdpa keeps the TOP within 10 mrad of the delayed HSI before the first contact",
          "[hil][passivity][!shouldfail]") {
  check_drift_and_chatter(50.0, true, false);
}

TEST_CASE("at 100 ms tdpa keeps the TOP within 10 mrad of the delayed HSI before the first contact",
          "[hil][passivity][!shouldfail]") {
  check_drift_and_chatter(100.0, true, false);
}

// When a contact ends the TOP is behind the HSI by the depth the hand went past the wall that the TOP did not follow
// (at most the motor's press, torque limit / kp, past the lever, and only as far as energy allowed); the pull closes
// that (docs/firmware.md, "Position drift").
void check_offset_after_contact(double delay_ms, std::uint64_t last_seed) {
  for (std::uint64_t seed = 1; seed <= last_seed; ++seed) {
    const auto o = tdpa_run(delay_ms, seed);
    CAPTURE(delay_ms, seed, o.max_rest_offset_after_contact_rad);
    CHECK(o.max_rest_offset_after_contact_rad <= 0.010);
  }
}

TEST_CASE("from 25 ms on, after a contact tdpa leaves the TOP at rest within 10 mrad of the delayed HSI",
          "[hil][passivity]") {
  for (const double delay_ms : {25.0, 50.0, 100.0}) check_offset_after_contact(delay_ms, 5);
}

// Ten seeds here: the event this guards against (the frame that brings the HSI to rest lost, and the TOP holding
// its last velocity until the refresh) comes once in several runs; LeverConfig::rest_repeat is what meets it
// (docs/firmware.md, "The lost rest frame").
TEST_CASE("at 10 ms, after a contact tdpa leaves the TOP at rest within 10 mrad of the delayed HSI",
          "[hil][passivity]") {
  check_offset_after_contact(10.0, 10);
}

// What the display's spread spending buys (PassivityConfig::display_spend_time_s): against the literature's
// controller, which lets the held energy out at once and then cuts the whole force, the same runs at 50 ms.
// Direction only: it was chosen after docs/firmware.md's table was measured. Not met now: the difference is within
// the seeds' spread (docs/firmware.md, "No longer measurable").
TEST_CASE("at 50 ms the display's spread spending gives fewer contact onsets than spending at once",
          "[hil][passivity][!shouldfail]") {
  double spread = 0.0, at_once = 0.0;
  for (const auto seed : kSeeds) {
    spread += tdpa_run(50.0, seed).onsets_per_s;
    at_once += run(50.0, fw::PassivityMode::tdpa, kReserveJ, seed, 0.0).onsets_per_s;
  }
  CAPTURE(spread, at_once);
  CHECK(spread < at_once);
}

// Not a test: the table behind docs/firmware.md's choice of the reserve and the display's spending
// (`lever_tests_hil "[passivity-table]"`): seeds 1-10: the lowest observed energy of either port, and the mean of
// the others.
TEST_CASE("passivity table", "[.][passivity-table]") {
  struct Variant {
    const char* name;
    fw::PassivityMode mode;
    double reserve_j;
    double display_spend_s;
    double reserve_share;
  };
  const double spend = fw::PassivityConfig{}.display_spend_time_s;
  const double share = fw::PassivityConfig{}.reserve_share;
  const Variant variants[] = {{"without", fw::PassivityMode::observe, 0.0, 0.0, share},
                              {"tdpa, no reserve, spent at once", fw::PassivityMode::tdpa, 0.0, 0.0, share},
                              {"tdpa, spent at once", fw::PassivityMode::tdpa, kReserveJ, 0.0, share},
                              {"tdpa, reserve filled first", fw::PassivityMode::tdpa, kReserveJ, spend, 1.0},
                              {"tdpa", fw::PassivityMode::tdpa, kReserveJ, spend, share}};
  for (const auto& variant : variants) {
    for (const double delay_ms : {0.0, 10.0, 25.0, 50.0, 100.0}) {
      double observed = 0.0, onsets = 0.0, trips = 0.0, drift = 0.0, rest = 0.0, rest_max = 0.0, rmse = 0.0;
      double after = 0.0, after_max = 0.0, after_rest = 0.0, after_rest_max = 0.0;
      constexpr int kTableSeeds = 10;
      for (int seed = 1; seed <= kTableSeeds; ++seed) {
        const auto o = run(delay_ms, variant.mode, variant.reserve_j, static_cast<std::uint64_t>(seed),
                           variant.display_spend_s, variant.reserve_share);
        observed = std::min({observed, o.min_observed_j[0], o.min_observed_j[1]});
        onsets += o.onsets_per_s / kTableSeeds;
        trips += o.lever_faults / static_cast<double>(kTableSeeds);
        drift += 1e3 * o.max_drift_rad / kTableSeeds;
        rest += 1e3 * o.max_rest_offset_rad / kTableSeeds;
        rest_max = std::max(rest_max, 1e3 * o.max_rest_offset_rad);
        rmse += o.force_rmse_n / kTableSeeds;
        after += 1e3 * o.max_drift_after_contact_rad / kTableSeeds;
        after_max = std::max(after_max, 1e3 * o.max_drift_after_contact_rad);
        after_rest += 1e3 * o.max_rest_offset_after_contact_rad / kTableSeeds;
        after_rest_max = std::max(after_rest_max, 1e3 * o.max_rest_offset_after_contact_rad);
      }
      std::printf(
          "| %s | %.0f ms | %.3f J | %.2f | %.1f | %.1f mrad | %.1f mrad (%.1f) | %.1f mrad (%.1f) | "
          "%.1f mrad (%.1f) | %.2f N |\n",
          variant.name, delay_ms, observed, onsets, trips, drift, rest, rest_max, after, after_max, after_rest,
          after_rest_max, rmse);
    }
  }
  SUCCEED();
}

// lever-fw refuses the same configuration (tests/cli/lever_fw_cli.sh); the HIL says why rather than run it.
TEST_CASE("the HIL refuses a TOP with a reference low-pass under tdpa", "[hil][passivity]") {
  SimConfig c;
  c.duration_s = 0.1;
  c.top_reference_cutoff_hz = 12.5;
  c.top_firmware.passivity.mode = fw::PassivityMode::tdpa;
  CHECK_THROWS_AS(run_simulation(c), std::invalid_argument);
  c.top_firmware.passivity.mode = fw::PassivityMode::off;
  CHECK_NOTHROW(run_simulation(c));
}
