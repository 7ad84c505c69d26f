// The Modbus gauge against a libmodbus TCP server on loopback: values, silence, loss and return of the server,
// exceptions, invalid and saturated readings, and how the gauge ends.
#include <modbus.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <memory>
#include <optional>

#include "gauge_test_support.hpp"
#include "gauge_type_cases.hpp"
#include "lever/board/modbus_gauge_presets.hpp"
#include "modbus_test_servers.hpp"

using namespace lever::board;
using namespace lever::test;
using namespace std::chrono_literals;

namespace {

ModbusTcpEndpoint loopback(int port) { return ModbusTcpEndpoint{.host = "127.0.0.1", .port = port, .unit_id = 255}; }

GaugeRegisterMap int32_at_zero() {
  GaugeRegisterMap map;
  map.type = RegisterType::int32;
  return map;
}

void hold_int32(ModbusTestServer& server, double value) {
  server.set_holding(0, registers_for(value, RegisterType::int32, WordOrder::high_first));
}

// A port nothing listens on: one the kernel just handed out, closed again.
int unused_port() { return TcpTestServer().port(); }

}  // namespace

TEST_CASE("TCP: every register type and word order reads the server's value and follows its changes") {
  TcpTestServer server;
  for (const auto& type_case : kTypeCases) {
    for (const auto function : {RegisterFunction::holding, RegisterFunction::input}) {
      INFO("type " << static_cast<int>(type_case.type) << ", word order " << static_cast<int>(type_case.order)
                   << ", function " << static_cast<int>(function));
      check_reads_and_follows(server, loopback(server.port()), type_case, function);
    }
  }
}

TEST_CASE("TCP: over IPv6 loopback too") {
  TcpTestServer server("::1");
  check_reads_and_follows(server, ModbusTcpEndpoint{.host = "::1", .port = server.port(), .unit_id = 1}, kTypeCases[2],
                          RegisterFunction::holding);
}

TEST_CASE(
    "TCP: a server that stops answering leaves the last sample to age, counts timeouts, never holds up "
    "latest(), and when it answers again the gauge reconnects") {
  TcpTestServer server;
  hold_int32(server, 4242);
  auto config = test_config(loopback(server.port()), int32_at_zero());
  config.response_timeout = 500ms;  // long enough to be caught waiting inside one read
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.latest().has_value(); }));

  server.set_behaviour(ServerBehaviour::mute);
  // Once a request arrives after the switch, the gauge waits on an answer that will not come, and every
  // answer before it has been taken: the newest sample is final.
  const auto received = server.requests_received();
  REQUIRE(eventually([&] { return server.requests_received() > received; }));
  const auto timeouts_before = gauge.counters().timeouts;

  // The poll thread is inside modbus_read_registers for the next 500 ms; latest() must answer at once all the
  // same, the first call included.
  const auto start = std::chrono::steady_clock::now();
  const GaugeSample frozen = *gauge.latest();
  constexpr int kCalls = 10'000;
  int same = 0;
  for (int i = 0; i < kCalls; ++i) {
    const auto sample = gauge.latest();
    if (sample && sample->sequence == frozen.sequence && sample->monotonic_ns == frozen.monotonic_ns) ++same;
  }
  const auto spent = std::chrono::steady_clock::now() - start;
  CHECK(same == kCalls);
  CHECK(spent < 100ms);
  CHECK(gauge.counters().timeouts == timeouts_before);  // all those calls fell inside the one stuck read

  // Timeouts pile up (each followed by a reconnect, since the server still accepts), the sample only ages.
  REQUIRE(eventually([&] { return gauge.counters().timeouts >= timeouts_before + 2; }));
  CHECK(gauge.latest()->sequence == frozen.sequence);
  CHECK(gauge.latest()->monotonic_ns == frozen.monotonic_ns);
  CHECK(monotonic_now_ns() - frozen.monotonic_ns > 2 * 500'000'000LL);
  CHECK(gauge.counters().errors >= gauge.counters().timeouts);
  CHECK(gauge.counters().last_errno == ETIMEDOUT);

  server.set_behaviour(ServerBehaviour::answer);
  hold_int32(server, -4242);
  REQUIRE(eventually([&] { return gauge.latest()->raw == -4242; }));
  const auto counters = gauge.counters();
  CHECK(gauge.latest()->sequence > frozen.sequence);
  CHECK(gauge.latest()->monotonic_ns > frozen.monotonic_ns);
  CHECK(counters.reconnects >= 1);
  CHECK(counters.connected);
  CHECK(counters.exceptions == 0);
  CHECK(counters.crc_errors == 0);
}

TEST_CASE("TCP: an answer that comes after its timeout is never taken for the next request's, and reading resumes") {
  TcpTestServer server;
  hold_int32(server, 1);
  auto config = test_config(loopback(server.port()), int32_at_zero());
  config.response_timeout = 50ms;
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == 1; }));

  // Every answer now comes 80 ms after its request, carrying 2: after its request's timeout. On the same
  // connection it would arrive while the next request waits, and every answer after it would be one late.
  hold_int32(server, 2);
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
  // A new connection after each timeout (the newest may still be on its way): the late answer dies with the old.
  CHECK(gauge.counters().reconnects + 1 >= gauge.counters().timeouts);

  hold_int32(server, 3);
  server.set_behaviour(ServerBehaviour::answer);
  REQUIRE(eventually([&] { return gauge.latest()->raw == 3; }));
}

TEST_CASE("TCP: a server that goes away and comes back on the same port is reconnected") {
  auto server = std::make_unique<TcpTestServer>();
  const int port = server->port();
  hold_int32(*server, 100);
  auto opened = ModbusGauge::open(test_config(loopback(port), int32_at_zero()));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == 100; }));
  CHECK(gauge.counters().reconnects == 0);

  server.reset();  // the connection and the listening socket close
  REQUIRE(eventually([&] { return !gauge.counters().connected; }));
  REQUIRE(eventually([&] { return gauge.counters().connect_failures >= 2; }));  // refused while it is away
  const GaugeSample frozen = *gauge.latest();
  CHECK(gauge.counters().last_errno == ECONNREFUSED);

  server = std::make_unique<TcpTestServer>("127.0.0.1", port);
  hold_int32(*server, 200);
  REQUIRE(eventually([&] { return gauge.latest()->raw == 200; }));
  const auto counters = gauge.counters();
  INFO("errors " << counters.errors << ", timeouts " << counters.timeouts << ", connect failures "
                 << counters.connect_failures << ", polls " << counters.polls << ", last errno "
                 << counters.last_errno);
  CHECK(counters.reconnects == 1);
  CHECK(counters.connected);
  CHECK(gauge.latest()->sequence > frozen.sequence);
  CHECK(gauge.latest()->monotonic_ns > frozen.monotonic_ns);
}

TEST_CASE("TCP: a good read resets the backoff, so after a long outage a short one costs only the first wait") {
  auto server = std::make_unique<TcpTestServer>();
  const int port = server->port();
  hold_int32(*server, 1);
  auto config = test_config(loopback(port), int32_at_zero());
  config.reconnect_backoff_initial = 10ms;
  config.reconnect_backoff_max = 400ms;
  auto opened = ModbusGauge::open(config);
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == 1; }));

  // A long outage: the wait doubles 10, 20, 40, ... until it reaches 400 ms.
  server.reset();
  REQUIRE(eventually([&] { return gauge.counters().connect_failures >= 6; }));
  server = std::make_unique<TcpTestServer>("127.0.0.1", port);
  hold_int32(*server, 2);
  REQUIRE(eventually([&] { return gauge.latest()->raw == 2; }));

  // A short one: the reads in between brought the wait back to 10 ms.
  server.reset();
  server = std::make_unique<TcpTestServer>("127.0.0.1", port);
  hold_int32(*server, 3);
  const auto back = std::chrono::steady_clock::now();
  REQUIRE(eventually([&] { return gauge.latest()->raw == 3; }));
  CHECK(std::chrono::steady_clock::now() - back < 200ms);
}

TEST_CASE("TCP: no server at start: the gauge exists, counts failed connects, and connects once one appears") {
  const int port = unused_port();
  auto opened = ModbusGauge::open(test_config(loopback(port), int32_at_zero()));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.counters().connect_failures >= 3; }));
  CHECK_FALSE(gauge.latest());
  CHECK_FALSE(gauge.counters().connected);
  CHECK(gauge.counters().polls == 0);

  TcpTestServer server("127.0.0.1", port);
  hold_int32(server, 7);
  REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == 7; }));
  CHECK(gauge.counters().reconnects == 0);  // the first connection is no reconnect
}

TEST_CASE("TCP: exception responses are counted and keep the connection") {
  TcpTestServer server("127.0.0.1", 0, 4);  // registers 0..3 only
  auto map = int32_at_zero();
  map.address = 10;
  auto opened = ModbusGauge::open(test_config(loopback(server.port()), map));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.counters().exceptions >= 5; }));
  const auto counters = gauge.counters();
  CHECK(counters.connected);
  CHECK(counters.reconnects == 0);
  CHECK(counters.timeouts == 0);
  CHECK(counters.errors >= counters.exceptions);
  CHECK(counters.last_errno == EMBXILADD);
  CHECK_FALSE(gauge.latest());
}

TEST_CASE("TCP: a float32 that is not a number is an invalid reading, never a sample") {
  TcpTestServer server;
  GaugeRegisterMap map;
  map.function = RegisterFunction::input;
  map.type = RegisterType::float32;
  const std::vector<std::uint16_t> quiet_nan{0x7FC0, 0x0000};
  const std::vector<std::uint16_t> infinity{0x7F80, 0x0000};
  server.set_input(0, quiet_nan);
  auto opened = ModbusGauge::open(test_config(loopback(server.port()), map));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  REQUIRE(eventually([&] { return gauge.counters().invalid_values >= 3; }));
  CHECK_FALSE(gauge.latest());

  server.set_input(0, registers_for(2.5, RegisterType::float32, WordOrder::high_first));
  REQUIRE(eventually([&] { return gauge.latest().has_value(); }));
  const GaugeSample good = *gauge.latest();
  CHECK(good.raw == 2.5);

  const auto invalid_before = gauge.counters().invalid_values;
  server.set_input(0, infinity);
  REQUIRE(eventually([&] { return gauge.counters().invalid_values >= invalid_before + 3; }));
  // The newest sample is still the good one (none came after the infinity), aging.
  CHECK(gauge.latest()->raw == 2.5);
  CHECK(gauge.latest()->sequence <= good.sequence + 1);
  CHECK(gauge.counters().errors >= gauge.counters().invalid_values);
  CHECK(gauge.counters().connected);
}

TEST_CASE("TCP: a reading at or beyond a saturation bound is flagged") {
  TcpTestServer server;
  GaugeRegisterMap map;  // int16
  map.saturation_raw_min = -30000;
  map.saturation_raw_max = 30000;
  auto opened = ModbusGauge::open(test_config(loopback(server.port()), map));
  REQUIRE(opened.ok());
  const ModbusGauge& gauge = opened.value();
  auto reads = [&](double raw, bool saturated) {
    server.set_holding(0, registers_for(raw, RegisterType::int16, WordOrder::high_first));
    REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == raw; }));
    CHECK(gauge.latest()->saturated == saturated);
  };
  reads(29999, false);
  reads(30000, true);
  reads(-29999, false);
  reads(-32768, true);
  reads(0, false);
}

TEST_CASE("TCP: each preset flags the amplifier's range end, the load cell's capacity, as saturated") {
  TcpTestServer server;
  SECTION("int32 gross weight in grams: +-5098 g is 50 N") {
    auto config = preset_gross_weight_int32(loopback(server.port()));
    config.response_timeout = 1s;
    auto opened = ModbusGauge::open(config);
    REQUIRE(opened.ok());
    const ModbusGauge& gauge = opened.value();
    auto reads = [&](double raw, bool saturated) {
      server.set_holding(0, registers_for(raw, RegisterType::int32, WordOrder::high_first));
      REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == raw; }));
      CHECK(gauge.latest()->saturated == saturated);
    };
    reads(5097, false);
    reads(5098, true);
    reads(-5097, false);
    reads(-5098, true);
    reads(20000, true);
  }
  SECTION("float32 force in newtons: +-50 N") {
    auto config = preset_force_float32(loopback(server.port()));
    config.response_timeout = 1s;
    auto opened = ModbusGauge::open(config);
    REQUIRE(opened.ok());
    const ModbusGauge& gauge = opened.value();
    auto reads = [&](double raw, bool saturated) {
      server.set_input(0, registers_for(raw, RegisterType::float32, WordOrder::high_first));
      REQUIRE(eventually([&] { return gauge.latest() && gauge.latest()->raw == raw; }));
      CHECK(gauge.latest()->saturated == saturated);
    };
    reads(49.5, false);
    reads(50.0, true);
    reads(-49.5, false);
    reads(-50.0, true);
  }
}

// What each section tells apart is a destructor that ends by itself from one that waits out a reconnect backoff (5 s
// here): the bound is half the backoff, past which only the wait explains the time. A tighter bound would time the
// machine's scheduling, which is a benchmark's business, not a test's.
TEST_CASE("TCP: the destructor ends at once between reads and within a response timeout during one") {
  constexpr auto kBackoff = 5s;
  SECTION("waiting out a reconnect backoff") {
    auto config = test_config(loopback(unused_port()), int32_at_zero());
    config.reconnect_backoff_initial = kBackoff;
    config.reconnect_backoff_max = 2 * kBackoff;
    std::optional<ModbusGauge> gauge(ModbusGauge::open(config).value());
    REQUIRE(eventually([&] { return gauge->counters().connect_failures >= 1; }));
    const auto start = std::chrono::steady_clock::now();
    gauge.reset();
    CHECK(std::chrono::steady_clock::now() - start < kBackoff / 2);
  }
  SECTION("inside a read the server will not answer") {
    TcpTestServer server;
    server.set_behaviour(ServerBehaviour::mute);
    auto config = test_config(loopback(server.port()), int32_at_zero());
    config.response_timeout = 300ms;
    // A destructor that let the failed read reconnect would wait this out after it.
    config.reconnect_backoff_initial = kBackoff;
    config.reconnect_backoff_max = 2 * kBackoff;
    std::optional<ModbusGauge> gauge(ModbusGauge::open(config).value());
    REQUIRE(eventually([&] { return server.requests_received() >= 1; }));
    const auto start = std::chrono::steady_clock::now();
    gauge.reset();
    CHECK(std::chrono::steady_clock::now() - start < config.response_timeout + kBackoff / 2);
  }
}

TEST_CASE("TCP: a moved gauge keeps polling, and open() refuses a config it cannot use, naming the field") {
  TcpTestServer server;
  hold_int32(server, 11);
  auto opened = ModbusGauge::open(test_config(loopback(server.port()), int32_at_zero()));
  REQUIRE(opened.ok());
  ModbusGauge moved(std::move(opened).value());
  REQUIRE(eventually([&] { return moved.latest() && moved.latest()->raw == 11; }));

  TcpTestServer other;
  hold_int32(other, 22);
  auto second = ModbusGauge::open(test_config(loopback(other.port()), int32_at_zero()));
  REQUIRE(second.ok());
  moved = std::move(second).value();  // the first gauge's thread ends, the second's goes on
  REQUIRE(eventually([&] { return moved.latest() && moved.latest()->raw == 22; }));
  hold_int32(other, 33);
  REQUIRE(eventually([&] { return moved.latest()->raw == 33; }));

  auto config = test_config(loopback(0), int32_at_zero());
  const auto refused = ModbusGauge::open(config);
  REQUIRE_FALSE(refused.ok());
  CHECK_THAT(refused.error().message, Catch::Matchers::Contains("tcp.port"));
  CHECK(refused.error().errno_value == EINVAL);
}
