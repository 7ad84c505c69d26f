// The passivity observer and controller (fw/passivity.hpp) on their own: the energy account under the link's
// accidents, and the controller's bound.
#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <optional>
#include <utility>

#include "lever/fw/passivity.hpp"
#include "lever/fw/top_role.hpp"

using namespace lever::fw;
using lever::protocol::EnergyMessage;

namespace {
EnergyMessage joules(double j, std::uint8_t epoch = 1) {
  return {static_cast<std::uint32_t>(static_cast<std::uint64_t>(j * 1e6) & 0xFFFFFFFFu), 0, epoch};
}
}  // namespace

TEST_CASE("the received energy is the largest sent, whatever the frames' order, loss or duplication", "[passivity]") {
  ReceivedEnergy r;
  r.accept(joules(0.0));  // the baseline
  // Sent in this order; arrive reordered, one duplicated, one lost (0.3).
  const double arrivals[] = {0.1, 0.4, 0.2, 0.4, 0.5, 0.25};
  double largest = 0.0;
  for (const double e : arrivals) {
    r.accept(joules(e));
    largest = e > largest ? e : largest;
    CHECK(r.energy_j() == Approx(largest).margin(1e-9));
  }
}

TEST_CASE("the energy field wraps at 2^32 uJ and the account goes on growing", "[passivity]") {
  ReceivedEnergy r;
  EnergyMessage m{0xFFFFFF00u, 0, 3};
  r.accept(m);             // baseline just below the wrap
  m.energy = 0x00000100u;  // 512 uJ later, past the wrap
  r.accept(m);
  CHECK(r.energy_j() == Approx(512e-6).margin(1e-12));
  m.energy = 0xFFFFFF80u;  // an older frame, from before the wrap: dropped
  r.accept(m);
  CHECK(r.energy_j() == Approx(512e-6).margin(1e-12));
}

TEST_CASE("a newer epoch restarts the account; an older one is dropped", "[passivity]") {
  ReceivedEnergy r;
  r.accept(joules(0.0, 5));
  r.accept(joules(2.0, 5));
  CHECK(r.accept(joules(0.0, 6)));  // the peer armed again
  CHECK(r.energy_j() == 0.0);
  r.accept(joules(9.0, 5));  // a late frame of the old epoch
  CHECK(r.energy_j() == 0.0);
  r.accept(joules(0.3, 6));
  CHECK(r.energy_j() == Approx(0.3).margin(1e-9));
}

TEST_CASE("tdpa never puts out more energy than the peer put in; observe only watches", "[passivity]") {
  PassivityPort tdpa({PassivityMode::tdpa, 5.0, 0.0});
  PassivityPort observe({PassivityMode::observe, 5.0, 0.0});
  for (auto* port : {&tdpa, &observe}) {
    port->on_armed();
    port->receive(joules(0.0));
    port->receive(joules(0.010));  // 10 mJ to spend
  }
  // 2 W out for 10 ms asks 20 mJ: tdpa gives 10 mJ and scales the rest away.
  double tdpa_out = 0.0;
  for (int i = 0; i < 10; ++i) {
    const double s = tdpa.limit(2.0, 1e-3);
    CHECK(s >= 0.0);
    CHECK(s <= 1.0);
    tdpa_out += s * 2.0 * 1e-3;
    CHECK(tdpa.state().observed_j >= -1e-12);
    CHECK(observe.limit(2.0, 1e-3) == 1.0);
  }
  CHECK(tdpa_out == Approx(0.010).margin(1e-9));
  CHECK(tdpa.state().dissipated_j == Approx(0.010).margin(1e-9));
  CHECK(observe.state().observed_j == Approx(-0.010).margin(1e-9));
  CHECK(observe.state().dissipated_j == 0.0);
}

TEST_CASE("input energy goes to the peer in the next energy frame, rounded down to the microjoule", "[passivity]") {
  PassivityPort port({PassivityMode::tdpa, 5.0, 0.0});
  port.on_armed();
  port.limit(-1.5, 1e-3);
  const auto frame = port.frame(100, false);
  REQUIRE(frame);
  CHECK(frame->energy == 1500u);
  CHECK_FALSE(port.frame(101, false));                          // nothing new
  CHECK(port.frame(102, true));                                 // but a refresh carries it again
  CHECK(port.state().observed_j == Approx(0.0).margin(1e-12));  // passed on: none of it is this port's to spend
}

TEST_CASE("tdpa lets out exactly the energy left, not more, on the tick the budget runs out", "[passivity]") {
  PassivityPort port({PassivityMode::tdpa, 5.0, 0.0});
  port.on_armed();
  port.receive(joules(0.0));
  port.receive(joules(0.003));          // 3 mJ
  CHECK(port.limit(2.0, 1e-3) == 1.0);  // 2 mJ of 3
  // 2 mJ asked, 1 mJ left: half of the output goes out.
  CHECK(port.limit(2.0, 1e-3) == Approx(0.5).margin(1e-9));
  CHECK(port.state().observed_j == Approx(0.0).margin(1e-12));
  CHECK(port.state().dissipated_j == Approx(0.001).margin(1e-9));
  CHECK(port.limit(2.0, 1e-3) == 0.0);  // nothing left
  // Energy this side puts in is not the budget: only the peer's counts.
  port.limit(-5.0, 1e-3);
  CHECK(port.limit(2.0, 1e-3) == 0.0);
}

// The display's spending spread over a time constant (PassivityConfig::display_spend_time_s): a hand that has
// pushed into the display and then yields. Spent at once, the whole force goes out until the account is empty and
// then none; spread, each tick spends a fixed share of what is held, so the force fades and the account never
// lets out more than the cut at once would.
TEST_CASE("spread over a time constant, the port spends a share of what it holds each tick and the force fades",
          "[passivity]") {
  constexpr double kDt = 1e-3, kPower = 0.05;  // 50 mW: 9 N at the 0.1 m handle, yielding at 0.055 rad/s
  for (const double spend_s : {0.0, 0.040}) {
    CAPTURE(spend_s);
    PassivityPort port(
        {.mode = PassivityMode::tdpa, .reserve_j = 0.0125, .reserve_share = 1.0, .display_spend_time_s = spend_s});
    port.on_armed();
    port.receive(joules(0.0));
    for (int tick = 0; tick < 20; ++tick) port.limit(-kPower, kDt, spend_s);  // pushes in: 1 mJ kept
    const double held = port.state().observed_j;
    REQUIRE(held == Approx(0.001).margin(1e-12));
    double out = 0.0, previous = 1.0, largest_drop = 0.0;
    for (int tick = 0; tick < 60; ++tick) {
      const double scale = port.limit(kPower, kDt, spend_s);  // yields
      out += scale * kPower * kDt;
      largest_drop = std::max(largest_drop, previous - scale);
      previous = scale;
    }
    CHECK(out <= held + 1e-12);
    CHECK(port.state().observed_j >= -1e-12);
    if (spend_s == 0.0) {
      CHECK(largest_drop == Approx(1.0).margin(1e-9));  // the whole force, then none
      CHECK(port.state().observed_j == Approx(0.0).margin(1e-12));
    } else {
      // First tick: 1 mJ x (1 ms / 40 ms) = 25 uJ of the 50 uJ asked; then 2.5 % less each tick.
      CHECK(largest_drop == Approx(0.5).margin(1e-9));
      CHECK(previous == Approx(0.5 * std::pow(1.0 - kDt / spend_s, 59)).epsilon(1e-9));
      CHECK(port.state().observed_j == Approx(0.001 * std::pow(1.0 - kDt / spend_s, 60)).epsilon(1e-9));
    }
  }
}

// The reserve is an account the port's own input refills: a hand that yields to the display (output) and pushes
// back (input) over and over spends the same millijoules, and with reserve_share 1 only input beyond a full reserve
// goes to the peer.
TEST_CASE("the reserve refills from the port's own input before anything more is passed", "[passivity]") {
  PassivityPort port({.mode = PassivityMode::tdpa, .reserve_j = 0.010, .reserve_share = 1.0});
  port.on_armed();
  port.receive(joules(0.0));
  port.limit(-15.0, 1e-3);  // 15 mJ in: 10 mJ kept, 5 mJ passed
  CHECK(port.state().passed_j == Approx(0.005).margin(1e-12));
  CHECK(port.state().observed_j == Approx(0.010).margin(1e-12));
  for (int cycle = 0; cycle < 100; ++cycle) {
    CAPTURE(cycle);
    CHECK(port.limit(8.0, 1e-3) == 1.0);  // yields: 8 mJ out of the reserve
    port.limit(-8.0, 1e-3);               // pushes back: the same 8 mJ in, kept
  }
  CHECK(port.state().passed_j == Approx(0.005).margin(1e-9));
  CHECK(port.state().dissipated_j == 0.0);
  port.limit(-4.0, 1e-3);  // beyond a full reserve: passed on
  CHECK(port.state().passed_j == Approx(0.009).margin(1e-9));
  // Spent is spent: output beyond the reserve is cut, and what was passed is not taken back.
  CHECK(port.limit(20.0, 1e-3) == Approx(0.5).margin(1e-9));
  CHECK(port.state().passed_j == Approx(0.009).margin(1e-9));
  // The peer's energy is spent here or kept, never bounced back.
  port.receive(joules(0.050));
  CHECK(port.state().passed_j == Approx(0.009).margin(1e-9));
  CHECK(port.state().observed_j == Approx(0.050).margin(1e-9));
}

// reserve_share: of each joule taken in, that share fills the reserve while it has room and the rest goes to the
// peer at once, so a peer that needs energy to follow is not kept waiting until this port's reserve is full.
TEST_CASE("with a reserve share, each joule taken in is split between the reserve and the peer", "[passivity]") {
  PassivityPort port({.mode = PassivityMode::tdpa, .reserve_j = 0.010, .reserve_share = 0.8});
  port.on_armed();
  port.receive(joules(0.0));
  port.limit(-5.0, 1e-3);  // 5 mJ in: 4 kept, 1 passed at once
  CHECK(port.state().kept_j == Approx(0.004).margin(1e-12));
  CHECK(port.state().passed_j == Approx(0.001).margin(1e-12));
  CHECK(port.frame(1, false)->energy == 1000u);  // in the next energy frame, in microjoules
  port.limit(-10.0, 1e-3);                       // 10 mJ in: 8 offered to the reserve, which has room for 6; 4 passed
  CHECK(port.state().kept_j == Approx(0.010).margin(1e-12));
  CHECK(port.state().passed_j == Approx(0.005).margin(1e-12));
  CHECK(port.state().observed_j == Approx(0.010).margin(1e-12));
  // What the port spends of its reserve refills at the same share.
  CHECK(port.limit(5.0, 1e-3) == 1.0);
  port.limit(-5.0, 1e-3);
  CHECK(port.state().kept_j == Approx(0.009).margin(1e-12));
  CHECK(port.state().passed_j == Approx(0.006).margin(1e-12));
}

// Two ports joined by a delayed, lossy link, driven by random power at both ends: whatever each port keeps of
// its own input (the reserve), the two-port never puts out more than came in. The sum of both inputs less both
// outputs is the channel's energy; it is checked every tick.
TEST_CASE("two ports over a delayed lossy link never put out more than came in, with or without a reserve",
          "[passivity]") {
  for (const auto& [reserve_j, share] : {std::pair{0.0, 1.0}, {0.0125, 1.0}, {0.0125, 0.8}, {0.5, 1.0}, {0.5, 0.3}}) {
    CAPTURE(reserve_j, share);
    const PassivityConfig config{.mode = PassivityMode::tdpa, .reserve_j = reserve_j, .reserve_share = share};
    PassivityPort ports[2] = {PassivityPort(config), PassivityPort(config)};
    for (auto& p : ports) p.on_armed();
    constexpr std::size_t kDelay = 37;  // ticks on the link, each way
    std::optional<EnergyMessage> link[2][kDelay];
    std::uint64_t rng = 0x9E3779B97F4A7C15u;
    auto uniform = [&rng] {  // xorshift64*, in [-1, 1)
      rng ^= rng >> 12;
      rng ^= rng << 25;
      rng ^= rng >> 27;
      return static_cast<double>((rng * 2685821657736338717u) >> 11) / 4503599627370496.0 - 1.0;
    };
    double in[2] = {0.0, 0.0}, out[2] = {0.0, 0.0}, lowest = 0.0;
    for (std::size_t tick = 0; tick < 200000; ++tick) {
      for (int i = 0; i < 2; ++i) {
        // Deliver what was sent kDelay ticks ago to the other port (1 % lost).
        auto& slot = link[i][tick % kDelay];
        if (slot && uniform() > -0.98) ports[1 - i].receive(*slot);
        slot.reset();
        // Up to 2 W either way, in bursts: a port's side pushes in or draws out.
        const double want_w = 2.0 * uniform() * (((tick / 500) % 3) == 0 ? 1.0 : 0.2);
        const double scale = ports[i].limit(want_w, 1e-3);
        if (want_w < 0.0)
          in[i] -= want_w * 1e-3;
        else
          out[i] += scale * want_w * 1e-3;
        slot = ports[i].frame(static_cast<lever::fw::Tick>(tick), tick % 100 == 0);
      }
      lowest = std::min(lowest, in[0] + in[1] - out[0] - out[1]);
    }
    CHECK(lowest >= -1e-9);
    CHECK(out[0] + out[1] > 1.0);  // energy did flow out: the bound was exercised, not idle
  }
}

// The TOP's drift pull under tdpa (top_role.hpp): out of contact it aims at the HSI's position; in contact no further
// past the lever than its position loop can press with the motor (torque limit / kp), wherever the HSI went.
TEST_CASE("in contact the TOP's pull aims no further past the lever than the motor can press", "[passivity]") {
  LeverConfig config;
  config.role = lever::protocol::Role::top;
  config.passivity.mode = PassivityMode::tdpa;
  TopRole top(config);
  const double max_press = config.torque_limit_nm / config.position.kp;
  REQUIRE(max_press == Approx(0.025));  // 1 N m at 40 N m/rad

  LeverTelemetry t;
  t.position_rad = 0.30;  // against the wall
  top.on_armed(t);
  // The peer's energy: the first frame is the baseline, the second gives plenty.
  top.passivity().receive({0, 0, 1});
  top.passivity().receive({10'000'000, 1, 1});  // 10 J
  // The HSI at rest at `hsi`, a motion frame (which carries its position) every 20 ticks; the gauge reads `force_n`,
  // and with `follow` the lever moves freely to its reference.
  lever::fw::Tick now = 1;
  double deepest = 0.0;
  auto run_until = [&](lever::fw::Tick end, double hsi, double force_n, bool follow) {
    for (; now < end; ++now) {
      if (now % 20 == 1) {
        lever::protocol::MotionMessage m;
        m.position = static_cast<std::int16_t>(std::lround(hsi / lever::protocol::kPositionLsbRad));
        m.tick = static_cast<std::uint16_t>(now);
        m.seq = static_cast<std::uint8_t>(now / 20);
        m.flags.restart = m.seq == 0;
        bool used = false;
        top.receive(lever::protocol::pack(m, 0), now, used);
      }
      t.force_n = force_n;
      if (follow) t.position_rad = t.position_ref_rad;
      top.control(now, 1e-3, t);
      deepest = std::max(deepest, t.position_ref_rad);
    }
  };
  // First the HSI where the TOP is, out of contact: the approach after arming ends.
  run_until(100, 0.30, 0.0, false);
  REQUIRE(t.position_ref_rad == Approx(0.30).margin(1e-3));
  // The HSI 0.1 rad past the wall while the TOP presses it (in contact).
  const double hsi = 0.40;
  deepest = 0.0;
  run_until(3000, hsi, 5.0, false);
  // It has pressed in as far as it may (the pull closes the gap at 10/s), and not further.
  CHECK(deepest <= t.position_rad + max_press + 1e-9);
  CHECK(t.position_ref_rad == Approx(t.position_rad + max_press).margin(1e-4));
  // Out of contact the same pull takes it all the way to the HSI.
  run_until(6000, hsi, 0.0, true);
  CHECK(t.position_ref_rad == Approx(hsi).margin(1e-3));
}

// Under tdpa the port limits the velocity the TOP applies and counts its power; the reference's low-pass after it would
// apply a velocity the port never counted, and before it lags the passive reference (docs/firmware.md).
TEST_CASE("a reference low-pass under tdpa is refused; without tdpa it is taken", "[passivity]") {
  LeverConfig config;
  config.role = lever::protocol::Role::top;
  config.position.reference_velocity_cutoff_hz = 12.5;
  for (const PassivityMode mode : {PassivityMode::off, PassivityMode::observe}) {
    config.passivity.mode = mode;
    CHECK(is_valid(config));
  }
  config.passivity.mode = PassivityMode::tdpa;
  CHECK(reference_low_pass_conflicts(config));
  CHECK_FALSE(is_valid(config));
  config.position.reference_velocity_cutoff_hz = 0.0;
  CHECK(is_valid(config));
  // The HSI has no position loop, so the key does nothing there.
  config.role = lever::protocol::Role::hsi;
  config.position.reference_velocity_cutoff_hz = 12.5;
  CHECK(is_valid(config));
}
