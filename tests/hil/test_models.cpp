// The HIL's models on their own: bus timing and arbitration, the network link, encoder, operator (the gauge's
// amplifier in test_strain_gauge_model.cpp).
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "lever/fw/quadrature_decoder.hpp"
#include "lever/hil/can_bus.hpp"
#include "lever/hil/human_operator.hpp"
#include "lever/hil/network.hpp"
#include "lever/hil/quadrature_encoder.hpp"
#include "lever/hil/wall.hpp"

using namespace lever;
using namespace lever::hil;

namespace {
protocol::CanFrame frame(std::uint32_t id) { return {id, 8, {}}; }
}  // namespace

TEST_CASE("frame length with worst-case stuffing", "[hil][bus]") {
  CHECK(frame_bits_worst_case(0) == 55);   // 47 + 8 stuff bits
  CHECK(frame_bits_worst_case(8) == 135);  // 111 + 24
}

TEST_CASE("the bus sends the lowest id first and takes 135 us per 8-byte frame at 1 Mbit/s", "[hil][bus]") {
  CanBus bus(1e6);
  const auto a = bus.add_node(), b = bus.add_node(), listener = bus.add_node();
  REQUIRE(bus.send(a, frame(0x700), 0));
  REQUIRE(bus.send(b, frame(0x100), 0));
  bus.advance_to(134'000);
  protocol::CanFrame got;
  CHECK_FALSE(bus.receive(listener, got));  // the first frame is still on the wire
  bus.advance_to(135'000);
  REQUIRE(bus.receive(listener, got));
  CHECK(got.id == 0x100u);  // won arbitration
  bus.advance_to(270'000);
  REQUIRE(bus.receive(listener, got));
  CHECK(got.id == 0x700u);
  CHECK(bus.load() == Approx(1.0));  // busy the whole time so far
  bus.advance_to(540'000);
  CHECK(bus.load() == Approx(0.5));
  int own = 0, others = 0;  // a node hears the others' frames, never its own
  while (bus.receive(a, got)) (got.id == 0x700u ? own : others)++;
  CHECK(own == 0);
  CHECK(others == 1);
}

TEST_CASE("a frame ready during another's transmission waits for the bus", "[hil][bus]") {
  CanBus bus(1e6);
  const auto a = bus.add_node(), b = bus.add_node(), listener = bus.add_node();
  bus.send(a, frame(0x700), 0);
  bus.send(b, frame(0x080), 10'000);  // higher priority, but the bus is busy
  bus.advance_to(1'000'000);
  protocol::CanFrame first, second;
  REQUIRE(bus.receive(listener, first));
  REQUIRE(bus.receive(listener, second));
  CHECK(first.id == 0x700u);
  CHECK(second.id == 0x080u);
}

TEST_CASE("a bus-off node neither sends nor receives", "[hil][bus]") {
  CanBus bus;
  const auto a = bus.add_node(), b = bus.add_node();
  bus.set_bus_off(a, true);
  CHECK_FALSE(bus.send(a, frame(0x100), 0));
  bus.send(b, frame(0x110), 0);
  bus.advance_to(1'000'000);
  protocol::CanFrame got;
  CHECK_FALSE(bus.receive(a, got));
  CHECK(bus.stats(a).tx_refused == 1u);
}

TEST_CASE("the link delays, loses and reorders as configured, reproducibly", "[hil][network]") {
  auto run = [](const NetworkParams& p, std::uint64_t seed) {
    NetworkLink link(p, seed);
    std::vector<std::uint32_t> arrived;
    for (int i = 0; i < 10000; ++i) link.send(frame(static_cast<std::uint32_t>(i % 0x7FF)), i * 100'000LL);
    TimedFrame f;
    for (Nanos t = 0; t < 2'000'000'000LL; t += 100'000)
      while (link.pop_arrived(t, f)) arrived.push_back(f.frame.id);
    return std::make_pair(link.stats(), arrived);
  };
  const auto [lossy, lossy_ids] = run({5.0, 0.0, 0.1, true}, 1);
  CHECK(lossy.lost == Approx(1000).margin(120));
  CHECK(lossy.reordered == 0u);
  const auto [jittery, jittery_ids] = run({5.0, 2.0, 0.0, true}, 1);
  CHECK(jittery.reordered > 100u);  // 2 ms jitter on datagrams 0.1 ms apart
  const auto [fifo, fifo_ids] = run({5.0, 2.0, 0.0, false}, 1);
  CHECK(fifo.reordered == 0u);
  CHECK(run({5.0, 2.0, 0.1, true}, 7).second == run({5.0, 2.0, 0.1, true}, 7).second);
  CHECK(run({5.0, 2.0, 0.1, true}, 7).second != run({5.0, 2.0, 0.1, true}, 8).second);
}

TEST_CASE("a datagram arrives after the configured delay", "[hil][network]") {
  NetworkLink link({20.0, 0.0, 0.0, true}, 1);
  link.send(frame(0x100), 1'000'000);
  TimedFrame f;
  CHECK_FALSE(link.pop_arrived(20'999'999, f));
  CHECK(link.pop_arrived(21'000'000, f));
  CHECK(f.time == 21'000'000);  // its arrival time, for the bridge's own timestamp
  link.set_down(true);
  link.send(frame(0x100), 30'000'000);
  CHECK_FALSE(link.pop_arrived(100'000'000, f));
}

TEST_CASE("the encoder's edges decode back to its count; glitches are illegal transitions", "[hil][encoder]") {
  QuadratureEncoder encoder(16384.0, 0.0);
  fw::QuadratureDecoder decoder;
  decoder.reset(encoder.levels());
  fw::EncoderEdge edges[64];
  std::uint32_t lost = 0;
  auto drain = [&] {
    for (fw::EdgeDrain d; (d = encoder.drain_edges(edges, 64)).count > 0 || d.lost > 0;) {
      lost += d.lost;
      for (std::size_t i = 0; i < d.count; ++i) decoder.feed(edges[i]);
    }
  };
  for (double angle = 0.0; angle < 1.0; angle += 0.003) {  // 7.8 edges per step: within the 32-edge queue
    encoder.track(angle);
    drain();
  }
  for (double angle = 1.0; angle > -0.5; angle -= 0.003) {
    encoder.track(angle);
    drain();
  }
  encoder.track(-0.5);
  drain();
  CHECK(decoder.counts() == encoder.count());
  CHECK(encoder.overflowed() == 0u);
  CHECK(lost == 0u);
  CHECK(decoder.counts() == static_cast<std::int32_t>(std::floor(-0.5 / (2 * std::numbers::pi / 16384))));
  CHECK(decoder.illegal_transitions() == 0u);
  encoder.glitch();
  drain();
  CHECK(decoder.illegal_transitions() == 2u);
}

TEST_CASE("the index fires once a turn, at count 0, in both directions", "[hil][encoder]") {
  QuadratureEncoder encoder(16384.0, -0.01);
  fw::QuadratureDecoder decoder;
  decoder.reset(encoder.levels());
  fw::EncoderEdge edges[64];
  int indices = 0;
  for (double angle = -0.01; angle < 0.01; angle += 0.001) {
    encoder.track(angle);
    for (fw::EdgeDrain d; (d = encoder.drain_edges(edges, 64)).count > 0;)
      for (std::size_t i = 0; i < d.count; ++i) {
        decoder.feed(edges[i]);
        indices += edges[i].index;
      }
  }
  CHECK(indices == 1);
  const auto at = decoder.take_index();
  REQUIRE(at.has_value());
  // The decoder started at the encoder's power-up count (-27), so count 0 is 27 counts on.
  CHECK(*at == 27);
}

TEST_CASE("edges beyond the queue's capacity are lost, counted and reported to the drain", "[hil][encoder]") {
  QuadratureEncoder encoder(16384.0, 0.0);
  encoder.track(1.0);  // 2607 edges at once into libgpiod's 2 x 16 events
  CHECK(encoder.overflowed() == 2607u - 32u);
  fw::EncoderEdge edges[64];
  const auto d = encoder.drain_edges(edges, 64);
  CHECK(d.count == 32u);
  CHECK(d.lost == 2607u - 32u);
  CHECK(encoder.drain_edges(edges, 64).lost == 0u);  // said once
}

TEST_CASE("the wall pushes, never pulls", "[hil][wall]") {
  const WallParams w{0.3, 200.0, 0.3};
  CHECK(wall_torque(w, 0.29, 1.0) == 0.0);
  CHECK(wall_torque(w, 0.31, 0.0) == Approx(-2.0));
  CHECK(wall_torque(w, 0.3001, -5.0) == 0.0);  // leaving fast: the damper would pull, the wall does not
}

TEST_CASE("the operator's intent follows the scenario", "[hil][operator]") {
  SECTION("free motion stays short of the wall") {
    HumanOperator op({}, ScenarioKind::free_motion, 0.3, 0.1, 1);
    double furthest = 0.0;
    for (fw::Tick t = 1; t < 20000; ++t) {
      op.update(t, 0.0);
      furthest = std::max(furthest, op.intent_angle());
    }
    CHECK(furthest < 0.3);
  }
  SECTION("a press pushes the intent on until the felt force reaches the target") {
    HumanOperator op({}, ScenarioKind::press_hold, 0.3, 0.1, 1);
    fw::Tick t = 1;
    while (op.segment().kind != Segment::Kind::press) op.update(t++, 0.0);
    const double target = op.segment().target_force;
    // A rigid wall at 0.3 rad: the felt force is the hand's spring force against it.
    double felt = 0.0;
    for (int i = 0; i < 1500; ++i) {
      op.update(t++, felt);
      felt = std::max(0.0, op.hand_force(0.3, 0.0));
    }
    CHECK(op.segment().kind == Segment::Kind::press);
    CHECK(felt == Approx(target).epsilon(0.05));
  }
  SECTION("the speed and dwell factors scale every move's time and pause, on the same draws") {
    // The same seed draws the same segments; each move's time is divided by the speed factor, each pause (the
    // segment's time after its move) multiplied by the dwell factor; presses keep their length.
    auto segments = [](double speed, double dwell) {
      OperatorParams p;
      p.speed_factor = speed;
      p.dwell_factor = dwell;
      HumanOperator op(p, ScenarioKind::wall_tap, 0.3, 0.1, 7);
      std::vector<Segment> out{op.segment()};
      for (fw::Tick t = 1; out.size() < 40; ++t) {
        op.update(t, 0.0);
        if (op.segment().duration_s != out.back().duration_s || op.segment().kind != out.back().kind ||
            op.segment().target_angle != out.back().target_angle)
          out.push_back(op.segment());
      }
      return out;
    };
    const auto base = segments(1.0, 1.0), scaled = segments(2.0, 3.0);
    int moves_with_pause = 0;
    for (std::size_t i = 0; i < base.size(); ++i) {
      REQUIRE(scaled[i].kind == base[i].kind);
      if (base[i].kind == Segment::Kind::press) {
        CHECK(scaled[i].duration_s == base[i].duration_s);
        continue;
      }
      CHECK(scaled[i].target_angle == base[i].target_angle);
      CHECK(scaled[i].move_s == Approx(base[i].move_s / 2.0));
      const double pause = base[i].duration_s - base[i].move_s;
      CHECK(scaled[i].duration_s - scaled[i].move_s == Approx(3.0 * pause).margin(1e-12));
      moves_with_pause += pause > 0.0 ? 1 : 0;
    }
    CHECK(moves_with_pause > 5);
    OperatorParams still;
    still.speed_factor = 0.0;
    CHECK_THROWS_AS(HumanOperator(still, ScenarioKind::wall_tap, 0.3, 0.1, 1), std::invalid_argument);
  }
}
