// The settings frame: each lever says which codec settings it sends by, at boot, every kSettingsPeriodMs and in
// the step of every change, with the counters a host confirms set_deadband and tare by.
#include <catch2/catch.hpp>
#include <optional>
#include <vector>

#include "lever_rig.hpp"

using namespace lever;
using lever::test::PairRig;
using protocol::Opcode;
using protocol::Role;

namespace {

struct Sent {
  fw::Tick tick;
  protocol::CanFrame frame;
};

// Runs `ticks` ticks; every frame sent in them, with the tick it was sent in.
std::vector<Sent> run_logged(PairRig& rig, fw::Tick ticks) {
  std::vector<Sent> out;
  for (fw::Tick i = 0; i < ticks; ++i) {
    const auto before = rig.bus.log.size();
    const fw::Tick at = rig.now;
    rig.tick();
    for (auto k = before; k < rig.bus.log.size(); ++k) out.push_back({at, rig.bus.log[k]});
  }
  return out;
}

std::vector<std::pair<fw::Tick, protocol::SettingsMessage>> settings_of(const std::vector<Sent>& sent, Role role) {
  std::vector<std::pair<fw::Tick, protocol::SettingsMessage>> out;
  for (const auto& s : sent) {
    protocol::FrameAddress a;
    protocol::SettingsMessage m;
    if (protocol::decode(s.frame, m, a) == protocol::DecodeError::none && a.role == role) out.emplace_back(s.tick, m);
  }
  return out;
}

protocol::CommandMessage set_deadband(protocol::Direction direction, codec::Mode mode, std::uint16_t p,
                                      std::uint16_t floor, std::uint16_t filter_hz) {
  protocol::CommandMessage c;
  c.opcode = Opcode::set_deadband;
  c.to_hsi = direction == protocol::Direction::motion;
  c.to_top = direction == protocol::Direction::force;
  c.direction = direction;
  c.mode = mode;
  c.p = p;
  c.floor = floor;
  c.filter_hz = filter_hz;
  return c;
}

}  // namespace

TEST_CASE("each lever sends the settings of its direction at boot and every 500 ms, not more often",
          "[firmware][settings]") {
  PairRig rig;
  const auto sent = run_logged(rig, 1200);
  const auto hsi = settings_of(sent, Role::hsi);
  const auto top = settings_of(sent, Role::top);
  REQUIRE(hsi.size() == 3);
  REQUIRE(top.size() == 3);
  for (std::size_t i = 0; i < 3; ++i) {
    CHECK(hsi[i].first == 1 + i * protocol::kSettingsPeriodMs);
    CHECK(top[i].first == 1 + i * protocol::kSettingsPeriodMs);
  }
  // The rig's defaults (LeverConfig): motion deadband p 0.1, floor 0.02 rad/s; force p 0.1, floor 0.05 N; no filter.
  const auto& h = hsi.front().second;
  CHECK((h.mode == codec::Mode::deadband && h.p == 1000 && h.floor == 20 && h.filter_hz == 0));
  CHECK((h.changes == 0 && h.tares == 0 && !h.taring));
  const auto& t = top.front().second;
  CHECK((t.mode == codec::Mode::deadband && t.p == 1000 && t.floor == 50 && t.filter_hz == 0));
  CHECK(rig.hsi.counters().settings_sent == 3u);
}

TEST_CASE("set_deadband: the settings frame goes out in the step that takes it, each accepted copy counted",
          "[firmware][settings]") {
  for (const bool one_controller : {false, true}) {
    INFO("one controller: " << one_controller);
    PairRig rig;
    rig.one_controller = one_controller;
    rig.boot_and_arm();
    REQUIRE(rig.hsi.supervisor().armed());
    run_logged(rig, 10);
    const auto command = set_deadband(protocol::Direction::motion, codec::Mode::predictive, 500, 30, 300);
    rig.bus.inject(protocol::pack(command, 0));
    const auto sent = run_logged(rig, 3);
    const auto hsi = settings_of(sent, Role::hsi);
    REQUIRE(hsi.size() == 1);
    const auto& m = hsi.front().second;
    CHECK((m.mode == codec::Mode::predictive && m.p == 500 && m.floor == 30 && m.filter_hz == 300));
    CHECK(m.changes == 1);
    CHECK(hsi.front().first == sent.front().tick);  // the step the command arrived in
    CHECK(settings_of(sent, Role::top).empty());    // the TOP's settings did not change
    // The first motion frame coded under the new settings is a refresh with the new mode: in step() the one just
    // before the settings frame in the same step, with both levers in one controller the next step's, right after
    // it. Every motion frame after it carries the new mode, none before it does.
    std::size_t settings_at = sent.size(), first_new = sent.size();
    for (std::size_t i = 0; i < sent.size(); ++i) {
      protocol::FrameAddress a;
      protocol::MotionMessage motion;
      if (sent[i].frame.id == protocol::settings_id(0, Role::hsi)) settings_at = i;
      if (protocol::decode(sent[i].frame, motion, a) != protocol::DecodeError::none) continue;
      if (first_new == sent.size() && motion.flags.mode == codec::Mode::predictive) {
        first_new = i;
        CHECK(motion.flags.refresh);
      }
      CHECK((motion.flags.mode == codec::Mode::predictive) == (i >= first_new));
    }
    REQUIRE(settings_at < sent.size());
    REQUIRE(first_new < sent.size());
    if (one_controller) {
      CHECK(first_new > settings_at);
      CHECK(sent[first_new].tick == sent[settings_at].tick + 1);
    } else {
      CHECK(first_new < settings_at);
      CHECK(sent[first_new].tick == sent[settings_at].tick);
    }

    // The same values again: the same configuration, and the copy counted, so a host sees its command arrive.
    rig.bus.inject(protocol::pack(command, 0));
    const auto again = settings_of(run_logged(rig, 2), Role::hsi);
    REQUIRE(again.size() == 1);
    CHECK(again.front().second.changes == 2);
    CHECK(again.front().second.p == 500);

    // A set_deadband the HSI refuses (the force direction is the TOP's) changes nothing and sends nothing.
    auto refused = set_deadband(protocol::Direction::force, codec::Mode::deadband, 100, 0, 0);
    refused.to_hsi = true;
    refused.to_top = false;
    rig.bus.inject(protocol::pack(refused, 0));
    CHECK(settings_of(run_logged(rig, 2), Role::hsi).empty());
  }
}

TEST_CASE("set_deadband while disarmed: the settings frame shows it at once", "[firmware][settings]") {
  PairRig rig;
  run_logged(rig, 60);
  rig.bus.inject(protocol::pack(set_deadband(protocol::Direction::force, codec::Mode::deadband, 250, 70, 0), 0));
  const auto top = settings_of(run_logged(rig, 1), Role::top);
  REQUIRE(top.size() == 1);
  CHECK((top.front().second.p == 250 && top.front().second.floor == 70 && top.front().second.changes == 1));
}

TEST_CASE("tare: the settings frame shows it averaging at once and counts it when the average ends",
          "[firmware][settings]") {
  PairRig rig;
  run_logged(rig, 60);
  rig.command(Opcode::tare, false, true);
  const auto start = settings_of(run_logged(rig, 1), Role::top);
  REQUIRE(start.size() == 1);
  CHECK(start.front().second.taring);
  CHECK(start.front().second.tares == 0);
  // One fresh reading a tick: 64 of them; then the frame of the change, in the step the average ended.
  fw::Tick ended = 0;
  std::vector<std::pair<fw::Tick, protocol::SettingsMessage>> frames;
  for (int i = 0; i < 100 && rig.top.gauge().taring(); ++i) {
    auto part = settings_of(run_logged(rig, 1), Role::top);
    frames.insert(frames.end(), part.begin(), part.end());
    ended = rig.now - 1;
  }
  REQUIRE_FALSE(rig.top.gauge().taring());
  REQUIRE_FALSE(frames.empty());
  CHECK(frames.back().first == ended);
  CHECK_FALSE(frames.back().second.taring);
  CHECK(frames.back().second.tares == 1);
  CHECK(frames.back().second.changes == 0);
  // The HSI has no gauge in the rig: it says 0.
  const auto hsi = settings_of(run_logged(rig, protocol::kSettingsPeriodMs), Role::hsi);
  REQUIRE_FALSE(hsi.empty());
  CHECK(hsi.back().second.tares == 0);
}

TEST_CASE("the settings frame's counters wrap at 64 on the wire", "[firmware][settings]") {
  PairRig rig;
  run_logged(rig, 10);
  const auto command = set_deadband(protocol::Direction::force, codec::Mode::deadband, 1000, 50, 0);
  std::optional<protocol::SettingsMessage> last;
  for (int i = 0; i < 65; ++i) {
    rig.bus.inject(protocol::pack(command, 0));
    const auto top = settings_of(run_logged(rig, 1), Role::top);
    REQUIRE(top.size() == 1);
    last = top.front().second;
  }
  CHECK(last->changes == 1);  // 65 modulo 64
}

// The levers hold a raw frame to what the programs' options refuse (codec::runs_at at 1 kHz): a Weber fraction below
// 1 and a prefilter cut-off below 500 Hz. A frame can carry p up to 6.5535 and 6553.5 Hz; past the bound it is
// counted as rejected and changes nothing, within it it is taken.
TEST_CASE("set_deadband past a Weber fraction of 1 or a cut-off of 500 Hz is refused, within them taken",
          "[firmware][settings]") {
  struct Case {
    std::uint16_t p, filter_hz;
    bool taken;
  };
  for (const Case c : {Case{10000, 0, false}, Case{65535, 0, false}, Case{9999, 0, true}, Case{1000, 5000, false},
                       Case{1000, 65535, false}, Case{1000, 4999, true}}) {
    INFO("p " << c.p << " x 1e-4, cut-off " << c.filter_hz << " x 0.1 Hz");
    PairRig rig;
    run_logged(rig, 10);
    const auto rejected = rig.top.counters().commands_rejected;
    rig.bus.inject(
        protocol::pack(set_deadband(protocol::Direction::force, codec::Mode::deadband, c.p, 50, c.filter_hz), 0));
    const auto top = settings_of(run_logged(rig, 1), Role::top);
    CHECK(top.size() == (c.taken ? 1u : 0u));
    CHECK(rig.top.counters().commands_rejected == rejected + (c.taken ? 0u : 1u));
    if (c.taken && !top.empty()) CHECK((top.front().second.p == c.p && top.front().second.filter_hz == c.filter_hz));
  }
}
