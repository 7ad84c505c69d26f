// The whole testbed in the HIL: determinism, and every injected fault taken to its safe behaviour.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>

#include "lever/hil/simulation.hpp"
#include "lever/protocol/faults.hpp"

using namespace lever;
using namespace lever::hil;

namespace {

SimConfig base(double duration = 8.0) {
  SimConfig c;
  c.scenario = ScenarioKind::wall_tap;
  c.duration_s = duration;
  c.velocity_codec = {codec::Mode::deadband, 0.1, 0.02, 0.0};
  c.force_codec = {codec::Mode::deadband, 0.1, 0.05, 0.0};
  return c;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// The torque each lever asks for while in its fault state, before the torque limit clamps it: its safe behaviour's
// (the TOP holds with at most safe_hold_torque_nm, the HSI displays nothing). What reaches the motor is clamped to
// the torque limit whatever the firmware asks, so a bound on that could not fail.
struct FaultTorque {
  double hsi = 0.0, top = 0.0;
  void observe(const SimView& v) {
    if (v.hsi.supervisor().state() == protocol::LeverState::fault)
      hsi = std::max(hsi, std::fabs(v.hsi.telemetry().torque_demand_nm));
    if (v.top.supervisor().state() == protocol::LeverState::fault)
      top = std::max(top, std::fabs(v.top.telemetry().torque_demand_nm));
  }
  void check(const SimConfig& c) const {
    CHECK(hsi == 0.0);
    CHECK(top <= c.top_firmware.safe_hold_torque_nm);
  }
};

}  // namespace

TEST_CASE("the same seed gives the same run, bit for bit; another seed another", "[hil][determinism]") {
  SimConfig c = base(3.0);
  c.network = {8.0, 2.0, 0.02, true};
  c.faults.push_back(parse_fault_spec("link-down@1.5+0.2"));
  c.record_trace = true;
  const auto a = run_simulation(c);
  const auto b = run_simulation(c);
  REQUIRE(a.trace.size() == b.trace.size());
  bool identical = true;
  for (std::size_t i = 0; i < a.trace.size(); ++i) {
    identical = identical && std::memcmp(&a.trace[i], &b.trace[i], sizeof(TraceRow)) == 0;
  }
  CHECK(identical);
  CHECK(same_bits(a.velocity_packet_rate, b.velocity_packet_rate));
  CHECK(same_bits(a.force_jnd_violation, b.force_jnd_violation));
  CHECK(a.network_lost == b.network_lost);
  c.seed = 2;
  CHECK_FALSE(same_bits(run_simulation(c).position_rmse_rad, a.position_rmse_rad));
}

TEST_CASE("without faults both levers stay armed and the TOP follows", "[hil]") {
  const auto r = run_simulation(base(10.0));
  CHECK(r.armed_ticks > 9800u);
  CHECK(r.position_rmse_rad < 0.02);
  CHECK(r.contact_share > 0.2);  // the wall-tap operator spends a good part of the time on the wall
  CHECK(r.contact_share < 0.8);
  CHECK(r.mean_contact_force_n > 1.0);
  CHECK(r.bus_load_hsi < 0.2);
}

namespace {

enum class Where : std::uint8_t { hsi, top, both };

struct Expectation {
  const char* spec;
  Where faulting;          // the lever(s) whose own fault it is
  protocol::Fault bit;     // latched there
  double detect_within_s;  // from injection to the fault state
  bool rehome;             // the position is lost: the lever must home again before the re-arm
};

}  // namespace

TEST_CASE("every fault kind brings the levers to their safe behaviour, in time, and re-arm recovers", "[hil][faults]") {
  // comms: the 100 ms timeout plus up to a few ms of transport; stale gauge: 5 ticks; the rest: next tick.
  // The other lever of the pair sees the faulting one leave the armed state in its next heartbeat (25 ms)
  // and latches PEER_STATE: the pair runs together or not at all.
  const Expectation cases[] = {
      {"link-down@3+0.5", Where::both, protocol::Fault::comms_timeout, 0.106, false},
      {"bus-off@3+0.3:top", Where::both, protocol::Fault::comms_timeout, 0.106, false},
      {"encoder-glitch@3+0.01:hsi", Where::hsi, protocol::Fault::encoder, 0.006, true},
      {"gauge-stale@3+0.5", Where::top, protocol::Fault::force_stale, 0.008, false},
      {"gauge-saturated@3+0.5", Where::top, protocol::Fault::force_saturated, 0.003, false},
      {"motor-fault@3+0.5:top", Where::top, protocol::Fault::motor_driver, 0.002, false},
      {"motor-fault@3+0.5:hsi", Where::hsi, protocol::Fault::motor_driver, 0.002, false},
      // 20 ms without a step while the lever moves: the edge queue (2 x 16 events) overflows too, so the TOP
      // latches ENCODER beside TIMING and must home again.
      {"tick-late@3+0.02:top", Where::top, protocol::Fault::timing, 0.021, true},
  };
  for (const auto& e : cases) {
    SECTION(e.spec) {
      SimConfig c = base();
      c.faults.push_back(parse_fault_spec(e.spec));
      FaultTorque torque;
      c.observer = [&](const SimView& v) { torque.observe(v); };
      const auto r = run_simulation(c);
      REQUIRE(r.faults.size() == 1);
      const auto& f = r.faults[0];
      const double injected = f.spec.start_s;
      torque.check(c);
      // The host looks every 100 ms and arms the pair together, so a re-arm can take a few of its periods;
      // homing first drives to the stop at 0.5 rad/s (up to 1.3 rad) and waits for the stall.
      const double recovery_s = e.rehome ? 5.0 : 0.35;
      for (const auto* side : {&f.hsi, &f.top}) {
        const bool own = e.faulting == Where::both || (side == &f.hsi) == (e.faulting == Where::hsi);
        INFO((side == &f.hsi ? "HSI" : "TOP") << (own ? ", its own fault" : ", its peer's fault"));
        REQUIRE(side->fault_at_s.has_value());
        CHECK(*side->fault_at_s - injected <= e.detect_within_s + (own ? 0.0 : 0.03));
        CHECK((side->latched & protocol::bit(own ? e.bit : protocol::Fault::peer_state)) != 0);
        REQUIRE(side->safe_at_s.has_value());
        CHECK(*side->safe_at_s == *side->fault_at_s);  // safe in the very tick the fault is found
        REQUIRE(side->rearmed_at_s.has_value());
        CHECK(*side->rearmed_at_s > injected + f.spec.duration_s);
        CHECK(*side->rearmed_at_s < injected + f.spec.duration_s + c.rearm_after_s + recovery_s);
        CHECK_FALSE(side->armed_without_rearm);
      }
    }
  }
}

// Half the datagrams lost for 3 s. With the default 100 ms timeout, 100 ms without a frame from the peer trips
// COMMS, which happens or not by the draw, early or late in the burst: how much data is lost while the levers
// still stream, and so how many gaps they count, is the draw's (it differs between libms; docs/firmware.md). So the
// counting is judged where the levers ride the burst out (the timeout raised past it), and the safety where they
// may not.
TEST_CASE("burst loss is healed by the refresh and counted, not a crash of the loop", "[hil][faults]") {
  SECTION("the levers ride it out, and count the frames they lose") {
    SimConfig c = base();
    c.faults.push_back(parse_fault_spec("burst-loss@2+3"));
    for (auto* fw : {&c.hsi_firmware, &c.top_firmware}) fw->comms_timeout = 300;
    const auto r = run_simulation(c);
    CAPTURE(r.network_lost, r.hsi_seq_gaps, r.top_seq_gaps, r.armed_ticks);
    CHECK(r.network_lost > 50u);
    CHECK(r.hsi_lever_faults.count + r.top_lever_faults.count == 0u);
    CHECK(r.hsi_seq_gaps > 10u);
    CHECK(r.top_seq_gaps > 10u);
  }
  SECTION("with the default timeout: safe at any fault, and armed again after the burst") {
    SimConfig c = base();
    c.faults.push_back(parse_fault_spec("burst-loss@2+3"));
    FaultTorque torque;
    c.observer = [&](const SimView& v) { torque.observe(v); };
    const auto r = run_simulation(c);
    CHECK(r.network_lost > 50u);
    torque.check(c);
    const auto& f = r.faults[0];
    for (const auto* side : {&f.hsi, &f.top}) {
      if (side->fault_at_s) CHECK(side->safe_at_s == side->fault_at_s);
    }
    CHECK(r.armed_ticks > 4500u);  // armed before the burst and again after it (faults in between are allowed)
  }
}

TEST_CASE("a 20 ms delay step is survived with the default timeout; a 150 ms one is a comms fault, handled safely",
          "[hil][faults]") {
  // The 100 ms timeout spans four 25 ms heartbeats: a delay step shorter than about 75 ms cannot trip it.
  SimConfig c = base();
  c.faults.push_back(parse_fault_spec("delay-step@3:20"));
  const auto small = run_simulation(c);
  CHECK_FALSE(small.faults[0].top.fault_at_s.has_value());
  CHECK_FALSE(small.faults[0].hsi.fault_at_s.has_value());

  c.faults = {parse_fault_spec("delay-step@3+1:150")};
  FaultTorque torque;
  c.observer = [&](const SimView& v) { torque.observe(v); };
  const auto large = run_simulation(c);
  const auto& f = large.faults[0];
  REQUIRE(f.top.fault_at_s.has_value());
  CHECK((f.top.latched & protocol::bit(protocol::Fault::comms_timeout)) != 0);
  CHECK(f.top.safe_at_s == f.top.fault_at_s);
  torque.check(c);
}

TEST_CASE("fault specs are parsed or rejected with a reason", "[hil][faults]") {
  const auto f = parse_fault_spec("bus-off@2.5+0.25:hsi");
  CHECK(f.kind == FaultKind::bus_off);
  CHECK(f.start_s == 2.5);
  CHECK(f.duration_s == 0.25);
  CHECK(f.site == Site::hsi);
  CHECK(std::isinf(parse_fault_spec("delay-step@1:30").duration_s));
  CHECK_THROWS_WITH(parse_fault_spec("meteor@1"), Catch::Contains("unknown kind 'meteor'"));
  CHECK_THROWS_WITH(parse_fault_spec("link-down"), Catch::Contains("KIND@START"));
  CHECK_THROWS_WITH(parse_fault_spec("link-down@x"), Catch::Contains("start 'x'"));
  CHECK_THROWS_WITH(parse_fault_spec("bus-off@1:left"), Catch::Contains("not hsi or top"));
  CHECK_THROWS_WITH(parse_fault_spec("delay-step@1"), Catch::Contains("needs :MILLISECONDS"));
}

TEST_CASE("late ticks: counted as overruns, TIMING exactly past the 2 ms bound, no velocity blow-up",
          "[hil][faults][timing]") {
  struct Case {
    const char* spec;
    bool timing_fault;
  };
  // The firmware is not stepped for D; its next step comes D + 1 ms after the last.
  for (const Case k : {Case{"tick-late@3+0.001:top", false}, Case{"tick-late@3+0.002:top", true},
                       Case{"tick-late@3+0.001:hsi", false}, Case{"tick-late@3+0.002:hsi", true}}) {
    SECTION(k.spec) {
      SimConfig c = base(5.0);
      c.faults.push_back(parse_fault_spec(k.spec));
      double worst_velocity = 0.0;
      c.observer = [&](const SimView& v) {
        for (const auto* t : {&v.hsi.telemetry(), &v.top.telemetry()}) {
          worst_velocity = std::max(worst_velocity, std::fabs(t->velocity_rad_s));
        }
      };
      const auto r = run_simulation(c);
      const auto& f = r.faults[0];
      const bool at_hsi = f.spec.site == Site::hsi;
      const auto& side = at_hsi ? f.hsi : f.top;
      CHECK((at_hsi ? r.hsi_overruns : r.top_overruns) == 1u);
      CHECK((at_hsi ? r.top_overruns : r.hsi_overruns) == 0u);
      if (k.timing_fault) {
        REQUIRE(side.fault_at_s.has_value());
        CHECK((side.latched & protocol::bit(protocol::Fault::timing)) != 0);
        CHECK(*side.fault_at_s == Approx(f.spec.start_s + f.spec.duration_s).margin(1.5e-3));
      } else {
        CHECK_FALSE(side.fault_at_s.has_value());
      }
      CHECK(worst_velocity < 10.0);  // a hand on a desk-top lever (docs/firmware.md, "Timing bounds")
    }
  }
}

TEST_CASE("edges lost in the encoder's event queue are detected, never a silently wrong count",
          "[hil][faults][encoder]") {
  // A 50 ms stall of the TOP's loop while the pair moves: at a few rad/s that is hundreds of edges, more
  // than the 2 x 16 events the queue keeps.
  // Several stalls, so that at least one falls on a fast movement of the TOP.
  SimConfig c = base(8.0);
  for (const char* spec : {"tick-late@2+0.05:top", "tick-late@2.3+0.05:top", "tick-late@2.6+0.05:top",
                           "tick-late@2.9+0.05:top", "tick-late@3.2+0.05:top", "tick-late@3.5+0.05:top"})
    c.faults.push_back(parse_fault_spec(spec));
  bool encoder_fault_seen = false;
  c.observer = [&](const SimView& v) {
    encoder_fault_seen = encoder_fault_seen || protocol::has(v.top.supervisor().latched(), protocol::Fault::encoder);
  };
  const auto r = run_simulation(c);
  REQUIRE(r.top_edges_lost > 0u);
  CHECK(encoder_fault_seen);
  CHECK(r.hsi_edges_lost == 0u);
  // Without the fault, nothing is lost at all in the same run.
  c.faults.clear();
  const auto clean = run_simulation(c);
  CHECK(clean.top_edges_lost == 0u);
  CHECK(clean.hsi_edges_lost == 0u);
}

namespace {

// Sender and receiver models agree bit for bit: the same samples held, the same newest value, the same
// extrapolation (compared in each end's own time base, which differ by a whole number of ticks).
template <typename SenderModel, typename ReceiverModel>
bool coherent(const SenderModel& s, const ReceiverModel& r) {
  if (s.samples_held() != r.samples_held() || s.mode() != r.mode()) return false;
  if (s.empty()) return true;
  const double sv = s.newest().v[0], rv = r.newest().v[0];
  const double sp = s.at(s.newest().t + 7.0)[0], rp = r.at(r.newest().t + 7.0)[0];
  return std::memcmp(&sv, &rv, sizeof sv) == 0 && std::memcmp(&sp, &rp, sizeof sp) == 0;
}

bool finite(const fw::LeverTelemetry& t) {
  return std::isfinite(t.position_ref_rad) && std::isfinite(t.velocity_ref_rad_s) && std::isfinite(t.torque_nm) &&
         std::isfinite(t.torque_demand_nm) && std::isfinite(t.velocity_rad_s) &&
         (!t.remote || std::isfinite(*t.remote));
}

}  // namespace

TEST_CASE(
    "a lever that reboots is homed and re-armed; its peer goes safe, comes back only by re-arm, and the "
    "streams are coherent again from the first frame",
    "[hil][faults][reboot]") {
  struct Case {
    const char* spec;
    codec::Mode mode;
    double duration;
  };
  // Before and after the peer's 16-bit tick wraps (65.5 s after its power-up), mid-stream, instant and
  // with a boot time, in deadband and predictive mode, each lever. The late reboots run 7 s past it: homing and
  // re-arming take about 3, and coherence is checked only on ticks with nothing in flight.
  const Case cases[] = {
      {"reboot@3:hsi", codec::Mode::deadband, 11.0},       {"reboot@3:top", codec::Mode::predictive, 11.0},
      {"reboot@3+0.2:hsi", codec::Mode::predictive, 11.0}, {"reboot@3.5+0.05:top", codec::Mode::deadband, 11.0},
      {"reboot@68:top", codec::Mode::predictive, 75.0},    {"reboot@68:hsi", codec::Mode::deadband, 75.0},
  };
  for (const auto& k : cases) {
    SECTION(std::string(k.spec) + (k.mode == codec::Mode::predictive ? " predictive" : " deadband")) {
      SimConfig c = base(k.duration);
      c.velocity_codec.mode = k.mode;
      c.force_codec.mode = k.mode;
      c.faults.push_back(parse_fault_spec(k.spec));
      const double reboot_at = c.faults[0].start_s;
      std::uint64_t checked_motion = 0, checked_force = 0, incoherent = 0, non_finite = 0;
      FaultTorque torque;
      c.observer = [&](const SimView& v) {
        torque.observe(v);
        non_finite += !finite(v.hsi.telemetry()) + !finite(v.top.telemetry());
        if (v.t < reboot_at || !v.hsi.supervisor().armed() || !v.top.supervisor().armed()) return;
        const auto& ms = v.hsi.role().sender();
        const auto& mr = v.top.role().receiver();
        if (mr.has_value() && mr.sequence().last() == ms.last_seq()) {  // nothing in flight
          ++checked_motion;
          incoherent += !coherent(ms.codec_sender().model(), mr.codec_receiver().model());
        }
        const auto& fs = v.top.role().sender();
        const auto& fr = v.hsi.role().receiver();
        if (fr.has_value() && fr.sequence().last() == fs.last_seq()) {
          ++checked_force;
          incoherent += !coherent(fs.codec_sender().model(), fr.codec_receiver().model());
        }
      };
      const auto r = run_simulation(c);
      const auto& f = r.faults[0];
      const bool hsi_rebooted = f.spec.site == Site::hsi;
      const auto& other = hsi_rebooted ? f.top : f.hsi;
      const auto& rebooted = hsi_rebooted ? f.hsi : f.top;
      CHECK(non_finite == 0u);
      CHECK(incoherent == 0u);
      CHECK(checked_motion > 500u);
      CHECK(checked_force > 500u);
      // The peer: safe within the comms timeout (or at once, seeing the rebooted lever's heartbeat).
      REQUIRE(other.fault_at_s.has_value());
      CHECK(*other.fault_at_s - reboot_at <= 0.106);
      CHECK((other.latched &
             (protocol::bit(protocol::Fault::peer_state) | protocol::bit(protocol::Fault::comms_timeout))) != 0);
      CHECK(other.safe_at_s == other.fault_at_s);
      CHECK_FALSE(other.armed_without_rearm);
      CHECK_FALSE(rebooted.armed_without_rearm);
      // Both armed again, after the rebooted lever homed.
      REQUIRE(other.rearmed_at_s.has_value());
      CHECK(*other.rearmed_at_s < reboot_at + f.spec.duration_s + 5.0);
      torque.check(c);
      CHECK(r.armed_ticks > static_cast<std::uint64_t>((k.duration - 5.0) * 1000.0));
    }
  }
}

// Over a link slower than the host's re-arm, a re-armed lever still receives its peer's heartbeats from before the
// peer's own re-arm: "armed", then "fault". Taken as a peer that armed with it and left, they threw the pair out
// again at every re-arm (docs/can-protocol.md). The arming handshake (a peer counts once its heartbeat echoes this
// lever's current arming) leaves the one fault and its one re-arm.
TEST_CASE("over a 100 ms link, one fault is one trip: the re-armed pair is not thrown out by old heartbeats",
          "[hil][faults]") {
  SimConfig c = base();
  c.scenario = ScenarioKind::free_motion;
  c.network = {100.0, 0.0, 0.0, true};
  for (auto* fw : {&c.hsi_firmware, &c.top_firmware}) fw->comms_timeout = 300;  // the watchdog stays out of it
  c.rearm_after_s = 0.0;  // the host re-arms at its next look, as it does after a trip
  c.faults.push_back(parse_fault_spec("motor-fault@3+0.05:top"));
  const auto r = run_simulation(c);
  REQUIRE(r.faults.size() == 1);
  const auto& f = r.faults[0];
  CAPTURE(r.hsi_lever_faults.count, r.top_lever_faults.count);
  CHECK(r.top_lever_faults.count == 1u);
  CHECK(r.top_lever_faults.bits == protocol::bit(protocol::Fault::motor_driver));
  CHECK(r.hsi_lever_faults.count == 1u);
  CHECK(r.hsi_lever_faults.bits == protocol::bit(protocol::Fault::peer_state));
  REQUIRE(f.hsi.rearmed_at_s.has_value());
  REQUIRE(f.top.rearmed_at_s.has_value());
  CHECK(*f.top.rearmed_at_s < 4.0);
}
