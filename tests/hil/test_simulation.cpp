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
      const auto r = run_simulation(c);
      REQUIRE(r.faults.size() == 1);
      const auto& f = r.faults[0];
      const double injected = f.spec.start_s;
      const double torque_limit = c.top_firmware.torque_limit_nm;
      const double recovery_s = e.rehome ? 4.0 : 0.25;  // homing drives to the stop at 0.5 rad/s first
      for (const auto* side : {&f.hsi, &f.top}) {
        const bool own = e.faulting == Where::both || (side == &f.hsi) == (e.faulting == Where::hsi);
        INFO((side == &f.hsi ? "HSI" : "TOP") << (own ? ", its own fault" : ", its peer's fault"));
        CHECK(side->max_torque_nm_during <= torque_limit);
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

TEST_CASE("burst loss is healed by the refresh and counted, not a crash of the loop", "[hil][faults]") {
  SimConfig c = base();
  c.faults.push_back(parse_fault_spec("burst-loss@2+3"));
  const auto r = run_simulation(c);
  CHECK(r.network_lost > 50u);
  CHECK(r.hsi_seq_gaps + r.top_seq_gaps > 10u);
  const auto& f = r.faults[0];
  for (const auto* side : {&f.hsi, &f.top}) {
    CHECK(side->max_torque_nm_during <= c.top_firmware.torque_limit_nm);
    if (side->fault_at_s) CHECK(side->safe_at_s == side->fault_at_s);
  }
  CHECK(r.armed_ticks > 4500u);  // armed before the burst and again after it (faults in between are allowed)
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
  const auto large = run_simulation(c);
  const auto& f = large.faults[0];
  REQUIRE(f.top.fault_at_s.has_value());
  CHECK((f.top.latched & protocol::bit(protocol::Fault::comms_timeout)) != 0);
  CHECK(f.top.safe_at_s == f.top.fault_at_s);
  CHECK(f.top.max_torque_nm_during <= c.top_firmware.torque_limit_nm);
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

TEST_CASE("late ticks: counted as overruns, TIMING exactly past the 5 ms bound, no velocity blow-up",
          "[hil][faults][timing]") {
  struct Case {
    const char* spec;
    bool timing_fault;
  };
  // The firmware is not stepped for D; its next step comes D + 1 ms after the last.
  for (const Case k : {Case{"tick-late@3+0.004:top", false}, Case{"tick-late@3+0.005:top", true},
                       Case{"tick-late@3+0.004:hsi", false}, Case{"tick-late@3+0.005:hsi", true}}) {
    SECTION(k.spec) {
      SimConfig c = base(5.0);
      c.faults.push_back(parse_fault_spec(k.spec));
      double worst_velocity = 0.0, worst_torque = 0.0;
      c.observer = [&](const SimView& v) {
        for (const auto* t : {&v.hsi.telemetry(), &v.top.telemetry()}) {
          worst_velocity = std::max(worst_velocity, std::fabs(t->velocity_rad_s));
          worst_torque = std::max(worst_torque, std::fabs(t->torque_nm));
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
      CHECK(worst_torque <= c.top_firmware.torque_limit_nm);
      CHECK(worst_velocity < 10.0);  // a hand on a desk-top lever; the Euler loop reached 37 rad/s from 1
    }
  }
}

TEST_CASE("edges lost in the encoder's event queue are detected, never a silently wrong count",
          "[hil][faults][encoder]") {
  // A 50 ms stall of the TOP's loop while the pair moves: at a few rad/s that is hundreds of edges, more
  // than the 2 x 16 events the queue keeps.
  SimConfig c = base(6.0);
  c.faults.push_back(parse_fault_spec("tick-late@3+0.05:top"));
  const auto r = run_simulation(c);
  REQUIRE(r.top_edges_lost > 0u);
  const auto& top = r.faults[0].top;
  REQUIRE(top.fault_at_s.has_value());
  CHECK((top.latched & protocol::bit(protocol::Fault::encoder)) != 0);
  CHECK(r.hsi_edges_lost == 0u);
  // Without the fault, nothing is lost at all in the same run.
  c.faults.clear();
  const auto clean = run_simulation(c);
  CHECK(clean.top_edges_lost == 0u);
  CHECK(clean.hsi_edges_lost == 0u);
}
