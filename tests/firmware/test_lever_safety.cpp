// The lever core's safety behaviour: every fault kind, within one tick, torque always limited, re-arm.
#include <catch2/catch.hpp>
#include <cmath>

#include "lever/common/rng.hpp"
#include "lever_rig.hpp"

using namespace lever;
using namespace lever::fw;
using lever::test::PairRig;
using protocol::Opcode;

namespace {

// Runs until the lever leaves `armed`; returns the tick it did.
template <typename L>
Tick run_until_fault(PairRig& rig, const L& lever, Tick limit = 2000) {
  for (Tick i = 0; i < limit; ++i) {
    rig.tick();
    if (lever.supervisor().state() == LeverState::fault) return rig.now - 1;
  }
  return 0;
}

}  // namespace

TEST_CASE("both levers arm once they hear each other", "[firmware][lever]") {
  PairRig rig;
  rig.command(Opcode::arm);  // too early: no peer heard yet
  rig.run(2);
  CHECK(rig.hsi.supervisor().state() == LeverState::disarmed);
  CHECK(rig.hsi.counters().commands_rejected == 1u);
  rig.boot_and_arm();
  CHECK(rig.hsi.supervisor().armed());
  CHECK(rig.top.supervisor().armed());
}

TEST_CASE("deadband silence is not loss: a still lever raises no comms fault", "[firmware][lever][watchdog]") {
  PairRig rig;
  rig.boot_and_arm();
  const auto sent_before = rig.hsi.counters().data_sent;
  rig.run(10000);  // ten seconds of nothing happening
  CHECK(rig.hsi.supervisor().armed());
  CHECK(rig.top.supervisor().armed());
  // Only the refresh keeps data flowing: about one frame per 100 ms.
  const auto sent = rig.hsi.counters().data_sent - sent_before;
  CHECK(sent >= 95u);
  CHECK(sent <= 110u);
}

TEST_CASE("real loss is: a cut bus latches COMMS just after the timeout", "[firmware][lever][watchdog]") {
  PairRig rig;
  rig.boot_and_arm();
  rig.run(500);
  rig.bus.cut = true;
  const Tick cut_at = rig.now;
  const Tick fault_at = run_until_fault(rig, rig.top);
  REQUIRE(fault_at != 0);
  CHECK(has(rig.top.supervisor().latched(), Fault::comms_timeout));
  // Silent for more than the 100-tick timeout, counted from the last frame heard (a heartbeat or data up to
  // 25 ticks before the cut).
  CHECK(fault_at - cut_at >= 76u);
  CHECK(fault_at - cut_at <= 101u);
  rig.run(2);  // the HSI last heard the TOP within a tick of when the TOP last heard it
  CHECK(rig.hsi.supervisor().state() == LeverState::fault);
}

TEST_CASE("a fault takes the TOP to a limited hold in the same tick, then to zero torque", "[firmware][lever]") {
  PairRig rig;
  rig.boot_and_arm();
  rig.hand_target = 0.1;
  rig.run(1000);
  rig.bus.cut = true;
  const Tick fault_at = run_until_fault(rig, rig.top);
  REQUIRE(fault_at != 0);
  const auto& cfg = rig.top.config();
  CHECK(std::fabs(rig.top_hal.motor_.last.torque_nm) <= cfg.safe_hold_torque_nm);
  rig.run(cfg.safe_hold_ticks - 2);
  CHECK(rig.top_hal.motor_.last.enable);  // still holding
  rig.run(2);
  CHECK_FALSE(rig.top_hal.motor_.last.enable);
  CHECK(rig.top_hal.motor_.last.torque_nm == 0.0);
  // The HSI displays nothing from the fault's tick on.
  CHECK_FALSE(rig.hsi_hal.motor_.last.enable);
  CHECK(rig.hsi_hal.motor_.last.torque_nm == 0.0);
}

TEST_CASE("every fault kind latches, makes the lever safe in one tick, and re-arm recovers", "[firmware][lever]") {
  struct Case {
    const char* name;
    Fault expected;
    void (*inject)(PairRig&);
    void (*heal)(PairRig&);
  };
  const Case cases[] = {
      {"motor driver", Fault::motor_driver, [](PairRig& r) { r.top_hal.motor_.fault = true; },
       [](PairRig& r) { r.top_hal.motor_.fault = false; }},
      {"force stale", Fault::force_stale, [](PairRig& r) { r.gauge_alive = false; },
       [](PairRig& r) { r.gauge_alive = true; }},
      {"force saturated", Fault::force_saturated,
       [](PairRig& r) {
         r.gauge_alive = false;
         r.top_hal.force_.reading = ForceReading{32767, r.now, false};
       },
       [](PairRig& r) { r.gauge_alive = true; }},
      {"position limit", Fault::position_limit, [](PairRig& r) { r.top_plant.angle = 1.5; },
       [](PairRig& r) {
         r.top_plant.angle = 0.0;
         r.top_plant.speed = 0.0;
       }},
  };
  for (const auto& c : cases) {
    SECTION(c.name) {
      PairRig rig;
      rig.boot_and_arm();
      rig.run(200);
      c.inject(rig);
      if (c.expected == Fault::force_saturated) {
        // Keep the saturated reading fresh.
        for (int i = 0; i < 3 && rig.top.supervisor().armed(); ++i) {
          rig.top_hal.force_.reading->tick = rig.now;
          rig.tick();
        }
      } else {
        rig.run(c.expected == Fault::force_stale ? 7 : 1);
      }
      REQUIRE(rig.top.supervisor().state() == LeverState::fault);
      CHECK(has(rig.top.supervisor().latched(), c.expected));
      CHECK(std::fabs(rig.top_hal.motor_.last.torque_nm) <= rig.top.config().safe_hold_torque_nm);
      if (c.expected == Fault::motor_driver) CHECK_FALSE(rig.top_hal.motor_.last.enable);  // nothing to hold with

      rig.command(Opcode::rearm, false, true);  // refused while the condition holds
      if (c.expected == Fault::force_saturated) rig.top_hal.force_.reading->tick = rig.now;
      rig.tick();
      CHECK(rig.top.supervisor().state() == LeverState::fault);

      c.heal(rig);
      rig.run(5);
      rig.command(Opcode::rearm, false, true);
      rig.run(2);
      CHECK(rig.top.supervisor().armed());
      CHECK(rig.top.supervisor().latched() == 0);
    }
  }
}

TEST_CASE(
    "the decoder starts from the levels the edge source read at open: the first edge counts, B leading A "
    "counts up",
    "[firmware][lever][encoder]") {
  constexpr AbState kForward[4] = {0b00, 0b01, 0b11, 0b10};  // (A << 1) | B: B rises first
  for (int start = 0; start < 4; ++start) {
    INFO("lines at " << kForward[start] << " when opened");
    test::CanBus bus;
    test::FakeHal<test::FakeEdgeEncoder> hal(bus);
    hal.encoder_.current = kForward[start];
    HsiLever<test::FakeHal<test::FakeEdgeEncoder>> hsi(hal, test::rig_config(protocol::Role::hsi));
    Tick now = 1;
    // 4000 steps forward, one per tick edge by edge, then 1500 back: as the guest's quadrature source drives them.
    int phase = start;
    for (int i = 0; i < 4000; ++i) {
      hal.encoder_.push(kForward[++phase % 4]);
      hsi.step(now++);
    }
    CHECK(hsi.decoder().counts() == 4000);
    for (int i = 0; i < 1500; ++i) {
      hal.encoder_.push(kForward[(--phase % 4 + 4) % 4]);
      hsi.step(now++);
    }
    CHECK(hsi.decoder().counts() == 2500);
    CHECK(hsi.decoder().illegal_transitions() == 0u);
  }
}

TEST_CASE("an encoder glitch storm latches ENCODER and the TOP lets go rather than hold blind",
          "[firmware][lever][encoder]") {
  test::CanBus bus;
  test::FakeHal<test::FakeEdgeEncoder> hal(bus);
  LeverConfig config = test::rig_config(protocol::Role::top);
  TopLever<test::FakeHal<test::FakeEdgeEncoder>> top(hal, config);
  hal.force_.reading = ForceReading{0, 0, false};
  Tick now = 1;
  auto heartbeat_from_hsi = [&] { bus.inject(protocol::pack(protocol::HeartbeatMessage{}, 0, protocol::Role::hsi)); };
  constexpr AbState kForward[4] = {0b00, 0b01, 0b11, 0b10};
  int phase = 0;
  for (; now < 50; ++now) {
    hal.force_.reading->tick = now;
    heartbeat_from_hsi();
    hal.encoder_.pending.clear();
    for (int e = 0; e < 3; ++e) hal.encoder_.push(kForward[++phase % 4]);  // legal forward edges
    top.step(now);
  }
  bus.inject(protocol::pack(protocol::CommandMessage{}, 0));  // arm
  hal.force_.reading->tick = now;
  top.step(now++);
  REQUIRE(top.supervisor().armed());
  const AbState here = kForward[phase % 4], opposite = kForward[(phase + 2) % 4];
  hal.encoder_.pending.clear();
  for (int e = 0; e < 10; ++e) hal.encoder_.push(e % 2 ? here : opposite);  // both lines flipping
  hal.force_.reading->tick = now;
  heartbeat_from_hsi();
  top.step(now++);
  CHECK(top.supervisor().state() == LeverState::fault);
  CHECK(has(top.supervisor().latched(), Fault::encoder));
  CHECK_FALSE(hal.motor_.last.enable);
  CHECK(top.decoder().illegal_transitions() > config.decoder.illegal_threshold);
}

TEST_CASE("a TOP told to go far away saturates, then latches TORQUE_LIMIT", "[firmware][lever]") {
  PairRig rig;
  rig.boot_and_arm();
  // The operator swings the HSI toward 0.9 rad. The TOP's load is heavy (1 kg m^2), so its motor saturates
  // long before it gets anywhere, and certainly before it could hit the wall hard enough to saturate the
  // gauge first.
  rig.top_plant.inertia = 1.0;
  rig.hand_target = 0.9;
  rig.hand_stiffness = 30.0;
  rig.hand_damping = 0.5;
  const Tick start = rig.now;
  const Tick fault_at = run_until_fault(rig, rig.top);
  REQUIRE(fault_at != 0);
  INFO("latched faults: " << rig.top.supervisor().latched());
  CHECK(has(rig.top.supervisor().latched(), Fault::torque_limit));
  CHECK(fault_at - start >= rig.top.config().torque_saturation_ticks);
  CHECK(rig.top_hal.motor_.max_abs_torque <= rig.top.config().torque_limit_nm);
}

TEST_CASE("whatever arrives on the bus, commanded torque never exceeds the limit", "[firmware][lever][fuzz]") {
  PairRig rig;
  rig.boot_and_arm();
  Rng rng(2024);
  for (int i = 0; i < 20000; ++i) {
    // Well-formed frames with hostile contents, malformed frames, and random commands, several per tick.
    for (int k = 0; k < 3; ++k) {
      protocol::CanFrame f;
      switch (rng.next() % 4) {
        case 0: {
          protocol::MotionMessage m;
          m.position = static_cast<std::int16_t>(rng.next());
          m.velocity = static_cast<std::int16_t>(rng.next());
          m.tick = static_cast<std::uint16_t>(rng.next());
          m.seq = static_cast<std::uint8_t>(rng.next());
          m.flags.mode = rng.next() & 1 ? codec::Mode::predictive : codec::Mode::deadband;
          f = protocol::pack(m, 0);
          break;
        }
        case 1: {
          protocol::ForceMessage m;
          m.force = static_cast<std::int32_t>(rng.next() % (1u << 24)) - (1 << 23);
          m.tick = static_cast<std::uint16_t>(rng.next());
          m.seq = static_cast<std::uint8_t>(rng.next());
          f = protocol::pack(m, 0);
          break;
        }
        case 2: {
          protocol::CommandMessage c;
          c.opcode = static_cast<Opcode>(1 + rng.next() % 5);
          c.direction = rng.next() & 1 ? protocol::Direction::force : protocol::Direction::motion;
          c.p = static_cast<std::uint16_t>(rng.next());
          c.floor = static_cast<std::uint16_t>(rng.next());
          c.filter_hz = static_cast<std::uint16_t>(rng.next());
          f = protocol::pack(c, 0);
          break;
        }
        default:
          f.id = static_cast<std::uint32_t>(rng.next() % 0x800);
          f.dlc = static_cast<std::uint8_t>(rng.next() % 16);
          for (auto& b : f.data) b = static_cast<std::uint8_t>(rng.next());
      }
      rig.bus.inject(f);
    }
    rig.tick();
  }
  CHECK(rig.top_hal.motor_.max_abs_torque <= rig.top.config().torque_limit_nm);
  CHECK(rig.hsi_hal.motor_.max_abs_torque <= rig.hsi.config().torque_limit_nm);
  CHECK(rig.top.counters().rx_rejected > 0u);
  CHECK(rig.top.counters().rx_stale > 0u);
}

TEST_CASE("a TOP whose HSI stopped streaming holds still instead of integrating old motion", "[firmware][lever]") {
  PairRig rig;
  rig.boot_and_arm();
  rig.hand_target = 0.25;
  rig.run(150);  // the HSI is moving: the TOP's last reconstructed velocity is far from zero
  REQUIRE(std::fabs(rig.top.telemetry().velocity_ref_rad_s) > 0.1);
  rig.bus.drop_id = protocol::motion_id(0);  // the HSI's data frames are lost; its heartbeats go on
  rig.run(1500);
  CHECK(rig.hsi.supervisor().armed());
  CHECK(rig.top.supervisor().armed());  // not a comms fault: the HSI is alive
  CHECK(rig.top.telemetry().velocity_ref_rad_s == 0.0);
  CHECK(std::fabs(rig.top.telemetry().position_ref_rad) < 0.5);  // no runaway reference
  CHECK(std::fabs(rig.top_plant.speed) < 0.01);
}

TEST_CASE("tare is accepted only while disarmed", "[firmware][lever]") {
  PairRig rig;
  rig.run(60);
  rig.command(Opcode::tare, false, true);
  rig.run(1);
  CHECK(rig.top.gauge().taring());
  rig.run(100);
  CHECK_FALSE(rig.top.gauge().taring());
  rig.command(Opcode::arm);
  rig.run(2);
  REQUIRE(rig.top.supervisor().armed());
  const auto rejected = rig.top.counters().commands_rejected;
  rig.command(Opcode::tare, false, true);
  rig.run(1);
  CHECK_FALSE(rig.top.gauge().taring());
  CHECK(rig.top.counters().commands_rejected == rejected + 1);
}

TEST_CASE("set_deadband reconfigures the sending end and the receiver follows at the same sample",
          "[firmware][lever]") {
  PairRig rig;
  rig.boot_and_arm();
  protocol::CommandMessage c;
  c.opcode = Opcode::set_deadband;
  c.direction = protocol::Direction::motion;
  c.mode = codec::Mode::predictive;
  c.p = 500;          // 5 %
  c.floor = 20;       // 0.02 rad/s
  c.filter_hz = 300;  // 30 Hz
  rig.bus.inject(protocol::pack(c, 0));
  rig.run(2);
  const auto& cfg = rig.hsi.role().sender().config();
  CHECK(cfg.mode == codec::Mode::predictive);
  CHECK(cfg.p == Approx(0.05));
  CHECK(cfg.floor == Approx(0.02));
  CHECK(cfg.filter_hz == Approx(30.0));
  CHECK(rig.top.role().receiver().codec_receiver().model().mode() == codec::Mode::predictive);
  // A force-direction change goes to the TOP's sender and leaves the HSI's alone.
  c.direction = protocol::Direction::force;
  c.mode = codec::Mode::deadband;
  c.p = 250;
  c.floor = 50;
  c.filter_hz = 0;
  rig.bus.inject(protocol::pack(c, 0));
  rig.run(2);
  CHECK(rig.hsi.role().sender().config().mode == codec::Mode::predictive);
  CHECK(rig.top.role().sender().config().p == Approx(0.025));
  CHECK(rig.top.role().sender().config().floor == Approx(0.05));
}

TEST_CASE("frames of another pair are ignored, not counted as errors", "[firmware][lever]") {
  PairRig rig;
  rig.boot_and_arm();
  protocol::CommandMessage disarm;
  disarm.opcode = Opcode::disarm;
  rig.bus.inject(protocol::pack(disarm, 5));
  rig.run(2);
  CHECK(rig.top.supervisor().armed());
  CHECK(rig.top.counters().rx_rejected == 0u);
}

TEST_CASE("a disarmed lever does not latch what it does not report, but will not arm while it holds",
          "[firmware][lever][supervisor]") {
  PairRig rig;
  rig.run(60);
  rig.top_hal.motor_.fault = true;
  rig.run(5);
  CHECK(rig.top.supervisor().latched() == 0);  // disarmed: the lever does not report, so nothing latches
  rig.command(Opcode::arm);
  rig.run(2);
  CHECK(rig.top.supervisor().state() == LeverState::disarmed);  // ...but the condition refuses the arm
  CHECK(rig.top.counters().commands_rejected == 1u);
  rig.top_hal.motor_.fault = false;
  rig.command(Opcode::arm);
  rig.run(2);
  CHECK(rig.top.supervisor().armed());
}

namespace {

// A TOP with an incremental edge encoder and hard-stop homing, on its own plant with an end stop.
struct HomingRig {
  test::CanBus bus;
  test::FakeHal<test::FakeEdgeEncoder> hal{bus};
  LeverConfig config = [] {
    LeverConfig c = test::rig_config(protocol::Role::top);
    c.homing.method = HomingMethod::hard_stop;
    return c;
  }();
  TopLever<test::FakeHal<test::FakeEdgeEncoder>> top{hal, config};
  double angle = 0.2, speed = 0.0;  // true angle: power-up anywhere
  double stop = -0.6, stop_stiffness = 20.0;
  std::int64_t count = 0;  // the encoder's count since power-up
  Tick now = 1;
  static constexpr AbState kGray[4] = {0b00, 0b01, 0b11, 0b10};

  void tick() {
    const double count_per_rad = 16384.0 / (2.0 * 3.14159265358979323846);
    for (int i = 0; i < 10; ++i) {
      const double torque = hal.motor_.last.enable ? hal.motor_.last.torque_nm : 0.0;
      const double bumper = angle < stop ? stop_stiffness * (stop - angle) - 0.05 * speed : 0.0;
      speed += (torque + (bumper > 0 ? bumper : 0.0) - 0.02 * speed) / 2e-3 * 1e-4;
      angle += speed * 1e-4;
      const auto target = static_cast<std::int64_t>(std::floor((angle - 0.2) * count_per_rad));
      while (count != target) {
        count += target > count ? 1 : -1;
        hal.encoder_.push(kGray[((count % 4) + 4) % 4]);
      }
    }
    hal.force_.reading = ForceReading{0, now, false};
    bus.inject(protocol::pack(protocol::HeartbeatMessage{}, 0, protocol::Role::hsi));
    top.step(now++);
  }
  void command(Opcode op) {
    protocol::CommandMessage m;
    m.opcode = op;
    bus.inject(protocol::pack(m, 0));
  }
  // Powered up, homed against the stop and armed: where the fault tests begin.
  void home_and_arm() {
    for (int i = 0; i < 60; ++i) tick();
    command(Opcode::home);
    for (int i = 0; i < 6000 && !top.telemetry().position_valid; ++i) tick();
    tick();
    command(Opcode::arm);
    tick();
  }
};

}  // namespace

TEST_CASE("an incremental lever is unhomed at power-up, refuses to arm, homes against its stop and then arms",
          "[firmware][lever][homing]") {
  HomingRig rig;
  for (int i = 0; i < 60; ++i) rig.tick();
  CHECK_FALSE(rig.top.telemetry().position_valid);
  rig.command(Opcode::arm);
  rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::disarmed);  // no arming on an unknown position
  rig.command(Opcode::home);
  rig.tick();
  REQUIRE(rig.top.supervisor().state() == LeverState::homing);
  double worst_torque = 0.0;
  int ticks = 0;
  while (rig.top.supervisor().state() == LeverState::homing && ticks++ < 10000) {
    rig.tick();
    worst_torque = std::max(worst_torque, std::fabs(rig.hal.motor_.last.torque_nm));
  }
  REQUIRE(rig.top.supervisor().state() == LeverState::disarmed);
  CHECK(rig.top.telemetry().position_valid);
  CHECK(worst_torque <= rig.config.homing.torque_limit_nm);
  // The stop pressed at the homing torque is where the config says it is (-0.61 rad), to within a count or
  // two of bumper settling, whatever the power-up angle was.
  CHECK(rig.top.telemetry().position_rad == Approx(rig.angle).margin(0.002));
  CHECK(rig.top.telemetry().position_rad == Approx(-0.61).margin(0.003));
  rig.command(Opcode::arm);
  rig.tick();
  CHECK(rig.top.supervisor().armed());
}

TEST_CASE("lost edges latch ENCODER, invalidate the position, and only homing makes it valid again",
          "[firmware][lever][homing][encoder]") {
  HomingRig rig;
  rig.home_and_arm();
  REQUIRE(rig.top.supervisor().armed());
  rig.hal.encoder_.lost = 5;  // the source says: five edges dropped
  rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::fault);
  CHECK(has(rig.top.supervisor().latched(), Fault::encoder));
  CHECK_FALSE(rig.top.telemetry().position_valid);
  rig.command(Opcode::rearm);
  rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::fault);  // the count is off: no re-arm before homing
  rig.command(Opcode::home);
  rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::fault);  // nor a home straight out of fault
  rig.command(Opcode::disarm);  // the host acknowledges the fault: the TOP stops its safe behaviour...
  rig.command(Opcode::home);    // ...and may then home, its faults still latched
  rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::homing);
  CHECK(has(rig.top.supervisor().latched(), Fault::encoder));
  for (int i = 0; i < 6000 && !rig.top.telemetry().position_valid; ++i) rig.tick();
  CHECK(rig.top.telemetry().position_valid);
  rig.tick();
  rig.command(Opcode::rearm);
  rig.tick();
  CHECK(rig.top.supervisor().armed());
}

TEST_CASE("a latched fault clears only by re-arm: a home meant for another lever leaves a faulted one in fault",
          "[firmware][lever][homing][supervisor]") {
  HomingRig rig;
  rig.home_and_arm();
  REQUIRE(rig.top.supervisor().armed());
  rig.hal.motor_.fault = true;  // the driver reports a fault, then recovers
  rig.tick();
  REQUIRE(rig.top.supervisor().state() == LeverState::fault);
  rig.hal.motor_.fault = false;
  const auto rejected = rig.top.counters().commands_rejected;
  // lever_restart.sh: the host homes a restarted peer with a command to both levers.
  rig.command(Opcode::home);
  for (int i = 0; i < 100; ++i) rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::fault);
  CHECK(rig.top.counters().commands_rejected == rejected + 1);
  CHECK(has(rig.top.supervisor().latched(), Fault::motor_driver));
  rig.command(Opcode::arm);  // arm does not clear either
  rig.tick();
  CHECK(rig.top.supervisor().state() == LeverState::fault);
  rig.command(Opcode::rearm);  // the one command that clears
  rig.tick();
  CHECK(rig.top.supervisor().armed());
  CHECK(rig.top.supervisor().latched() == 0);
}

TEST_CASE("a 16-bit hardware counter behind the counting port is unwrapped, not taken as the count",
          "[firmware][lever][encoder]") {
  test::CanBus bus;
  test::FakeHal<> hal(bus);
  LeverConfig config = test::rig_config(protocol::Role::hsi);
  config.counter_bits = 16;
  hal.encoder_.width_mask = 0xFFFF;
  HsiLever<test::FakeHal<>> hsi(hal, config);
  const double rad_per_count = 2.0 * 3.14159265358979323846 / config.counts_per_rev;
  // Power-up at -10 counts, then 20 turns forward at 3000 counts a tick: the register wraps every 65536.
  std::int64_t truth = -10;
  Tick now = 1;
  for (int i = 0; i < 110; ++i) {
    hal.encoder_.counts = static_cast<std::int32_t>(truth);  // the fake keeps only the low 16 bits
    hsi.step(now++);
    REQUIRE(hsi.telemetry().position_rad == Approx(static_cast<double>(truth) * rad_per_count));
    truth += 3000;
  }
  CHECK(truth > 65536 * 5);
}

namespace {

// A CAN port that can say it lost the bus (a controller gone bus-off, an interface down).
struct FaultyCanHal : test::FakeHal<> {
  struct Port : test::CanBus::Port {
    explicit Port(const test::CanBus::Port& p) : test::CanBus::Port(p) {}
    bool off = false;
    bool bus_fault() const { return off; }
  };
  explicit FaultyCanHal(test::CanBus& bus) : test::FakeHal<>(bus), port(can_) {}
  Port port;
  Port& can() { return port; }
};

}  // namespace

TEST_CASE("a CAN port that reports bus-off latches CAN_BUS at once, and the TOP holds", "[firmware][lever][can]") {
  static_assert(HasBusFault<FaultyCanHal::Port>);
  test::CanBus bus;
  FaultyCanHal hal(bus);
  test::FakeHal<> hsi_hal(bus);
  TopLever<FaultyCanHal> top(hal, test::rig_config(protocol::Role::top));
  HsiLever<test::FakeHal<>> hsi(hsi_hal, test::rig_config(protocol::Role::hsi));
  hal.force_.reading = ForceReading{0, 0, false};
  Tick now = 1;
  auto tick = [&] {
    hal.force_.reading->tick = now;
    hsi.step(now);
    top.step(now);
    ++now;
  };
  for (int i = 0; i < 60; ++i) tick();
  bus.inject(protocol::pack(protocol::CommandMessage{}, 0));
  tick();
  REQUIRE(top.supervisor().armed());
  hal.port.off = true;
  tick();
  CHECK(top.supervisor().state() == LeverState::fault);
  CHECK(has(top.supervisor().latched(), Fault::can_bus));
  hal.port.off = false;
  bus.inject(protocol::pack(protocol::CommandMessage{protocol::Opcode::rearm}, 0));
  for (int i = 0; i < 3; ++i) tick();
  CHECK(top.supervisor().armed());  // back once the bus is, by a re-arm
}

// Resending (docs/can-protocol.md, "Resending"): a host that has not yet seen a lever's heartbeat answer sends the
// command again, so a copy may reach a lever that already did what it says.
namespace {

template <typename L>
std::uint32_t rejected_by(const L& lever) {
  return lever.counters().commands_rejected;
}

// Data frames on the bus from `from` on that start a new stream: what an arming does.
std::size_t restarts_since(const test::CanBus& bus, std::size_t from) {
  std::size_t n = 0;
  for (std::size_t i = from; i < bus.log.size(); ++i) {
    protocol::FrameAddress address;
    protocol::MotionMessage motion;
    protocol::ForceMessage force;
    if (protocol::decode(bus.log[i], motion, address) == protocol::DecodeError::none && motion.flags.restart) ++n;
    if (protocol::decode(bus.log[i], force, address) == protocol::DecodeError::none && force.flags.restart) ++n;
  }
  return n;
}

}  // namespace

TEST_CASE("a duplicated arm, re-arm or disarm changes nothing and is not counted as rejected",
          "[firmware][lever][idempotent]") {
  PairRig rig;
  rig.boot_and_arm();
  rig.run(100);
  REQUIRE(rig.hsi.supervisor().armed());
  REQUIRE(rig.top.supervisor().armed());
  const auto mark = rig.bus.log.size();
  const auto hsi_rejected = rejected_by(rig.hsi), top_rejected = rejected_by(rig.top);
  rig.command(Opcode::arm);
  rig.run(5);
  rig.command(Opcode::rearm);
  rig.run(200);
  CHECK(rig.hsi.supervisor().armed());
  CHECK(rig.top.supervisor().armed());
  CHECK(restarts_since(rig.bus, mark) == 0u);  // no new stream: the arming the pair agreed on stands
  CHECK(rejected_by(rig.hsi) == hsi_rejected);
  CHECK(rejected_by(rig.top) == top_rejected);
  rig.command(Opcode::disarm);
  rig.run(2);
  rig.command(Opcode::disarm);
  rig.run(2);
  CHECK(rig.hsi.supervisor().state() == LeverState::disarmed);
  CHECK(rig.top.supervisor().state() == LeverState::disarmed);
  CHECK(rejected_by(rig.hsi) == hsi_rejected);
  CHECK(rejected_by(rig.top) == top_rejected);
}

TEST_CASE("a duplicated tare does not restart the average the first copy started", "[firmware][lever][idempotent]") {
  PairRig rig;
  rig.run(60);
  rig.command(Opcode::tare, false, true);
  rig.run(30);
  REQUIRE(rig.top.gauge().taring());
  rig.command(Opcode::tare, false, true);
  // One fresh reading a tick: the first copy's 64 readings end at tick 64; a restarted average at tick 94.
  rig.run(40);
  CHECK_FALSE(rig.top.gauge().taring());
  CHECK(rejected_by(rig.top) == 0u);
}

TEST_CASE("a duplicated home neither restarts a homing in progress nor homes a homed lever again",
          "[firmware][lever][homing][idempotent]") {
  const auto ticks_to_home = [](bool duplicate) {
    HomingRig rig;
    for (int i = 0; i < 60; ++i) rig.tick();
    rig.command(Opcode::home);
    int ticks = 0;
    for (; ticks < 10000 && !rig.top.telemetry().position_valid; ++ticks) {
      if (duplicate && ticks == 300) {
        REQUIRE(rig.top.supervisor().state() == LeverState::homing);
        rig.command(Opcode::home);
      }
      rig.tick();
    }
    CHECK(rig.top.counters().commands_rejected == 0u);
    return ticks;
  };
  CHECK(ticks_to_home(true) == ticks_to_home(false));

  HomingRig rig;
  for (int i = 0; i < 60; ++i) rig.tick();
  rig.command(Opcode::home);
  for (int i = 0; i < 10000 && !rig.top.telemetry().position_valid; ++i) rig.tick();
  REQUIRE(rig.top.telemetry().position_valid);
  rig.tick();
  rig.command(Opcode::home);  // a copy that arrives after the homing ended
  bool stayed = true;
  for (int i = 0; i < 500; ++i) {
    rig.tick();
    stayed = stayed && rig.top.supervisor().state() == LeverState::disarmed && rig.top.telemetry().position_valid &&
             !rig.hal.motor_.last.enable;
  }
  CHECK(stayed);
  CHECK(rig.top.telemetry().position_rad == Approx(rig.angle).margin(0.002));  // the first homing's reference
  CHECK(rig.top.counters().commands_rejected == 0u);
}
