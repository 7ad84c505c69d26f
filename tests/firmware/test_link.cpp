// Silence is not loss: sequence numbers, tick unwrapping, the watchdog, refresh, coherent parameter changes.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>

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
  CHECK(u.unwrap(65530) == 65530u);
  CHECK(u.unwrap(65535) == 65535u);
  CHECK(u.unwrap(4) == 65540u);
  CHECK(u.unwrap(100) == 65636u);
}

TEST_CASE("the watchdog fires only after the timeout", "[firmware][link]") {
  Watchdog w;
  CHECK(w.silent(0, 50));  // never heard
  w.heard(100);
  CHECK_FALSE(w.silent(150, 50));
  CHECK(w.silent(151, 50));
}

namespace {

struct Link {
  DataSender<std::int32_t> tx;
  DataReceiver<std::int32_t> rx;
  explicit Link(const Config<double>& c, Tick refresh = 100)
      : tx(c, {lever::protocol::kForceLsb, lever::protocol::kForceCodeMin, lever::protocol::kForceCodeMax}, refresh),
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
      REQUIRE(link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, out.mode, out.code));
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
    if (out.send) link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, out.mode, out.code);
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
    if (out.send && !lose) link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, out.mode, out.code);
    if (now > 50 && healed_at == 0 && std::fabs(*link.rx.value_at(now, 1000) - 3.0) < 1e-4) healed_at = now;
  }
  CHECK(healed_at == 150u);  // the refresh 100 ticks after the lost frame
  CHECK(link.rx.sequence().missing() == 1u);
}

TEST_CASE("duplicates and late frames are not fed to the model", "[firmware][link]") {
  Link link({Mode::predictive, 0.05, 0.0, 0.0});
  const auto a = link.tx.offer(0, 1.0);
  const auto b = link.tx.offer(1, 2.0);
  REQUIRE((a.send && b.send));
  CHECK(link.rx.accept(1, 1, b.seq, b.mode, b.code));
  CHECK_FALSE(link.rx.accept(2, 0, a.seq, a.mode, a.code));  // late
  CHECK_FALSE(link.rx.accept(2, 1, b.seq, b.mode, b.code));  // duplicate
  CHECK(link.rx.sequence().stale() == 2u);
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
      REQUIRE(link.rx.accept(now, static_cast<std::uint16_t>(now), out.seq, out.mode, out.code));
    }
    const auto shown = link.rx.value_at(now, 1000);
    REQUIRE(shown.has_value());
    const double believed = link.tx.codec_sender().model().at(static_cast<double>(now))[0];
    REQUIRE(std::memcmp(&believed, &*shown, sizeof(double)) == 0);
  }
  CHECK(mode_switches_seen == 2);
}
