// The whole strain-gauge path of lever-fw: a libmodbus server, the Modbus gauge's poll thread, the GaugePort that
// stamps samples on the firmware's clock, and the core's StrainGauge. An amplifier that stops answering must
// become FORCE_STALE exactly when the staleness window says, measured from its last good sample, and never hang
// the loop; one that answers again is fresh again.
#include <catch2/catch.hpp>
#include <chrono>
#include <thread>

#include "gauge_test_support.hpp"
#include "lever/app/gauge_port.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/platform/modbus_gauge_presets.hpp"
#include "lever/platform/monotonic_clock.hpp"
#include "modbus_test_servers.hpp"

using namespace lever;
using namespace lever::platform;

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
    port.now_ns = lever::platform::monotonic_ns();
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
