// lever-view's monitor: frames packed by the protocol's own packers, fed with time stamps, read back as the
// screen shows them.
#include <catch2/catch.hpp>

#include "lever/protocol/messages.hpp"
#include "pair_monitor.hpp"
#include "rate_window.hpp"
#include "sequence_counter.hpp"

using namespace lever;
using protocol::Role;

namespace {

constexpr std::int64_t kT0 = 1'700'000'000'000'000;  // a realistic epoch time stamp, microseconds

protocol::CanFrame motion(std::uint8_t seq, std::int16_t position, std::int16_t velocity, bool restart = false) {
  protocol::MotionMessage m;
  m.seq = seq;
  m.position = position;
  m.velocity = velocity;
  m.flags.restart = restart;
  return protocol::pack(m, 0);
}

protocol::CanFrame force(std::uint8_t seq, std::int32_t code) {
  protocol::ForceMessage m;
  m.seq = seq;
  m.force = code;
  return protocol::pack(m, 0);
}

protocol::CanFrame heartbeat(Role role, protocol::LeverState state, std::uint8_t counter,
                             protocol::FaultBits faults = 0, bool homed = true) {
  protocol::HeartbeatMessage h;
  h.state = state;
  h.counter = counter;
  h.faults = faults;
  h.position_valid = homed;
  return protocol::pack(h, 0, role);
}

}  // namespace

TEST_CASE("a rate window counts the last whole second of events", "[view]") {
  view::RateWindow w;
  for (int i = 0; i < 2000; ++i) w.add(kT0 + i * 1000);  // 1 kHz for 2 s
  CHECK(w.last_second(kT0 + 2'000'000) == 1000);
  CHECK(w.last_second(kT0 + 2'050'000) == 1000);
  CHECK(w.last_second(kT0 + 2'550'000) == 500);  // half the window has gone silent
  CHECK(w.last_second(kT0 + 3'100'000) == 0);
  w.reset();
  CHECK(w.last_second(kT0 + 2'000'000) == 0);
}

TEST_CASE("a rate window read while events still come counts ten whole buckets, not nine", "[view]") {
  view::RateWindow w;
  // Read as a screen reads it: in the middle of a steady 1 kHz stream, the newest bucket still filling.
  for (int i = 0; i < 3000; ++i) {
    w.add(kT0 + i * 1000);
    if (i >= 1100 && i % 50 == 0) CHECK(w.last_second(kT0 + i * 1000) == 1000);
  }
}

TEST_CASE("a sequence counter tells frames lost from frames out of order, across the wrap", "[view]") {
  view::SequenceCounter c;
  for (const int s : {250, 251, 252, 255, 0, 1})
    c.on(static_cast<std::uint8_t>(s));  // 253 and 254 missing; 255 -> 0 wraps
  CHECK(c.lost() == 2);
  CHECK(c.out_of_order() == 0);
  c.on(1);    // a duplicate
  c.on(254);  // a late one
  CHECK(c.out_of_order() == 2);
  CHECK(c.lost() == 2);
  c.restart();
  c.on(0);  // a new stream starts anywhere
  CHECK(c.lost() == 2);
  c.on(3);
  CHECK(c.lost() == 4);
}

TEST_CASE("a 1 kHz stream reads 1000 frames/s, a share of 1 and no savings, half of it 0.5", "[view]") {
  view::PairMonitor m;
  for (int i = 0; i < 2000; ++i) {
    const std::int64_t t = kT0 + i * 1000;
    m.on_frame(motion(static_cast<std::uint8_t>(i), 100, -5), t);
    if (i % 2 == 0) m.on_frame(force(static_cast<std::uint8_t>(i / 2), 123456), t + 10);
  }
  const auto s = m.snapshot(kT0 + 2'000'000);
  REQUIRE(s.pairs.size() == 1);
  const auto& p = s.pairs[0];
  CHECK(p.motion.per_second == 1000.0);
  CHECK(p.motion.share() == 1.0);
  CHECK(p.motion.savings() == 0.0);
  CHECK(p.force.per_second == 500.0);
  CHECK(p.force.savings() == 0.5);
  CHECK(p.motion.frames == 2000);
  CHECK(p.motion.lost == 0);
  CHECK(p.force.lost == 0);
  // The values as the protocol scales them.
  CHECK(*p.hsi_position_rad() == Approx(100 * 2 * 3.141592653589793 / 16384));
  CHECK(*p.hsi_velocity_rad_s() == Approx(-0.005));
  CHECK(*p.top_force_n() == Approx(1.23456));
  // A classic 8-byte frame is 47 + 64 bits, and up to (34 + 64 - 1) / 4 = 24 stuff bits: 135 on the wire; 1500
  // of them a second on 1 Mbit/s.
  CHECK(s.bus.frames_per_s == 1500.0);
  CHECK(s.bus.bits_per_s == 1500.0 * 135);
  CHECK(s.bus.load == Approx(0.2025));
}

TEST_CASE("frames missing from a data stream are lost, a restart is not a loss", "[view]") {
  view::PairMonitor m;
  std::int64_t t = kT0;
  for (const int seq : {0, 1, 2, 6, 7, 5})
    m.on_frame(motion(static_cast<std::uint8_t>(seq), 0, 0), t += 1000);  // 3-5 gone, 5 late
  m.on_frame(motion(0, 0, 0, true), t += 1000);                           // the HSI re-armed: a new stream from 0
  m.on_frame(motion(1, 0, 0), t += 1000);
  const auto s = m.snapshot(t);
  CHECK(s.pairs[0].motion.lost == 3);
  CHECK(s.pairs[0].motion.out_of_order == 1);
  CHECK(s.pairs[0].motion.restarts == 1);
}

TEST_CASE("heartbeats give each lever's state, homing and latched faults, and their own losses", "[view]") {
  view::PairMonitor m;
  const protocol::FaultBits faults =
      protocol::bit(protocol::Fault::force_stale) | protocol::bit(protocol::Fault::peer_state);
  m.on_frame(heartbeat(Role::hsi, protocol::LeverState::armed, 10), kT0);
  m.on_frame(heartbeat(Role::top, protocol::LeverState::fault, 20, faults, false), kT0 + 1);
  m.on_frame(heartbeat(Role::hsi, protocol::LeverState::armed, 13), kT0 + 25'000);  // 11 and 12 lost
  auto s = m.snapshot(kT0 + 30'000);
  const auto& hsi = s.pairs[0].levers[0];
  const auto& top = s.pairs[0].levers[1];
  CHECK(hsi.heartbeat.state == protocol::LeverState::armed);
  CHECK(hsi.heartbeat.position_valid);
  CHECK(hsi.heartbeats_lost == 2);
  CHECK(top.heartbeat.state == protocol::LeverState::fault);
  CHECK_FALSE(top.heartbeat.position_valid);
  CHECK(top.heartbeat.faults == faults);
  CHECK_FALSE(hsi.silent());
  // Four heartbeat periods without one: silent.
  s = m.snapshot(kT0 + 25'000 + 100'001);
  CHECK(s.pairs[0].levers[0].silent());
}

TEST_CASE("a frame that fails to decode is counted, and other ids are not the protocol's", "[view]") {
  view::PairMonitor m;
  auto bad = motion(0, 0, 0);
  bad.dlc = 6;
  m.on_frame(bad, kT0);
  auto reserved = force(0, 0);
  reserved.data[7] = 1;
  m.on_frame(reserved, kT0);
  m.on_frame(protocol::CanFrame{0x555, 8, {}}, kT0);
  const auto s = m.snapshot(kT0);
  CHECK(s.bus.rejected == 2);
  CHECK(s.bus.unknown_ids == 1);
  CHECK(s.bus.frames == 3);
  CHECK(s.pairs.empty());  // nothing of a pair decoded
}

TEST_CASE("one pair shown (--pair), while the bus load counts every frame", "[view]") {
  view::PairMonitor m({1e6, std::uint8_t{3}});
  m.on_frame(motion(0, 0, 0), kT0);  // pair 0
  protocol::MotionMessage mm;
  m.on_frame(protocol::pack(mm, 3), kT0);
  const auto s = m.snapshot(kT0);
  REQUIRE(s.pairs.size() == 1);
  CHECK(s.pairs[0].pair == 3);
  CHECK(s.bus.frames == 2);
}

TEST_CASE("the history takes the newest value every 0.1 s, and none once the stream is stale", "[view]") {
  view::PairMonitor m;
  for (int i = 0; i < 1000; ++i)
    m.on_frame(motion(static_cast<std::uint8_t>(i), static_cast<std::int16_t>(i), 0), kT0 + i * 1000);
  auto s = m.snapshot(kT0 + 999'000);
  const auto& h = s.pairs[0].hsi_position_history;
  REQUIRE(h.size() == 9);  // 0.1, 0.2, ... 0.9 s
  // The sample at 0.1 s is the frame of 0.1 s (position 100 counts): taken before a frame at the boundary.
  CHECK(*h[0] == Approx(99 * protocol::kPositionLsbRad));
  CHECK(*h[8] == Approx(899 * protocol::kPositionLsbRad));
  s = m.snapshot(kT0 + 1'500'000);
  const auto& later = s.pairs[0].hsi_position_history;
  CHECK(later.back() == std::nullopt);  // 0.5 s after the last frame
  CHECK(later.size() == 15);
}

TEST_CASE("reset zeroes the counters and keeps what the levers said last", "[view]") {
  view::PairMonitor m;
  m.on_frame(heartbeat(Role::hsi, protocol::LeverState::armed, 1), kT0);
  m.on_frame(heartbeat(Role::hsi, protocol::LeverState::armed, 5), kT0 + 1);
  m.on_frame(motion(0, 42, 0), kT0 + 2);
  m.on_frame(motion(3, 42, 0), kT0 + 3);
  m.reset();
  const auto s = m.snapshot(kT0 + 4);
  const auto& p = s.pairs[0];
  CHECK(p.levers[0].heartbeats == 0);
  CHECK(p.levers[0].heartbeats_lost == 0);
  CHECK(p.motion.frames == 0);
  CHECK(p.motion.lost == 0);
  CHECK(s.bus.frames == 0);
  CHECK(p.levers[0].heartbeat.state == protocol::LeverState::armed);
  CHECK(p.motion_message->position == 42);
  // And counting goes on from there: the next frame is not a loss against the one before the reset.
  m.on_frame(motion(4, 42, 0), kT0 + 5);
  CHECK(m.snapshot(kT0 + 6).pairs[0].motion.lost == 0);
}

TEST_CASE("each lever's newest settings frame is kept with a count of them, bad ones rejected", "[view]") {
  view::PairMonitor m;
  protocol::SettingsMessage st;
  st.p = 1000;
  m.on_frame(protocol::pack(st, 0, Role::top), kT0);
  st.p = 250;
  st.changes = 1;
  m.on_frame(protocol::pack(st, 0, Role::top), kT0 + 1);
  auto bad = protocol::pack(st, 0, Role::hsi);
  bad.data[0] = 3;  // mode 3: none such
  m.on_frame(bad, kT0 + 2);
  auto s = m.snapshot(kT0 + 3);
  const auto& top = s.pairs[0].levers[1];
  REQUIRE(top.settings);
  CHECK(top.settings->p == 250);
  CHECK(top.settings->changes == 1);
  CHECK(top.settings_frames == 2);
  CHECK_FALSE(s.pairs[0].levers[0].settings);
  CHECK(s.bus.rejected == 1);
  m.reset();
  s = m.snapshot(kT0 + 4);
  CHECK(s.pairs[0].levers[1].settings_frames == 0);
  CHECK(s.pairs[0].levers[1].settings->p == 250);  // what the lever said last stays
}
