// The Modbus gauge over RTU on a pseudo-terminal pair: a libmodbus RTU server on the master end, the gauge on
// the slave end as on a serial port; and a hand-written responder for frames with a bad CRC.
#include <modbus.h>

#include <catch2/catch.hpp>
#include <chrono>

#include "gauge_test_support.hpp"
#include "gauge_type_cases.hpp"
#include "modbus_test_servers.hpp"

using namespace lever::board;
using namespace lever::test;
using namespace std::chrono_literals;

namespace {

ModbusRtuEndpoint serial(const std::string& device, int slave_id = 1) {
  ModbusRtuEndpoint rtu;
  rtu.device = device;
  rtu.slave_id = slave_id;
  return rtu;
}

GaugeRegisterMap int32_at_zero() {
  GaugeRegisterMap map;
  map.type = RegisterType::int32;
  return map;
}

}  // namespace

TEST_CASE("RTU: every register type and word order reads the server's value and follows its changes") {
  RtuTestServer server(17);
  for (const auto& type_case : kTypeCases) {
    for (const auto function : {RegisterFunction::holding, RegisterFunction::input}) {
      INFO("type " << static_cast<int>(type_case.type) << ", word order " << static_cast<int>(type_case.order)
                   << ", function " << static_cast<int>(function));
      check_reads_and_follows(server, serial(server.device(), 17), type_case, function);
    }
  }
}

TEST_CASE(
    "RTU: a server that stops answering leaves the last sample to age and counts timeouts, and when it "
    "answers again the gauge reopens the port and samples resume") {
  RtuTestServer server;
  server.set_holding(0, registers_for(-5, RegisterType::int32, WordOrder::high_first));
  auto config = test_config(serial(server.device()), int32_at_zero());
  config.response_timeout = 50ms;
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == -5; }));

  server.set_behaviour(ServerBehaviour::mute);
  const auto received = server.requests_received();
  REQUIRE(eventually([&] { return server.requests_received() > received; }));
  const GaugeSample frozen = *gauge.latest();
  REQUIRE(eventually([&] { return gauge.counters().timeouts >= 3; }));
  CHECK(gauge.latest()->sequence == frozen.sequence);
  CHECK(gauge.latest()->monotonic_ns == frozen.monotonic_ns);
  CHECK(gauge.counters().last_errno == ETIMEDOUT);

  server.set_holding(0, registers_for(5, RegisterType::int32, WordOrder::high_first));
  server.set_behaviour(ServerBehaviour::answer);
  REQUIRE(eventually([&] { return gauge.latest()->raw == 5; }));
  const auto counters = gauge.counters();
  CHECK(counters.reconnects >= 1);  // the port was closed after each timeout and reopened
  CHECK(counters.connected);
  CHECK(gauge.latest()->monotonic_ns > frozen.monotonic_ns);
  CHECK(counters.crc_errors == 0);
}

TEST_CASE("RTU: an answer that comes after its timeout is dropped, never taken for the next request's") {
  RtuTestServer server;
  server.set_holding(0, registers_for(1, RegisterType::int32, WordOrder::high_first));
  auto config = test_config(serial(server.device()), int32_at_zero());
  config.response_timeout = 50ms;
  config.reconnect_backoff_initial = 250ms;  // the late answer (80 ms) lands while the port is closed
  config.reconnect_backoff_max = 250ms;
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == 1; }));

  // Every answer now comes too late, carrying 2. The pty keeps it (as a serial adapter's buffer may) until
  // the gauge has reopened the port; taken then, it would pass for the answer to the next request.
  server.set_holding(0, registers_for(2, RegisterType::int32, WordOrder::high_first));
  server.set_behaviour(ServerBehaviour::late);
  const auto frozen_sequence = gauge.latest()->sequence + 1;  // one answer may still have been on time
  bool late_value_taken = false;
  REQUIRE(eventually(
      [&] {
        late_value_taken = late_value_taken || gauge.latest()->sequence > frozen_sequence;
        return gauge.counters().timeouts >= 3;
      },
      3s));
  CHECK_FALSE(late_value_taken);

  server.set_holding(0, registers_for(3, RegisterType::int32, WordOrder::high_first));
  server.set_behaviour(ServerBehaviour::answer);
  REQUIRE(eventually([&] { return gauge.latest()->raw == 3; }));
  CHECK(gauge.counters().errors == gauge.counters().timeouts);
}

TEST_CASE("RTU: exception responses are counted and keep the port open") {
  RtuTestServer server(1, 4);
  auto map = int32_at_zero();
  map.function = RegisterFunction::input;
  map.address = 3;  // registers 3 and 4: the second is past the end
  auto opened = ModbusGauge::open(test_config(serial(server.device()), map));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.counters().exceptions >= 5; }));
  const auto counters = gauge.counters();
  CHECK(counters.connected);
  CHECK(counters.reconnects == 0);
  CHECK(counters.timeouts == 0);
  CHECK(counters.last_errno == EMBXILADD);
  CHECK_FALSE(gauge.latest());
}

TEST_CASE("RTU: frames with a bad CRC are counted and dropped, the good ones between them are taken") {
  // -123456789 = 0xF8A432EB, high word first.
  BadCrcRtuResponder responder(0xF8A4, 0x32EB);
  auto opened = ModbusGauge::open(test_config(serial(responder.device()), int32_at_zero()));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(
      eventually([&] { return gauge.counters().crc_errors >= 5 && gauge.latest() && gauge.latest()->sequence >= 5; }));
  const auto counters = gauge.counters();
  CHECK(gauge.latest()->raw == -123456789.0);
  CHECK(counters.crc_errors <= responder.corrupted_sent());
  CHECK(counters.crc_errors + 1 >= responder.corrupted_sent());  // one may still be on its way
  CHECK(counters.timeouts == 0);
  CHECK(counters.reconnects == 0);  // a bad frame is noise on a working line, not a lost connection
  CHECK(counters.connected);
  CHECK(counters.errors == counters.crc_errors);  // the noise after each bad frame cost nothing more
}

TEST_CASE("RTU: a device that does not exist is retried with backoff, without a sample or a crash") {
  auto opened = ModbusGauge::open(test_config(serial("/dev/lever-test-no-such-tty")));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.counters().connect_failures >= 2; }));
  CHECK(gauge.counters().last_errno == ENOENT);
  CHECK_FALSE(gauge.counters().connected);
  CHECK_FALSE(gauge.latest());
}
