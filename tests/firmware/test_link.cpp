// Silence is not loss: sequence numbers, tick unwrapping, the watchdog, refresh, coherent parameter changes.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>
#include <vector>

#include "lever/common/rng.hpp"
#include "lever/fw/data_channel.hpp"
#include "lever/fw/link.hpp"
#include "lever/protocol/messages.hpp"

using namespace lever::fw;
using lever::codec::Config;
using lever::codec::Mode;

TEST_CASE("sequence numbers tell gaps from duplicates and reordering, across the wrap", "[firmware][link]") {
  SequenceTracker s;
  CHECK(s.observe(250) == SequenceTracker::Verdict::first);
  CHECK(s.observe(251) == SequenceTracker::Verdict::in_order);
  CHECK(s.observe(251) == SequenceTracker::Verdict::stale);  // duplicate
  CHECK(s.observe(254) == SequenceTracker::Verdict::after_gap);
  CHECK(s.missing() == 2u);
  CHECK(s.observe(253) == SequenceTracker::Verdict::stale);    // late
  CHECK(s.observe(2) == SequenceTracker::Verdict::after_gap);  // 255, 0, 1 missing across the wrap
  CHECK(s.missing() == 5u);
  CHECK(s.stale() == 2u);
}

TEST_CASE("the sender's 16-bit tick unwraps into a monotonic 64-bit tick", "[firmware][link]") {
  TickUnwrapper u;
  CHECK(u.unwrap(65530).tick == 65530u);
  CHECK(u.unwrap(65535).tick == 65535u);
  CHECK(u.unwrap(4).tick == 65540u);
  CHECK(u.unwrap(100).tick == 65636u);
  CHECK_FALSE(u.unwrap(101).restarted);
}

TEST_CASE("a sender's clock going back restarts the unwrap instead of underflowing", "[firmware][link]") {
  // A peer that rebooted to a small tick once gave a time near 2^64 here, and NaN references downstream.
  TickUnwrapper u;
  CHECK(u.unwrap(10).tick == 10u);
  CHECK(u.unwrap(20).tick == 20u);
  const auto back = u.unwrap(3);  // rebooted: 17 ticks "back"
  CHECK(back.restarted);
  CHECK(back.tick == 3u);
  CHECK(u.unwrap(4).tick == 4u);
  // Back by the most a 16-bit difference can say, repeatedly: never below the new tick, never wrapping.
  for (int i = 0; i < 100; ++i) {
    const auto r = u.unwrap(static_cast<std::uint16_t>(4 + 32768 * (i + 1)));
    CHECK(r.tick < 70000u);
  }
  u.unwrap(7);
  CHECK(u.unwrap(7).restarted);  // the same tick twice: not an advance
}

TEST_CASE("the watchdog fires only after the timeout", "[firmware][link]") {
  Watchdog w;
  CHECK(w.silent(0, 50));  // never heard
  w.heard(100);
  CHECK_FALSE(w.silent(150, 50));
  CHECK(w.silent(151, 50));
}

namespace {

template <typename Out>
lever::protocol::DataFlags flags_of(const Out& out) {
  return {out.saturated, false, out.refresh, out.mode, out.restart};
}

struct Link {
  DataSender<std::int32_t> tx;
  DataReceiver<std::int32_t> rx;
  explicit Link(const Config<double>& c, Tick refresh = 100, Tick rest_repeat = 0)
      : tx(c, {lever::protocol::kForceLsb, lever::protocol::kForceCodeMin, lever::protocol::kForceCodeMax}, refresh,
           rest_repeat),
        rx({lever::protocol::kForceLsb, lever::protocol::kForceCodeMin, lever::protocol::kForceCodeMax}) {}
};

}  // namespace

TEST_CASE("deadband silence keeps the receiver exact; the refresh bounds it", "[firmware][link]") {
  Link link({Mode::deadband, 0.1, 0.0, 0.0}, 100);
  int sent = 0;
  Tick last_sent = 0;
  Tick longest_silence = 0;
  for (Tick now = 1000; now < 3000; ++now) {
    const double force = 5.0;  // constant: the deadband alone would never send again
    const auto out = link.tx.offer(now, force);
    if (out.send) {
      REQUIRE(link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, flags_of(out), out.code));
      if (sent > 0) longest_silence = std::max(longest_silence, now - last_sent);
      last_sent = now;
      ++sent;
    }
    REQUIRE(link.rx.value_at(now, 1000).has_value());
    CHECK(*link.rx.value_at(now, 1000) == Approx(5.0).margin(1e-5));
  }
  CHECK(longest_silence == 100u);
  CHECK(sent == 20);
  CHECK(link.rx.sequence().missing() == 0u);
}

TEST_CASE("a stream that stopped is stale, not held forever", "[firmware][link]") {
  Link link({Mode::predictive, 0.1, 0.0, 0.0}, 100);
  for (Tick now = 0; now < 10; ++now) {
    const auto out = link.tx.offer(now, static_cast<double>(now));  // a ramp
    if (out.send) link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, flags_of(out), out.code);
  }
  const Tick last = link.rx.last_arrival();  // the predictor needed only the first samples of the ramp
  CHECK(link.rx.value_at(last + 200, 200).has_value());
  CHECK_FALSE(link.rx.value_at(last + 201, 200).has_value());  // no extrapolating a sender that went quiet
}

TEST_CASE("a lost update heals at the next refresh, and the gap is counted", "[firmware][link]") {
  Link link({Mode::deadband, 0.1, 0.0, 0.0}, 100);
  Tick healed_at = 0;
  for (Tick now = 0; now < 400; ++now) {
    const double force = now < 50 ? 1.0 : 3.0;  // one step at tick 50
    const auto out = link.tx.offer(now, force);
    const bool lose = now == 50;  // exactly the frame carrying the step
    if (out.send && !lose) link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, flags_of(out), out.code);
    if (now > 50 && healed_at == 0 && std::fabs(*link.rx.value_at(now, 1000) - 3.0) < 1e-4) healed_at = now;
  }
  CHECK(healed_at == 150u);  // the refresh 100 ticks after the lost frame
  CHECK(link.rx.sequence().missing() == 1u);
}

// At rest the deadband goes quiet, so the frame that brings a stream there is the one whose loss lasts: the
// receiver would hold the last moving value until the refresh (at one encoder count per tick, 38 mrad of drift).
TEST_CASE("the frame that brings a stream to rest is repeated once, so its loss heals in the repeat time",
          "[firmware][link]") {
  // A value that moves, comes to rest (zero, the paper's rule: floor 0), moves again and rests again.
  const auto value_at = [](Tick now) { return (now >= 100 && now < 195) || (now >= 400 && now < 450) ? 2.0 : 0.0; };
  for (const Tick rest_repeat : {Tick{0}, Tick{10}}) {
    INFO("rest_repeat " << rest_repeat);
    Link link({Mode::deadband, 0.1, 0.0, 0.0}, 100, rest_repeat);
    std::vector<Tick> refreshes;
    Tick healed_at = 0;
    for (Tick now = 1; now < 700; ++now) {
      const auto out = link.tx.offer(now, value_at(now));
      if (out.send && out.refresh) refreshes.push_back(now);
      const bool lose = now == 195;  // exactly the frame that brings the stream to rest
      if (out.send && !lose) link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, flags_of(out), out.code);
      if (now > 195 && healed_at == 0 && *link.rx.value_at(now, 1000) == 0.0) healed_at = now;
    }
    CHECK(link.rx.sequence().missing() == 1u);
    if (rest_repeat == 0) {
      CHECK(healed_at == 295u);  // the refresh
      CHECK(refreshes == std::vector<Tick>{1, 295, 395, 550, 650});
    } else {
      CHECK(healed_at == 205u);
      // Each arrival at rest once (the first frame of the stream included), never a moving value, and the
      // refresh period counts from the repeat.
      CHECK(refreshes == std::vector<Tick>{1, 11, 205, 305, 460, 560, 660});
    }
  }
}

// The paper counts the packets its rule sends; the refresh and the rest repeat are this link's own, counted apart.
TEST_CASE("each data frame says why it goes: the rule, a refresh, or a rest repeat", "[firmware][link]") {
  const auto value_at = [](Tick now) { return now >= 100 && now < 195 ? 2.0 : 0.0; };
  Link link({Mode::deadband, 0.1, 0.0, 0.0}, 100, 10);
  std::vector<std::pair<Tick, SendCause>> sent;
  for (Tick now = 1; now < 400; ++now) {
    const auto out = link.tx.offer(now, value_at(now));
    if (out.send) sent.emplace_back(now, out.cause);
  }
  using C = SendCause;
  // The first frame (no reference yet: the rule's, though forced as a restart) and its repeat at rest, the rule's
  // step up and down, the repeat of the frame that brought the stream to rest, then a refresh a period later.
  CHECK(sent == std::vector<std::pair<Tick, SendCause>>{{1, C::deadband},
                                                        {11, C::rest_repeat},
                                                        {100, C::deadband},
                                                        {195, C::deadband},
                                                        {205, C::rest_repeat},
                                                        {305, C::refresh}});
}

TEST_CASE("with a floor, rest is anywhere within the floor of zero", "[firmware][link]") {
  // Decaying toward zero: the deadband stops sending once the held value is within the floor (0.5 N).
  Link link({Mode::deadband, 0.1, 0.5, 0.0}, 1000, 10);
  std::vector<Tick> refreshes;
  Tick last_data = 0;
  double last_value = 0.0;
  for (Tick now = 1; now < 500; ++now) {
    const double force = now < 50 ? 5.0 : 5.0 * std::exp(-static_cast<double>(now - 50) / 20.0);
    const auto out = link.tx.offer(now, force);
    if (!out.send) continue;
    if (out.refresh) refreshes.push_back(now);
    if (!out.refresh) {
      last_data = now;
      last_value = out.code * lever::protocol::kForceLsb;
    }
  }
  REQUIRE(last_data > 50u);
  CHECK(std::fabs(last_value) <= 0.5);
  CHECK(refreshes == std::vector<Tick>{1, last_data + 10});  // only the arrival within the floor, once
}

TEST_CASE("duplicates and late frames are not fed to the model", "[firmware][link]") {
  Link link({Mode::predictive, 0.05, 0.0, 0.0});
  const auto first = link.tx.offer(0, 1.0);
  const auto a = link.tx.offer(1, 2.0);
  const auto b = link.tx.offer(2, 3.5);
  REQUIRE((first.send && first.restart && a.send && b.send && !a.restart));
  CHECK(link.rx.accept(0, 0, first.seq, flags_of(first), first.code));
  CHECK(link.rx.accept(2, 2, b.seq, flags_of(b), b.code));
  CHECK_FALSE(link.rx.accept(3, 1, a.seq, flags_of(a), a.code));              // late
  CHECK_FALSE(link.rx.accept(3, 2, b.seq, flags_of(b), b.code));              // duplicate
  CHECK_FALSE(link.rx.accept(3, 0, first.seq, flags_of(first), first.code));  // the restart frame, again
  CHECK(link.rx.sequence().stale() == 3u);
  CHECK(link.rx.restarts() == 1u);
}

TEST_CASE("a restarted sender is followed at once: its first frame resets the receiver, whatever its numbers",
          "[firmware][link][reboot]") {
  // Before: the staleness check ran first, so a rebooted peer whose sequence numbers looked old was dropped
  // for up to 127 frames; and the receiver kept the old stream's samples, so in predictive mode it
  // extrapolated a slope from before the restart.
  Link link({Mode::predictive, 0.0, 0.0, 0.0}, 100);
  Tick now = 0;
  // Stop where the rebooted sender's first numbers (0, 1, ...) are 129 or more behind: "stale" to a tracker
  // that does not know the sender restarted.
  for (; now < 5000 && !(now > 300 && link.tx.last_seq() >= 64 && link.tx.last_seq() <= 127); ++now) {
    const auto out = link.tx.offer(now + 40000, std::sin(static_cast<double>(now) * 0.01));
    if (out.send)
      REQUIRE(link.rx.accept(now, static_cast<std::uint16_t>(now + 40000), out.seq, flags_of(out), out.code));
  }
  REQUIRE(link.tx.last_seq() >= 64);  // the new stream's first numbers look stale to the old tracker
  REQUIRE(link.tx.last_seq() <= 127);
  // The sender reboots: new sender, sequence from 0, tick from 1.
  Link rebooted({Mode::predictive, 0.0, 0.0, 0.0}, 100);
  for (Tick t = 1; t < 400; ++t, ++now) {
    const auto out = rebooted.tx.offer(t, 3.0 + 0.002 * static_cast<double>(t));
    if (!out.send) continue;
    REQUIRE(link.rx.accept(now, static_cast<std::uint16_t>(t), out.seq, flags_of(out), out.code));
    // Coherent from the first frame on: the receiver believes exactly what the sender believes.
    const auto shown = link.rx.value_at(now, 1000);
    REQUIRE(shown.has_value());
    const double believed = rebooted.tx.codec_sender().model().at(static_cast<double>(t))[0];
    REQUIRE(std::memcmp(&believed, &*shown, sizeof(double)) == 0);
    REQUIRE(std::isfinite(*shown));
  }
}

TEST_CASE("changing parameters mid-stream keeps both ends bit-identical", "[firmware][link]") {
  Link link({Mode::deadband, 0.1, 0.0, 0.0});
  lever::Rng rng(4);
  double x = 2.0;
  int mode_switches_seen = 0;
  Mode receiver_mode = Mode::deadband;
  // The sender counts from 260000; the receiver only sees ticks modulo 2^16 and so works from another base,
  // across a wrap at 262144. Tick-unit times make the two agree exactly anyway.
  for (Tick now = 260000; now < 265000; ++now) {
    if (now == 261000) link.tx.reconfigure({Mode::predictive, 0.05, 0.01, 40.0});
    if (now == 263000) link.tx.reconfigure({Mode::deadband, 0.2, 0.0, 0.0});
    x += 0.02 * rng.normal();
    const auto out = link.tx.offer(now, x);
    if (now == 261000 || now == 263000) CHECK(out.send);  // the switching sample is always transmitted
    if (out.send) {
      if (out.mode != receiver_mode) ++mode_switches_seen;
      receiver_mode = out.mode;
      REQUIRE(link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, flags_of(out), out.code));
    }
    const auto shown = link.rx.value_at(now, 1000);
    REQUIRE(shown.has_value());
    const double believed = link.tx.codec_sender().model().at(static_cast<double>(now))[0];
    REQUIRE(std::memcmp(&believed, &*shown, sizeof(double)) == 0);
  }
  CHECK(mode_switches_seen == 2);
}

TEST_CASE("the sender decides on what the receiver will decode: no data frame repeats the previous wire code",
          "[firmware][link][codec]") {
  // Deciding on the unquantized value sent 21 % of velocity frames with the code of the frame before at
  // p = 10 %: a change nobody at the other end can see. Long noisy traces, velocity-sized and force-sized.
  for (const double lsb : {lever::protocol::kVelocityLsb, lever::protocol::kForceLsb}) {
    DataSender<std::int32_t> tx({Mode::deadband, 0.1, 0.0, 0.0}, {lsb, -(1 << 23), (1 << 23) - 1}, 100);
    lever::Rng rng(17);
    double x = 0.0;
    std::int32_t previous = 0;
    bool have_previous = false;
    int repeats = 0, data_frames = 0, refreshes = 0;
    for (Tick now = 1; now < 200000; ++now) {
      // Lingering within a few codes of zero, where p |ref| is below half a code: exactly where a decision
      // on the unquantized value sends a frame that decodes to the code already held.
      x = 4.0 * lsb * std::sin(static_cast<double>(now) * 1e-3) + 0.7 * lsb * rng.normal();
      const auto out = tx.offer(now, x);
      if (!out.send) continue;
      if (out.refresh) {
        ++refreshes;  // a refresh repeats on purpose, and says so
      } else {
        ++data_frames;
        if (have_previous && out.code == previous) ++repeats;
      }
      previous = out.code;
      have_previous = true;
    }
    INFO("lsb " << lsb);
    CHECK(data_frames > 1000);
    CHECK(refreshes >= 1);  // at least the first, forced frame
    CHECK(repeats == 0);
  }
}
