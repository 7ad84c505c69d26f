// The levers' crossover frequencies and phase margins, computed from the firmware's gains and the HIL's plant,
// and the timing budget of firmware/core derived from them (docs/firmware.md, "Timing budget"): the defaults of
// StepTiming::Config are held to the derivation, so a change of gains, plant or budget that breaks it fails here.
#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <deque>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "contact_check.hpp"
#include "lever/fw/lever_config.hpp"
#include "lever/hil/simulation.hpp"
#include "loop_response.hpp"

using namespace lever;
using test::Complex;
using test::kPeriod;

namespace {

// The share of a loop's phase margin that timing may spend; the rest stays for what the model leaves out.
constexpr double kTimingShareOfMargin = 0.5;

struct Loops {
  hil::SimConfig sim = hil::SimConfig{};  // the HIL's plant, wall, operator and amplifier (docs/hil-model.md)
  // The firmware's gains as the boards run them (firmware/config/hsi.toml and top.toml, which the HIL's defaults
  // follow).
  fw::LeverConfig top = sim.top_firmware;
  fw::LeverConfig hsi = sim.hsi_firmware;
  // What the HSI sends as its velocity: in the HIL the paper's chain (SimConfig's default), on a board its
  // configuration's (firmware/config/hsi.toml, LeverConfig's default).
  fw::MotionVelocity hil_sent = sim.hsi_firmware.motion_velocity;
  fw::MotionVelocity board_sent = fw::LeverConfig{}.motion_velocity;
  // How the TOP takes the reference's velocity: through k_d + k_ff after a first-order low-pass at `cutoff_hz` (0:
  // as received), or through k_ff alone with the D on the TOP's own velocity (docs/hil-model.md, "The TOP's use of
  // the reference's velocity, derived").
  struct ReferencePath {
    double cutoff_hz = 0.0;
    bool feedforward_only = false;
  };
  // Each HSI contact loop with the settings it runs with: the HIL's those it designs for its HSI's velocity
  // (hil::contact_settings), a board's its configuration's (LeverConfig's defaults, which firmware/config/hsi.toml
  // and top.toml follow).
  struct ContactSide {
    ReferencePath reference;
    double damping_nms = 0.0;
  };
  static ContactSide side_of(const hil::ContactSettings& c) {
    return {{c.top_reference_cutoff_hz, false}, c.hsi_contact_damping_nms};
  }
  ContactSide hil_contact = side_of(hil::contact_settings(sim));
  ContactSide board_contact{{fw::LeverConfig{}.position.reference_velocity_cutoff_hz, false},
                            fw::LeverConfig{}.display.contact_damping_nms};
  // As the derivations before the contact's design ran: both loops on one reference path, the firmware's damping.
  void both_contacts(ReferencePath path) { hil_contact = board_contact = {path, hsi.display.contact_damping_nms}; }

  test::LeverMechanics top_free(bool moving) const {
    const auto& p = sim.top_plant;
    // At rest the Coulomb friction is a steep linear zone (coulomb / coulomb_speed), in motion it adds nothing.
    return {p.inertia, p.viscous + (moving ? 0.0 : p.coulomb / p.coulomb_speed), 0.0, p.motor_time_constant};
  }
  test::LeverMechanics top_at_wall() const {
    const auto& p = sim.top_plant;
    return {p.inertia, p.viscous + sim.wall.damping, sim.wall.stiffness, p.motor_time_constant};
  }
  test::LeverMechanics hsi_in_hand() const {
    const auto& p = sim.hsi_plant;
    const auto& h = sim.operator_params;
    return {p.inertia + h.hand_inertia, p.viscous + h.damping, h.stiffness, p.motor_time_constant};
  }

  // The TOP's position loop broken at its torque: PD on the angle, the D through the velocity estimate.
  Complex top_loop(const test::SampledPlant& plant, double w) const {
    const Complex z = std::polar(1.0, w * kPeriod);
    const Complex v = test::velocity_estimate(z, top.velocity);
    return (top.position.kp + top.position.kd * v) * plant.at(z);
  }

  // The velocity the HSI sends, over its angle.
  Complex sent_velocity(Complex z, fw::MotionVelocity sent) const {
    return sent == fw::MotionVelocity::difference ? (1.0 - 1.0 / z) / kPeriod
                                                  : test::velocity_estimate(z, hsi.velocity);
  }
  // The TOP's torque over the reference's velocity as received.
  Complex reference_gain(const ReferencePath& reference, Complex z) const {
    const auto& c = top.position;
    if (reference.feedforward_only) return c.kff_velocity;
    if (reference.cutoff_hz <= 0.0) return c.kd + c.kff_velocity;
    const double alpha = 1.0 - std::exp(-2.0 * std::numbers::pi * reference.cutoff_hz * kPeriod);
    return (c.kd + c.kff_velocity) * alpha / (1.0 - (1.0 - alpha) / z);
  }
  // The TOP's angle over the reference's angle, both sent the same tick (the link's delay left out).
  Complex tracking(const test::SampledPlant& top_plant, fw::MotionVelocity sent, const ReferencePath& reference,
                   Complex z) const {
    const auto& c = top.position;
    const Complex pt = top_plant.at(z);
    const Complex v_top = test::velocity_estimate(z, top.velocity);
    return pt * (c.kp + reference_gain(reference, z) * sent_velocity(z, sent)) / (1.0 + pt * (c.kp + c.kd * v_top));
  }

  // The HSI in contact, broken at its torque: its own contact damping, and the teleoperation loop (its angle
  // and the velocity it sends to the TOP over the link, the TOP's closed position loop pressing the wall, the
  // wall's force through the amplifier and back over the link, displayed). `gauge`: the amplifier (its filter;
  // none at a cut-off of 0); `gauge_delay_s`: its output hold and, on a board, the Modbus poll. `sent`: what the HSI
  // sends as its velocity (the HIL's paper chain the quantized angle's backward difference, a board its estimate).
  Complex hsi_loop(const test::SampledPlant& hsi_plant, const test::SampledPlant& top_plant, int link_ticks,
                   const hil::StrainGaugeParams& gauge, double gauge_delay_s, fw::MotionVelocity sent,
                   const ContactSide& contact, double w) const {
    const Complex z = std::polar(1.0, w * kPeriod);
    const Complex s{0.0, w};
    const Complex v_hsi = test::velocity_estimate(z, hsi.velocity);
    const Complex hold = std::exp(-s * gauge_delay_s);
    const double pole = 2.0 * std::numbers::pi * gauge.pole_hz();
    const Complex amplifier = gauge.filter_hz > 0.0 ? hold / ((1.0 + s / pole) * (1.0 + s / pole)) : hold;
    const Complex wall_torque = sim.wall.stiffness + sim.wall.damping * s;
    const double display = hsi.display.gain * hsi.display.lever_arm_m / sim.top_plant.radius;
    const Complex teleoperation = std::pow(z, -2.0 * link_ticks) * amplifier * wall_torque *
                                  tracking(top_plant, sent, contact.reference, z) * display;
    return (teleoperation + contact.damping_nms * v_hsi) * hsi_plant.at(z);
  }
};

// The amplifier's output hold in the HIL, half its output period on average (the run's gauge chain's amplifier).
double hil_gauge_hold_s(const Loops& l) { return 0.5 / hil::effective_gauge(l.sim).output_rate_hz(); }
// On a board the newest Modbus reading is half a poll old on average, plus the exchange (1.5 ms at 115200 baud).
constexpr double kBoardGaugeHoldS = 0.5 * 5e-3 + 1.5e-3;

// The smallest margin of each loop the timing budget covers, in the table's order (docs/firmware.md): the TOP in free
// motion moving and at rest, the TOP at the wall, the HSI in contact on the HIL's amplifier and on a board's Modbus
// poll; none for a loop whose gain never reaches 1.
std::array<std::optional<test::Margin>, 5> loop_margins(const Loops& l) {
  const test::SampledPlant moving(l.top_free(true)), rest(l.top_free(false)), wall(l.top_at_wall());
  const test::SampledPlant hsi(l.hsi_in_hand());
  const int link = hil::nominal_one_way_delay_ticks(l.sim);
  return {test::smallest_margin([&](double w) { return l.top_loop(moving, w); }),
          test::smallest_margin([&](double w) { return l.top_loop(rest, w); }),
          test::smallest_margin([&](double w) { return l.top_loop(wall, w); }), test::smallest_margin([&](double w) {
            return l.hsi_loop(hsi, wall, link, hil::effective_gauge(l.sim), hil_gauge_hold_s(l), l.hil_sent,
                              l.hil_contact, w);
          }),
          test::smallest_margin([&](double w) {
            return l.hsi_loop(hsi, wall, link, l.sim.gauge, kBoardGaugeHoldS, l.board_sent, l.board_contact, w);
          })};
}

// The delay margin a loop needs for the timing budget: one lost period and a long step within its share.
double budget_delay_margin_ms() {
  const fw::StepTiming::Config timing{};
  return (kPeriod * 1e3 + static_cast<double>(timing.long_step_us) * 1e-3) / kTimingShareOfMargin;
}

void print(const char* loop, const test::Margin& m) {
  std::printf("loop margins: %-44s crossover %6.2f Hz  phase margin %6.1f deg  %5.1f deg/ms  delay margin %5.2f ms\n",
              loop, m.crossover_hz, m.phase_margin_deg, m.degrees_per_ms(), m.delay_margin_ms());
}

// The TOP at the wall, linear, simulated at 10 us with the firmware's estimator and PD, its torque applied
// `delay_s` after each sample: the peak angle in the last 100 ms over the first 100 ms after a 1 mrad kick.
double top_growth_with_delay(const Loops& l, double delay_s) {
  const auto m = l.top_at_wall();
  constexpr int kSub = 100;
  const double h = kPeriod / kSub;
  const int delay_steps = static_cast<int>(std::lround(delay_s / h));
  std::deque<double> pending(static_cast<std::size_t>(delay_steps) + 1, 0.0);
  double angle = 1e-3, speed = 0.0, motor = 0.0, command = 0.0;
  fw::VelocityEstimator estimator(l.top.velocity);
  estimator.update(angle, kPeriod);  // primed at the kicked angle, at rest
  double first = 0.0, last = 0.0;
  constexpr int kTicks = 800;
  for (int k = 0; k < kTicks; ++k) {
    const double velocity = estimator.update(angle, kPeriod);  // the firmware's step, on the sampled angle
    const double torque = -(l.top.position.kp * angle + l.top.position.kd * velocity);
    for (int i = 0; i < kSub; ++i) {
      pending.push_back(torque);
      command = pending.front();
      pending.pop_front();
      motor += (command - motor) * h / m.motor_lag_s;
      speed += (motor - m.damping * speed - m.stiffness * angle) / m.inertia * h;
      angle += speed * h;
    }
    if (k < 100) first = std::max(first, std::fabs(angle));
    if (k >= kTicks - 100) last = std::max(last, std::fabs(angle));
  }
  return last / first;
}

}  // namespace

TEST_CASE("the loops' crossovers and phase margins, and the timing budget of firmware/core derived from them",
          "[hil][timing][margins]") {
  const Loops l;
  // The adaptive window is not linear; neither end sends it by default.
  REQUIRE(l.hil_sent != fw::MotionVelocity::adaptive_window);
  REQUIRE(l.board_sent != fw::MotionVelocity::adaptive_window);
  const auto [free_moving, free_rest, wall, contact, contact_board] = loop_margins(l);
  REQUIRE(free_moving);
  REQUIRE(free_rest);
  REQUIRE(wall);
  REQUIRE(contact);
  REQUIRE(contact_board);
  print("TOP free, moving (viscous friction only)", *free_moving);
  print("TOP free, at rest (Coulomb's linear zone)", *free_rest);
  print("TOP at the wall", *wall);
  print("HSI in contact, hand on (HIL amplifier)", *contact);
  print("HSI in contact, hand on (Modbus at 5 ms)", *contact_board);

  // The frequency responses against the time domain: a sustained extra delay below the TOP's delay margin
  // leaves its loop at the wall stable, one above it does not.
  CHECK(top_growth_with_delay(l, 0.0) < 0.1);
  CHECK(top_growth_with_delay(l, 0.8 * wall->delay_margin_ms() * 1e-3) < 1.0);
  CHECK(top_growth_with_delay(l, 1.2 * wall->delay_margin_ms() * 1e-3) > 1.0);

  // The budget: timing may cost each closed loop that must stay stable (the TOP at the wall, the HSI in
  // contact) half its phase margin, within each period of its crossover; a step's duration is a sustained
  // delay and takes its share first. The TOP in free motion is left out: moving, its margin is a few degrees
  // (the tracking loop's velocity lags the angle by 80 degrees at 250 rad/s), which no timing budget can
  // protect; at rest Coulomb's linear zone damps it (docs/firmware.md, "Timing budget").
  const fw::StepTiming::Config timing{};
  const double step_ms = static_cast<double>(timing.long_step_us) * 1e-3;
  const auto budget_ms = [&](const test::Margin& m) { return kTimingShareOfMargin * m.delay_margin_ms(); };
  const double lateness_ms = std::min({budget_ms(*wall), budget_ms(*contact), budget_ms(*contact_board)}) - step_ms;
  const double slowest_cycle_ms =
      1e3 / std::min({wall->crossover_hz, contact->crossover_hz, contact_board->crossover_hz});
  std::printf(
      "loop margins: budget %.2f ms of lost time per %.1f ms (the slowest crossover's period), after %.2f ms of "
      "step; a late tick loses %.0f ms: %.1f deg at the wall, %.1f deg at the HSI\n",
      lateness_ms, slowest_cycle_ms, step_ms, kPeriod * 1e3, wall->degrees_per_ms(), contact->degrees_per_ms());
  // One late tick must fit, or no lateness would be tolerable at all.
  CHECK(lateness_ms >= 1.0);
  // The firmware allows fault_after - 1 periods of lost time per window: no more than the budget, and the
  // whole periods of it.
  const double allowed_ms = static_cast<double>(timing.fault_after - 1) * kPeriod * 1e3;
  CHECK(allowed_ms <= lateness_ms);
  CHECK(allowed_ms + kPeriod * 1e3 > lateness_ms);
  // Within any crossover period of any of the loops, no more than the budget: the window spans the longest.
  CHECK(static_cast<double>(timing.window) == std::ceil(slowest_cycle_ms));
}

// The method of docs/hil-model.md, "The TOP's velocity estimate, derived again": of the tracking loop's two outputs
// at 100, 125, ..., 825 rad/s, those whose every TOP loop and both HSI contact loops keep a delay margin of twice one
// lost period and a long step (the timing budget), the one with the least white-noise gain; a tie within 1 % goes to
// the integrator, then to the smaller bandwidth. Its pick failed the contact check and is not applied; hidden, a tool
// that prints every candidate and the pick (lever_tests_hil "[velocity-derivation]").
TEST_CASE("the TOP's velocity estimate by its documented derivation", "[.][velocity-derivation]") {
  const double needed_ms = budget_delay_margin_ms();
  std::optional<fw::VelocityEstimator::Config> pick;
  double pick_gain = 0.0;
  for (const auto method : {fw::VelocityMethod::tracking_loop, fw::VelocityMethod::tracking_loop_rate}) {
    for (double b = 100.0; b <= 825.0; b += 25.0) {
      Loops l;
      l.both_contacts({});
      l.top.velocity = {method, b};
      const auto margins = loop_margins(l);
      const bool kept = std::all_of(margins.begin(), margins.end(),
                                    [&](const auto& m) { return m && m->delay_margin_ms() >= needed_ms; });
      const double gain = test::white_noise_gain(l.top.velocity);
      std::printf("velocity derivation: %-18s %3.0f rad/s  delay margins (ms)", std::string(fw::name(method)).c_str(),
                  b);
      for (const auto& m : margins) std::printf(" %5.2f", m ? m->delay_margin_ms() : -1.0);
      std::printf("  white-noise gain %6.0f%s\n", gain, kept ? "  kept" : "");
      if (kept && (!pick || gain < 0.99 * pick_gain)) {
        pick = l.top.velocity;
        pick_gain = gain;
      }
    }
  }
  REQUIRE(pick);
  std::printf("velocity derivation: the pick is %s at %.0f rad/s (white-noise gain %.0f)\n",
              std::string(fw::name(pick->method)).c_str(), pick->bandwidth_rad_s, pick_gain);
}

// The method of docs/hil-model.md, "The TOP's damping gain and velocity estimate, for the contact's damping": k_d on
// 0.10, 0.15, ..., 1.20 with either output of the tracking loop at 100, 125, ..., 825 rad/s; kept when every TOP
// loop and both HSI contact loops keep the timing budget's delay margin and the D's quantization noise is at most
// half a count of position torque (k_d G <= sqrt(3) k_p); the least resonance peak of the TOP at the wall decides, a
// tie within 1 % going to the lower noise. Hidden, a tool that prints every candidate within the noise bound and the
// pick (lever_tests_hil "[damping-derivation]").
TEST_CASE("the TOP's damping gain and velocity estimate by their documented derivation", "[.][damping-derivation]") {
  const double needed_ms = budget_delay_margin_ms();
  struct Pick {
    fw::VelocityEstimator::Config velocity;
    double kd = 0.0, noise = 0.0, peak = 0.0;
  };
  std::vector<Pick> kept;
  int candidates = 0, quiet = 0;
  for (const auto method : {fw::VelocityMethod::tracking_loop, fw::VelocityMethod::tracking_loop_rate}) {
    for (double b = 100.0; b <= 825.0; b += 25.0) {
      const double gain = test::white_noise_gain({method, b});
      for (int step = 0; step <= 22; ++step) {
        const double kd = 0.10 + 0.05 * step;
        ++candidates;
        Loops l;
        l.both_contacts({});
        l.top.velocity = {method, b};
        l.top.position.kd = kd;
        const double noise = kd * gain;
        if (noise > std::sqrt(3.0) * l.top.position.kp) continue;
        ++quiet;
        const auto margins = loop_margins(l);
        const test::SampledPlant wall(l.top_at_wall());
        // A loop whose gain never reaches 1 has no crossover for a delay to shift: any delay leaves it stable.
        const bool timely = std::all_of(margins.begin(), margins.end(),
                                        [&](const auto& m) { return !m || m->delay_margin_ms() >= needed_ms; });
        const auto response = [&](double w) {
          const Complex z = std::polar(1.0, w * kPeriod);
          return std::abs(wall.at(z) / (1.0 + l.top_loop(wall, w)));
        };
        double peak = 0.0;
        for (double w = 1.0; w < std::numbers::pi / kPeriod; w *= 1.001) peak = std::max(peak, response(w));
        peak /= response(1.0);
        std::printf("damping derivation: %-18s %3.0f rad/s  k_d %.2f  noise %4.1f  delay margins (ms)",
                    std::string(fw::name(method)).c_str(), b, kd, noise);
        for (const auto& m : margins) m ? std::printf(" %5.3f", m->delay_margin_ms()) : std::printf("  none");
        std::printf("  peak %.3f%s\n", peak, timely ? "  kept" : "");
        if (timely) kept.push_back({l.top.velocity, kd, noise, peak});
      }
    }
  }
  std::printf("damping derivation: %d candidates, %d within the noise bound, %d of them within the timing budget\n",
              candidates, quiet, static_cast<int>(kept.size()));
  REQUIRE(!kept.empty());
  const double least_peak =
      std::min_element(kept.begin(), kept.end(), [](const Pick& a, const Pick& b) { return a.peak < b.peak; })->peak;
  std::optional<Pick> pick;
  for (const Pick& p : kept)
    if (p.peak <= 1.01 * least_peak && (!pick || p.noise < pick->noise)) pick = p;
  REQUIRE(pick);
  std::printf("damping derivation: the pick is k_d %.2f with %s at %.0f rad/s (noise %.1f, peak %.3f)\n", pick->kd,
              std::string(fw::name(pick->velocity.method)).c_str(), pick->velocity.bandwidth_rad_s, pick->noise,
              pick->peak);
}

// The method of docs/hil-model.md, "The TOP's use of the reference's velocity, derived": the reference's velocity as
// received, through a first-order low-pass at 400-6.25 Hz, or through k_ff alone; kept when its quantization noise,
// on what the HIL and what a board send, is at most half a count of position torque (k_ref G_ref <= sqrt(3) k_p) and
// both HSI contact loops keep the timing budget's delay margin; the least delay of the TOP behind its reference at
// the script's 4 Hz thrust decides, a tie within 1 % going to the lower noise. Hidden, a tool that prints every
// candidate and the pick (lever_tests_hil "[reference-derivation]").
TEST_CASE("the TOP's use of the reference's velocity by its documented derivation", "[.][reference-derivation]") {
  const double needed_ms = budget_delay_margin_ms();
  const double noise_bound = std::sqrt(3.0) * Loops{}.top.position.kp;
  const double thrust_w = 2.0 * std::numbers::pi * 4.0;
  std::vector<Loops::ReferencePath> candidates{{0.0, false}};
  for (const double cutoff_hz : {400.0, 200.0, 100.0, 50.0, 25.0, 12.5, 6.25}) candidates.push_back({cutoff_hz, false});
  candidates.push_back({0.0, true});
  struct Pick {
    Loops::ReferencePath path;
    double noise = 0.0, lag_ms = 0.0;
  };
  std::optional<Pick> pick;
  std::vector<Pick> kept;
  for (const auto& path : candidates) {
    Loops l;
    l.both_contacts(path);
    const auto noise = [&](fw::MotionVelocity sent) {
      return test::white_noise_gain([&](Complex z) { return l.reference_gain(path, z) * l.sent_velocity(z, sent); });
    };
    const double hil_noise = noise(l.hil_sent), board_noise = noise(l.board_sent);
    const auto margins = loop_margins(l);
    const test::SampledPlant moving(l.top_free(true));
    const double lag_ms =
        -std::arg(l.tracking(moving, l.hil_sent, path, std::polar(1.0, thrust_w * kPeriod))) / thrust_w * 1e3;
    const bool quiet = std::max(hil_noise, board_noise) <= noise_bound;
    // A loop whose gain never reaches 1 has no crossover for a delay to shift: any delay leaves it stable.
    const bool timely = std::all_of(margins.begin() + 3, margins.end(),
                                    [&](const auto& m) { return !m || m->delay_margin_ms() >= needed_ms; });
    char label[32];
    if (path.feedforward_only)
      std::snprintf(label, sizeof label, "through k_ff only");
    else if (path.cutoff_hz > 0.0)
      std::snprintf(label, sizeof label, "low-pass at %.2f Hz", path.cutoff_hz);
    else
      std::snprintf(label, sizeof label, "as received");
    std::printf("reference derivation: %-22s noise %6.1f (HIL) %6.1f (board)  delay margins (ms)", label, hil_noise,
                board_noise);
    for (const auto& m : margins) m ? std::printf(" %6.3f", m->delay_margin_ms()) : std::printf("   none");
    std::printf("  lag at 4 Hz %6.2f ms%s\n", lag_ms, quiet && timely ? "  kept" : "");
    if (quiet && timely) kept.push_back({path, std::max(hil_noise, board_noise), lag_ms});
  }
  REQUIRE(!kept.empty());
  const double least_lag = std::min_element(kept.begin(), kept.end(), [](const Pick& a, const Pick& b) {
                             return a.lag_ms < b.lag_ms;
                           })->lag_ms;
  for (const Pick& p : kept)
    if (p.lag_ms <= least_lag + 0.01 * std::fabs(least_lag) && (!pick || p.noise < pick->noise)) pick = p;
  REQUIRE(pick);
  std::printf("reference derivation: the pick is %s (cut-off %.2f Hz), noise %.1f, lag at 4 Hz %.2f ms\n",
              pick->path.feedforward_only ? "through k_ff only" : "through k_d + k_ff", pick->path.cutoff_hz,
              pick->noise, pick->lag_ms);
}

// The method of docs/hil-model.md, "The design's dampings within the timing budget": on each gauge chain, of the
// dampings that held every open-loop design run at 6.25 Hz (the design's table), those whose HIL contact loop keeps
// the budget's delay margin in every topology the chain runs in; of them the least force_jnd_violation of that
// table, a tie within 0.01 points to the larger. Hidden, a tool that prints every candidate and the pick
// (lever_tests_hil "[contact-budget]").
TEST_CASE("the design's dampings within the timing budget, by the documented method", "[.][contact-budget]") {
  struct Candidate {
    double damping_nms, jnd_percent;
  };
  struct Chain {
    const char* name;
    hil::GaugeChain chain;
    std::vector<Candidate> held;
  };
  // docs/hil-model.md, "The contact designed on seeds of its own": the dampings with which every open-loop design
  // run held at 6.25 Hz, and their mean force_jnd_violation on two sites.
  const Chain chains[] = {{"dad141",
                           hil::GaugeChain::dad141,
                           {{0.5, 2.84}, {0.6, 2.41}, {0.8, 2.24}, {1.0, 2.18}, {1.2, 2.11}, {1.6, 1.96}, {2.0, 1.75}}},
                          {"paper-adc",
                           hil::GaugeChain::paper_adc,
                           {{0.2, 2.67}, {0.3, 2.09}, {0.4, 1.99}, {1.2, 2.70}, {1.6, 3.07}, {2.0, 3.56}}}};
  constexpr double kCutoffHz = 6.25;
  const double needed_ms = budget_delay_margin_ms();
  for (const auto& chain : chains) {
    test::LeastJndPick pick;
    for (const auto& candidate : chain.held) {
      double smallest_ms = std::numeric_limits<double>::infinity();
      std::printf("contact budget: %s, damping %.2f:", chain.name, candidate.damping_nms);
      for (const auto topology : {hil::Topology::one_controller, hil::Topology::one_site, hil::Topology::two_sites}) {
        Loops l;
        l.sim.topology = topology;
        l.sim.gauge_chain = chain.chain;
        l.hil_contact = {{kCutoffHz, false}, candidate.damping_nms};
        const auto contact = loop_margins(l)[3];
        // A loop whose gain never reaches 1 has no crossover for a delay to shift.
        const double margin_ms = contact ? contact->delay_margin_ms() : std::numeric_limits<double>::infinity();
        smallest_ms = std::min(smallest_ms, margin_ms);
        std::printf("  %s %.1f Hz %.1f deg %.2f ms", std::string(hil::name(topology)).c_str(),
                    contact ? contact->crossover_hz : 0.0, contact ? contact->phase_margin_deg : 0.0, margin_ms);
      }
      const bool kept = smallest_ms >= needed_ms;
      std::printf("  -> %s (needs %.2f ms)\n", kept ? "keeps the budget" : "short of the budget", needed_ms);
      if (kept) pick.offer(candidate.damping_nms, candidate.jnd_percent);
    }
    if (pick.damping_nms)
      std::printf("contact budget: %s, pick %.2f N m s/rad (force_jnd_violation %.2f %%)\n", chain.name,
                  *pick.damping_nms, pick.jnd_percent);
    else
      std::printf("contact budget: %s has no damping that held and keeps the budget\n", chain.name);
  }
  SUCCEED();
}

TEST_CASE("a crossing with a phase lead is a wide margin, one with a lag past -180 degrees a negative one",
          "[hil][margins]") {
  // 0.5 (1 + j w / 50) crosses |L| = 1 at 50 sqrt(3) rad/s with a 60 degree lead: 1 + L never vanishes, the margin is
  // 240 degrees, not -120. A double integrator 1e4 / (j w)^2 behind a 3 ms delay crosses at 100 rad/s lagging 17.2
  // degrees past -180: the margin is negative.
  const auto lead = [](double w) { return 0.5 * Complex{1.0, w / 50.0}; };
  const auto m = test::smallest_margin(lead);
  REQUIRE(m);
  CHECK(m->crossover_hz == Approx(50.0 * std::sqrt(3.0) / (2.0 * std::numbers::pi)).epsilon(1e-3));
  CHECK(m->phase_margin_deg == Approx(240.0).margin(0.1));
  const auto lagging = [](double w) { return 1e4 / (Complex{0.0, w} * Complex{0.0, w}) * std::polar(1.0, -3e-3 * w); };
  const auto n = test::smallest_margin(lagging);
  REQUIRE(n);
  CHECK(n->phase_margin_deg == Approx(-3e-3 * 100.0 * 180.0 / std::numbers::pi).margin(0.1));
}
