// The whole strain-gauge path of lever-fw: a libmodbus server, the Modbus gauge's poll thread, the GaugePort that
// stamps samples on the firmware's clock, and the core's StrainGauge. An amplifier that stops answering must
// become FORCE_STALE exactly when the staleness window says, measured from its last good sample, and never hang
// the loop; one that answers again is fresh again.
#include <catch2/catch.hpp>
#include <chrono>
#include <thread>

#include "gauge_test_support.hpp"
#include "lever/app/gauge_port.hpp"
#include "lever/board/modbus_gauge_presets.hpp"
#include "lever/board/monotonic_clock.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "modbus_test_servers.hpp"

using namespace lever;
using namespace lever::board;

TEST_CASE(
    "an amplifier that stops answering is a stale force exactly at the window's end; one that comes back is "
    "fresh again",
    "[board][gauge][app]") {
  test::TcpTestServer server;
  server.set_holding(0, test::registers_for(1000, RegisterType::int32, WordOrder::high_first));  // 1000 g
  auto config = preset_gross_weight_int32(ModbusTcpEndpoint{"127.0.0.1", server.port(), 255});
  config.response_timeout = std::chrono::milliseconds(50);
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  auto& gauge = opened.value();

  constexpr fw::Tick kStaleAfter = 20;
  fw::StrainGauge core_gauge({1.0, 0.0, -1e9, 1e9, kStaleAfter, 4});  // the amplifier reports newtons
  app::GaugePort port{&gauge};
  fw::Tick tick = 0;
  double slowest_latest_us = 0.0;
  auto step = [&] {  // one firmware tick, paced like the board's loop
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++tick;
    port.now_tick = tick;
    port.now_ns = lever::board::monotonic_ns();
    const auto t0 = std::chrono::steady_clock::now();
    const auto reading = port.latest();
    slowest_latest_us = std::max(
        slowest_latest_us, std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
    return core_gauge.update(reading, tick);
  };

  std::optional<double> force;
  for (int i = 0; i < 3000 && !force; ++i) force = step();
  REQUIRE(force.has_value());
  CHECK(*force == Approx(1000 * 9.80665e-3));

  server.set_behaviour(test::ServerBehaviour::mute);
  // Once the gauge goes quiet, staleness comes exactly kStaleAfter ticks after the last good sample's stamp.
  fw::Tick stale_at = 0;
  for (int i = 0; i < 5000 && stale_at == 0; ++i)
    if (!step()) stale_at = tick;
  REQUIRE(stale_at != 0);
  CHECK(core_gauge.state().stale);
  CHECK(stale_at - core_gauge.state().last_tick == kStaleAfter + 1);
  CHECK(slowest_latest_us < 1000.0);  // the loop never waits for the amplifier (the poll thread does)

  server.set_behaviour(test::ServerBehaviour::answer);
  force.reset();
  for (int i = 0; i < 5000 && !force; ++i) force = step();
  REQUIRE(force.has_value());  // reconnected, fresh again
  CHECK_FALSE(core_gauge.state().stale);
}

TEST_CASE(
    "the gauge survives one lost response; four in a row, or a server that dies, are a stale force; each "
    "failure reaches the core as a failed reading",
    "[board][gauge][app]") {
  auto server = std::make_unique<test::TcpTestServer>();
  const int port = server->port();
  server->set_holding(0, test::registers_for(1000, RegisterType::int32, WordOrder::high_first));
  // lever-fw's amplifier and its staleness window derived as lever-fw derives them, on timings twenty and forty
  // times the defaults' (poll 100 ms, timeout 400 ms), so a loaded machine's scheduling is small beside the
  // margins. Answers come late where the core must see a failure as the newest reading: an answer in the same
  // millisecond would hide it (the core looks once a tick; the gauge's counters count every one).
  auto config = preset_gross_weight_int32(ModbusTcpEndpoint{"127.0.0.1", port, 255});
  config.poll_period = std::chrono::milliseconds(100);
  config.response_timeout = std::chrono::milliseconds(400);
  const auto stale_after =
      static_cast<fw::Tick>(std::chrono::ceil<std::chrono::milliseconds>(longest_gap(config, 1)).count() + 1);
  CHECK(stale_after == 1301);  // 100 + 2 x 400 ms + a connect bounded by 400 ms, and a tick
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  auto& gauge = opened.value();
  fw::StrainGauge core_gauge({1.0, 0.0, -1e9, 1e9, stale_after, 4});
  app::GaugePort port_of_core{&gauge};
  fw::Tick tick = 0;
  bool stale_seen = false;
  auto step = [&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ++tick;
    port_of_core.now_tick = tick;
    port_of_core.now_ns = lever::board::monotonic_ns();
    const auto force = core_gauge.update(port_of_core.latest(), tick);
    stale_seen = stale_seen || !force;
    return force;
  };
  auto run_ms = [&](int ms) {
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (std::chrono::steady_clock::now() < until) step();
  };
  auto until_fresh = [&] {
    for (int i = 0; i < 20000; ++i)
      if (step()) return true;
    return false;
  };
  REQUIRE(until_fresh());
  run_ms(300);
  stale_seen = false;
  const auto before = gauge.counters();

  SECTION("one response lost and the retry answered just within its timeout: no stale force") {
    // Near the worst case the window is made for: the poll a period after the last reading, its timeout, a
    // reconnect (instant on loopback; up to the timeout on a network), then the answer 350 of its 400 ms late:
    // the reading is 850 ms old when the next arrives.
    server->set_late_delay(std::chrono::milliseconds(350));
    server->set_behaviour(test::ServerBehaviour::late);
    server->drop_next(1);
    run_ms(1500);
    CHECK(server->drops_left() == 0);
    CHECK_FALSE(stale_seen);
    CHECK(gauge.counters().timeouts == before.timeouts + 1);
    CHECK(gauge.counters().reconnects == before.reconnects + 1);  // at once, no backoff
    CHECK(core_gauge.state().failed_readings == 1u);
  }
  SECTION("two exception responses: no stale force, two failed readings") {
    server->refuse_next(2);
    run_ms(600);
    CHECK(server->refusals_left() == 0);
    CHECK_FALSE(stale_seen);
    CHECK(gauge.counters().exceptions == before.exceptions + 2);
    CHECK(core_gauge.state().failed_readings == 2u);
  }
  SECTION("four lost in a row: a stale force (4 x 400 ms > 1301 ms), then fresh again") {
    server->set_behaviour(test::ServerBehaviour::late);
    server->drop_next(4);
    run_ms(2500);
    CHECK(server->drops_left() == 0);
    CHECK(stale_seen);
    CHECK(core_gauge.state().failed_readings == 4u);
    CHECK_FALSE(core_gauge.state().stale);
  }
  SECTION("the server dies and comes back: stale while it is away, failed connects counted, fresh again") {
    server.reset();
    run_ms(1500);
    CHECK(stale_seen);
    CHECK(core_gauge.state().stale);
    CHECK(gauge.counters().connect_failures >= 2);
    CHECK(core_gauge.state().failed_readings >= 2u);
    server = std::make_unique<test::TcpTestServer>("127.0.0.1", port);
    server->set_holding(0, test::registers_for(2000, RegisterType::int32, WordOrder::high_first));
    REQUIRE(until_fresh());
    CHECK(*core_gauge.state().force == Approx(2000 * 9.80665e-3));
    CHECK(gauge.counters().reconnects >= 1);
  }
}
