// GaugeServer with the board's own client, board::ModbusGauge, from the same config: over TCP loopback and
// over its RTU pty (through the symlink at rtu.device), every register type in both word orders.
#include <sys/stat.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include "gauge_test_support.hpp"
#include "gauge_type_cases.hpp"
#include "lever/board/modbus_gauge.hpp"
#include "lever/hil/devices/gauge_server.hpp"

using lever::board::GaugeRegisterMap;
using lever::board::ModbusGauge;
using lever::board::ModbusGaugeConfig;
using lever::board::ModbusRtuEndpoint;
using lever::board::ModbusTcpEndpoint;
using lever::board::RegisterFunction;
using lever::hil::devices::GaugeServer;
using lever::test::eventually;
using lever::test::kTypeCases;

namespace {

constexpr double kScale = 0.5;
constexpr double kOffset = -2.0;

// A temporary directory for the RTU symlink, removed with everything in it.
class TempDir {
 public:
  TempDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/lever-gauge-XXXXXX";
    REQUIRE(::mkdtemp(pattern.data()) != nullptr);
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

GaugeServer open_server(const ModbusGaugeConfig& config) {
  auto server = GaugeServer::open(config);
  if (!server) FAIL(server.error().message);
  return std::move(server).value();
}

ModbusGauge open_gauge(const ModbusGaugeConfig& config) {
  auto gauge = ModbusGauge::open(config);
  if (!gauge) FAIL(gauge.error().message);
  return std::move(gauge).value();
}

// The config both sides read; for TCP the client's is the server's with the port it got.
ModbusGaugeConfig config_for(lever::board::ModbusTransport transport, GaugeRegisterMap map = {}) {
  map.scale = kScale;
  map.offset = kOffset;
  return lever::test::test_config(std::move(transport), map);
}

ModbusGaugeConfig client_config(ModbusGaugeConfig config, const GaugeServer& server) {
  if (auto* tcp = std::get_if<ModbusTcpEndpoint>(&config.transport)) tcp->port = server.port();
  return config;
}

bool reads_near(const ModbusGauge& gauge, double newtons) {
  const auto sample = gauge.latest();
  return sample && std::abs(sample->newtons - newtons) <= kScale;  // one raw unit
}

// The force the world sets for a raw value, off the integer grid by a fraction of a unit.
double force_for(double raw) { return raw * kScale + kOffset + 0.3 * kScale; }

void check_every_type(const lever::board::ModbusTransport& transport) {
  for (const auto& type_case : kTypeCases) {
    for (const RegisterFunction function : {RegisterFunction::holding, RegisterFunction::input}) {
      CAPTURE(static_cast<int>(type_case.type), static_cast<int>(type_case.order), static_cast<int>(function));
      GaugeRegisterMap map;
      map.function = function;
      map.address = 3;
      map.type = type_case.type;
      map.word_order = type_case.order;
      const ModbusGaugeConfig config = config_for(transport, map);
      GaugeServer server = open_server(config);
      INFO(server.description());
      server.set_force(force_for(type_case.first));
      ModbusGauge gauge = open_gauge(client_config(config, server));
      CHECK(eventually([&] { return reads_near(gauge, force_for(type_case.first)); }));
      server.set_force(force_for(type_case.second));
      CHECK(eventually([&] { return reads_near(gauge, force_for(type_case.second)); }));
      CHECK(gauge.counters().errors == 0);
      CHECK(server.counters().replies > 0);
    }
  }
}

}  // namespace

TEST_CASE("TCP: the board's gauge reads the force set, every type and word order, holding and input") {
  check_every_type(ModbusTcpEndpoint{"127.0.0.1", 0, 255});
}

TEST_CASE("RTU: the board's gauge reads the force set through the symlink, every type and word order") {
  TempDir dir;
  check_every_type(ModbusRtuEndpoint{.device = dir.path() + "/gauge", .slave_id = 7});
}

TEST_CASE("TCP on ::1, port 0: the port picked is reported, and the description names it") {
  const ModbusGaugeConfig config = config_for(ModbusTcpEndpoint{"::1", 0, 255});
  GaugeServer server = open_server(config);
  CHECK(server.port() > 0);
  CHECK(server.description() == "Modbus TCP [::1]:" + std::to_string(server.port()) + " unit 255, holding 0 int16");
  server.set_force(10.0);
  ModbusGauge gauge = open_gauge(client_config(config, server));
  CHECK(eventually([&] { return reads_near(gauge, 10.0); }));
}

TEST_CASE("a muted server makes the gauge time out; unmuted, it reads again") {
  for (const bool rtu : {false, true}) {
    CAPTURE(rtu);
    TempDir dir;
    ModbusGaugeConfig config = rtu ? config_for(ModbusRtuEndpoint{.device = dir.path() + "/gauge"})
                                   : config_for(ModbusTcpEndpoint{"127.0.0.1", 0, 255});
    config.response_timeout = std::chrono::milliseconds(30);
    GaugeServer server = open_server(config);
    server.set_force(4.0);
    ModbusGauge gauge = open_gauge(client_config(config, server));
    REQUIRE(eventually([&] { return reads_near(gauge, 4.0); }));
    server.set_muted(true);
    const auto requests = server.counters().requests;
    CHECK(eventually([&] { return gauge.counters().timeouts >= 2; }));
    CHECK(server.counters().requests > requests);  // read, not answered
    server.set_force(6.0);
    CHECK_FALSE(reads_near(gauge, 6.0));
    server.set_muted(false);
    CHECK(eventually([&] { return reads_near(gauge, 6.0); }));
  }
}

TEST_CASE("a second client is served after the first is gone, on TCP and RTU") {
  for (const bool rtu : {false, true}) {
    CAPTURE(rtu);
    TempDir dir;
    const ModbusGaugeConfig config = rtu ? config_for(ModbusRtuEndpoint{.device = dir.path() + "/gauge"})
                                         : config_for(ModbusTcpEndpoint{"127.0.0.1", 0, 255});
    GaugeServer server = open_server(config);
    server.set_force(3.0);
    {
      ModbusGauge first = open_gauge(client_config(config, server));
      REQUIRE(eventually([&] { return reads_near(first, 3.0); }));
    }
    const auto replies = server.counters().replies;
    server.set_force(8.0);
    ModbusGauge second = open_gauge(client_config(config, server));
    CHECK(eventually([&] { return reads_near(second, 8.0); }));
    CHECK(server.counters().replies > replies);
    if (!rtu) CHECK(server.counters().connections == 2);
  }
}

TEST_CASE("TCP: a client that still holds a connection does not lock out a new one") {
  const ModbusGaugeConfig config = config_for(ModbusTcpEndpoint{"127.0.0.1", 0, 255});
  GaugeServer server = open_server(config);
  server.set_force(5.0);
  ModbusGauge first = open_gauge(client_config(config, server));
  REQUIRE(eventually([&] { return reads_near(first, 5.0); }));
  ModbusGauge second = open_gauge(client_config(config, server));
  CHECK(eventually([&] { return reads_near(second, 5.0) && server.counters().connections >= 2; }));
}

TEST_CASE("TCP: a restarted server gets its port back at once") {
  const ModbusGaugeConfig config = config_for(ModbusTcpEndpoint{"127.0.0.1", 0, 255});
  std::optional<GaugeServer> server(open_server(config));
  server->set_force(2.0);
  const ModbusGaugeConfig client = client_config(config, *server);
  ModbusGauge gauge = open_gauge(client);
  REQUIRE(eventually([&] { return reads_near(gauge, 2.0); }));
  server.reset();  // the server closes first: its end of the connection waits in TIME_WAIT on the port
  server.emplace(open_server(client));
  server->set_force(9.0);
  CHECK(eventually([&] { return reads_near(gauge, 9.0); }, std::chrono::milliseconds(5000)));
}

TEST_CASE("a request outside the configured registers gets an exception") {
  GaugeRegisterMap map;
  map.address = 10;
  const ModbusGaugeConfig config = config_for(ModbusTcpEndpoint{"127.0.0.1", 0, 255}, map);
  GaugeServer server = open_server(config);
  ModbusGaugeConfig wrong = client_config(config, server);
  wrong.registers.address = 11;
  ModbusGauge gauge = open_gauge(wrong);
  CHECK(eventually([&] { return gauge.counters().exceptions >= 2; }));
  CHECK_FALSE(gauge.latest().has_value());
  wrong.registers.address = 10;
  wrong.registers.function = RegisterFunction::input;
  ModbusGauge other_table = open_gauge(wrong);
  CHECK(eventually([&] { return other_table.counters().exceptions >= 2; }));
}

TEST_CASE("RTU: the symlink points at the pty, replaces a symlink, refuses a file, goes with the server") {
  TempDir dir;
  const std::string device = dir.path() + "/gauge";
  REQUIRE(::symlink("/nonexistent", device.c_str()) == 0);  // left by a HIL that died
  const ModbusGaugeConfig config = config_for(ModbusRtuEndpoint{.device = device, .slave_id = 3});
  {
    GaugeServer server = open_server(config);
    const auto target = std::filesystem::read_symlink(device).string();
    CHECK(target.rfind("/dev/pts/", 0) == 0);
    CHECK(server.description() == "Modbus RTU " + device + " -> " + target + " slave 3, holding 0 int16");
    CHECK(server.port() == 0);
  }
  CHECK_FALSE(std::filesystem::exists(std::filesystem::symlink_status(device)));

  std::ofstream(device) << "somebody's file\n";
  const auto refused = GaugeServer::open(config);
  REQUIRE_FALSE(refused.ok());
  CHECK(refused.error().message.find(device + " exists and is not a symlink") != std::string::npos);
  CHECK(std::filesystem::is_regular_file(device));
}

TEST_CASE("a config the client could not use is refused, naming the field") {
  ModbusGaugeConfig config = config_for(ModbusTcpEndpoint{"localhost", 0, 255});
  const auto named = GaugeServer::open(config);
  REQUIRE_FALSE(named.ok());
  CHECK(named.error().message.find("gauge server: tcp.host") == 0);
}
