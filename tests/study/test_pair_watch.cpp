// The rules by which the study runner holds an interval back or voids it, and confirms a lever's settings.
#include <catch2/catch.hpp>

#include "lever/study/pair_watch.hpp"

namespace {

namespace protocol = lever::protocol;
using lever::study::PairWatch;
using protocol::Role;

constexpr std::uint8_t kPair = 3;

protocol::HeartbeatMessage armed() {
  protocol::HeartbeatMessage h;
  h.state = protocol::LeverState::armed;
  h.position_valid = true;
  return h;
}

void hear_both(PairWatch& w, std::int64_t t_us, protocol::HeartbeatMessage h = armed()) {
  w.on_frame(protocol::pack(h, kPair, Role::hsi), t_us);
  w.on_frame(protocol::pack(h, kPair, Role::top), t_us);
}

protocol::SettingsMessage settings(double p, std::uint8_t changes) {
  protocol::SettingsMessage s;
  s.p = protocol::unsigned_code(p, protocol::kPLsb);
  s.floor = 10;
  s.changes = changes;
  return s;
}

}  // namespace

TEST_CASE("study runner: a pair both armed, homed and free of faults, and heard lately, is ready") {
  PairWatch w(kPair);
  CHECK(w.not_ready(0) == "HSI: no heartbeat heard; TOP: no heartbeat heard");
  hear_both(w, 1'000'000);
  CHECK(w.not_ready(1'000'000).empty());
  CHECK(w.not_ready(1'000'000 + lever::study::kHeartbeatFreshUs).empty());
}

TEST_CASE("study runner: a lever unheard for ten heartbeats is not ready") {
  PairWatch w(kPair);
  hear_both(w, 1'000'000);
  CHECK(w.not_ready(1'000'000 + lever::study::kHeartbeatFreshUs + 1) ==
        "HSI: no heartbeat for 0.3 s; TOP: no heartbeat for 0.3 s");
}

TEST_CASE("study runner: disarmed, unhomed or faulted is not ready, and says which and why") {
  PairWatch w(kPair);
  hear_both(w, 0);
  auto h = armed();
  h.state = protocol::LeverState::disarmed;
  w.on_frame(protocol::pack(h, kPair, Role::top), 10);
  CHECK(w.not_ready(10) == "TOP: disarmed");
  h = armed();
  h.position_valid = false;
  w.on_frame(protocol::pack(h, kPair, Role::hsi), 20);
  CHECK(w.not_ready(20) == "HSI: not homed; TOP: disarmed");
  h = armed();
  h.faults = protocol::bit(protocol::Fault::comms_timeout);
  w.on_frame(protocol::pack(h, kPair, Role::hsi), 30);
  w.on_frame(protocol::pack(armed(), kPair, Role::top), 30);
  CHECK(w.not_ready(30) == "HSI: faults comms_timeout");
}

TEST_CASE("study runner: frames of another pair change nothing; data frames are counted per direction") {
  PairWatch w(kPair);
  hear_both(w, 0);
  auto h = armed();
  h.state = protocol::LeverState::fault;
  w.on_frame(protocol::pack(h, kPair + 1, Role::hsi), 5);
  CHECK(w.not_ready(5).empty());
  protocol::MotionMessage motion;
  protocol::ForceMessage force;
  for (int i = 0; i < 3; ++i) w.on_frame(protocol::pack(motion, kPair), 10 + i);
  w.on_frame(protocol::pack(force, kPair), 20);
  w.on_frame(protocol::pack(force, kPair + 1), 21);
  CHECK(w.data_frames(protocol::Direction::motion) == 3);
  CHECK(w.data_frames(protocol::Direction::force) == 1);
  CHECK(w.newest_us() == 20);
}

TEST_CASE("study runner: an interval's p goes to the lever that sends the path, the rest of its settings kept") {
  const auto baseline = settings(0.0, 7);
  const lever::study::Interval interval{0.05, 0.10, 20.0};
  const auto motion = lever::study::settings_for(interval, protocol::Direction::motion, baseline);
  const auto force = lever::study::settings_for(interval, protocol::Direction::force, baseline);
  CHECK(motion.p == 500);
  CHECK(force.p == 1000);
  CHECK(motion.floor == baseline.floor);
  const auto command = lever::study::command_for(protocol::Direction::force, force);
  CHECK(command.opcode == protocol::Opcode::set_deadband);
  CHECK_FALSE(command.to_hsi);
  CHECK(command.to_top);
  CHECK(command.p == 1000);
  CHECK(command.floor == baseline.floor);
  CHECK(lever::study::sender_of(protocol::Direction::motion) == Role::hsi);
}

TEST_CASE("study runner: a setting is confirmed by a settings frame whose counter moved on and whose values match") {
  const auto wanted = settings(0.05, 0);
  CHECK(lever::study::confirms(settings(0.05, 8), 7, wanted));
  // The lever's settings already matched, and it has not answered the command: not confirmed yet.
  CHECK_FALSE(lever::study::confirms(settings(0.05, 7), 7, wanted));
  // It answered another command.
  CHECK_FALSE(lever::study::confirms(settings(0.10, 8), 7, wanted));
  // The counter wraps at 64.
  CHECK(lever::study::confirms(settings(0.05, 0), 63, wanted));
}
