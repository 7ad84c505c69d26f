// validate(): each problem names its field; the defaults and both presets are valid.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <string>

#include "lever/board/modbus_gauge_config.hpp"
#include "lever/board/modbus_gauge_presets.hpp"

using namespace lever::board;
using namespace std::chrono_literals;

namespace {

ModbusGaugeConfig rtu_config() {
  ModbusGaugeConfig config;
  config.transport = ModbusRtuEndpoint{};
  return config;
}

// The message, or "" when validate() accepted the config.
std::string problem(const ModbusGaugeConfig& config) { return validate(config).value_or(""); }

std::string problem_with_tcp(void (*change)(ModbusTcpEndpoint&)) {
  ModbusGaugeConfig config;
  change(std::get<ModbusTcpEndpoint>(config.transport));
  return problem(config);
}

std::string problem_with_rtu(void (*change)(ModbusRtuEndpoint&)) {
  ModbusGaugeConfig config = rtu_config();
  change(std::get<ModbusRtuEndpoint>(config.transport));
  return problem(config);
}

std::string problem_with_map(void (*change)(GaugeRegisterMap&)) {
  ModbusGaugeConfig config;
  change(config.registers);
  return problem(config);
}

using Catch::Matchers::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInfinity = std::numeric_limits<double>::infinity();

}  // namespace

TEST_CASE("the defaults are valid, over TCP and over RTU, with the documented values") {
  const ModbusGaugeConfig config;
  CHECK(problem(config).empty());
  CHECK(problem(rtu_config()).empty());
  CHECK(config.poll_period == 5ms);
  CHECK(config.response_timeout == 10ms);
  CHECK(config.reconnect_backoff_initial == 10ms);
  CHECK(config.reconnect_backoff_max == 2s);
}

TEST_CASE("the longest gap between readings: a period, a timeout per missed poll and the answer's, RTU's quiet wait") {
  ModbusGaugeConfig tcp;
  CHECK(longest_gap(tcp, 0) == 15ms);  // 5 + 10: no poll missed, the answer at the last moment
  CHECK(longest_gap(tcp, 1) == 35ms);  // + a timeout and a connect bounded by it
  CHECK(longest_gap(tcp, 3) == 75ms);
  auto rtu = rtu_config();
  rtu.reconnect_backoff_initial = 30ms;
  CHECK(longest_gap(rtu, 1) == 55ms);  // + a timeout and the 30 ms a late answer gets to land on a closed port
}

TEST_CASE("both presets are valid and read the documented registers") {
  const auto weight = preset_gross_weight_int32(ModbusTcpEndpoint{});
  CHECK(problem(weight).empty());
  CHECK(weight.registers.function == RegisterFunction::holding);
  CHECK(weight.registers.address == 0);
  CHECK(weight.registers.type == RegisterType::int32);
  CHECK(weight.registers.word_order == WordOrder::high_first);
  CHECK(weight.registers.scale == Approx(9.80665e-3));
  // The testbed's 50 N load cell in grams: the amplifier's maximum output, whole counts.
  CHECK(*weight.registers.saturation_raw_max == 5098.0);
  CHECK(*weight.registers.saturation_raw_min == -5098.0);

  const auto force = preset_force_float32(ModbusRtuEndpoint{}, 2.0);
  CHECK(problem(force).empty());
  CHECK(std::holds_alternative<ModbusRtuEndpoint>(force.transport));
  CHECK(force.registers.function == RegisterFunction::input);
  CHECK(force.registers.type == RegisterType::float32);
  CHECK(force.registers.scale == 2.0);
  CHECK(force.poll_period == 5ms);
  CHECK(*force.registers.saturation_raw_max == 25.0);  // 50 N at 2 N per unit
  CHECK(*force.registers.saturation_raw_min == -25.0);
  CHECK(*preset_force_float32(ModbusTcpEndpoint{}).registers.saturation_raw_max == 50.0);
  CHECK(*preset_gross_weight_int32(ModbusTcpEndpoint{}, 0.01, 200.0).registers.saturation_raw_max == 20000.0);
}

TEST_CASE("a saturation bound the register type cannot reach is refused: it would never flag anything") {
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) {
               m.type = RegisterType::int32;
               m.saturation_raw_max = 1e15;
             }),
             StartsWith("registers.saturation_raw_max: 1e+15 is above the highest value"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.saturation_raw_min = -40000; }),  // int16
             StartsWith("registers.saturation_raw_min: -40000 is below the lowest value"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) {
               m.type = RegisterType::uint16;
               m.saturation_raw_max = 65536;
             }),
             StartsWith("registers.saturation_raw_max:"));
  // The ends themselves are reachable.
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.saturation_raw_min = -32768; }).empty());
  CHECK(problem_with_map([](GaugeRegisterMap& m) {
          m.type = RegisterType::uint16;
          m.saturation_raw_min = 0;
          m.saturation_raw_max = 65535;
        }).empty());
}

TEST_CASE("TCP endpoint problems name their field") {
  CHECK_THAT(problem_with_tcp([](ModbusTcpEndpoint& t) { t.host = "amplifier.local"; }), StartsWith("tcp.host:"));
  CHECK_THAT(problem_with_tcp([](ModbusTcpEndpoint& t) { t.host = ""; }), StartsWith("tcp.host:"));
  CHECK(problem_with_tcp([](ModbusTcpEndpoint& t) { t.host = "::1"; }).empty());
  CHECK(problem_with_tcp([](ModbusTcpEndpoint& t) { t.host = "192.168.0.20"; }).empty());
  CHECK_THAT(problem_with_tcp([](ModbusTcpEndpoint& t) { t.port = 0; }), StartsWith("tcp.port:"));
  CHECK_THAT(problem_with_tcp([](ModbusTcpEndpoint& t) { t.port = 65536; }), StartsWith("tcp.port:"));
  CHECK_THAT(problem_with_tcp([](ModbusTcpEndpoint& t) { t.unit_id = 248; }), StartsWith("tcp.unit_id:"));
  CHECK_THAT(problem_with_tcp([](ModbusTcpEndpoint& t) { t.unit_id = -1; }), StartsWith("tcp.unit_id:"));
  CHECK(problem_with_tcp([](ModbusTcpEndpoint& t) { t.unit_id = 0; }).empty());
  CHECK(problem_with_tcp([](ModbusTcpEndpoint& t) { t.unit_id = 247; }).empty());
}

TEST_CASE("RTU endpoint problems name their field") {
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.device = ""; }), StartsWith("rtu.device:"));
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.baud = 12345; }),
             StartsWith("rtu.baud:") && Catch::Matchers::Contains("not a standard rate"));
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.baud = 0; }), StartsWith("rtu.baud:"));
  CHECK(problem_with_rtu([](ModbusRtuEndpoint& r) { r.baud = 9600; }).empty());
  CHECK(problem_with_rtu([](ModbusRtuEndpoint& r) { r.baud = 921600; }).empty());
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.parity = static_cast<Parity>('X'); }),
             StartsWith("rtu.parity:"));
  CHECK(problem_with_rtu([](ModbusRtuEndpoint& r) { r.parity = Parity::even; }).empty());
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.data_bits = 7; }), StartsWith("rtu.data_bits:"));
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.stop_bits = 3; }), StartsWith("rtu.stop_bits:"));
  CHECK(problem_with_rtu([](ModbusRtuEndpoint& r) { r.stop_bits = 2; }).empty());
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.slave_id = 0; }), StartsWith("rtu.slave_id:"));
  CHECK_THAT(problem_with_rtu([](ModbusRtuEndpoint& r) { r.slave_id = 248; }), StartsWith("rtu.slave_id:"));
}

TEST_CASE("register map problems name their field") {
  // Each names the values the type's own table holds (kAllRegisterTypes and name(), beside the type).
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.function = static_cast<RegisterFunction>(7); }) ==
        "registers.function: must be holding or input");
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.type = static_cast<RegisterType>(9); }) ==
        "registers.type: must be int16, uint16, int32, uint32 or float32");
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.word_order = static_cast<WordOrder>(2); }) ==
        "registers.word_order: must be high_first or low_first");
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.address = -1; }), StartsWith("registers.address:"));
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.address = 65535; }).empty());  // one int16
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) {
               m.address = 65535;
               m.type = RegisterType::float32;
             }),
             StartsWith("registers.address:"));  // two registers do not fit
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.scale = kNaN; }),
             StartsWith("registers.scale:") && Catch::Matchers::Contains("nan"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.scale = kInfinity; }), StartsWith("registers.scale:"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.scale = 0.0; }), StartsWith("registers.scale:"));
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.scale = -0.01; }).empty());  // a gauge mounted reversed
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.offset = kNaN; }), StartsWith("registers.offset:"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.saturation_raw_min = kNaN; }),
             StartsWith("registers.saturation_raw_min:"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) { m.saturation_raw_max = kNaN; }),
             StartsWith("registers.saturation_raw_max:"));
  CHECK_THAT(problem_with_map([](GaugeRegisterMap& m) {
               m.saturation_raw_min = 10;
               m.saturation_raw_max = 10;
             }),
             StartsWith("registers.saturation_raw_min:"));
  CHECK(problem_with_map([](GaugeRegisterMap& m) { m.saturation_raw_max = 30000; }).empty());  // one bound alone
}

TEST_CASE("timing problems name their field") {
  auto with = [](auto change) {
    ModbusGaugeConfig config;
    change(config);
    return problem(config);
  };
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.poll_period = 0us; }), StartsWith("poll_period:"));
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.poll_period = 11s; }), StartsWith("poll_period:"));
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.response_timeout = 0us; }), StartsWith("response_timeout:"));
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.response_timeout = 2s; }), StartsWith("response_timeout:"));
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.reconnect_backoff_initial = 0ms; }),
             StartsWith("reconnect_backoff_initial:"));
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.reconnect_backoff_initial = 3s; }),
             StartsWith("reconnect_backoff_initial:"));  // above the maximum
  CHECK_THAT(with([](ModbusGaugeConfig& c) { c.reconnect_backoff_max = 61s; }), StartsWith("reconnect_backoff_max:"));
}

TEST_CASE("register_count: one register for 16-bit types, two for 32-bit ones") {
  CHECK(register_count(RegisterType::int16) == 1);
  CHECK(register_count(RegisterType::uint16) == 1);
  CHECK(register_count(RegisterType::int32) == 2);
  CHECK(register_count(RegisterType::uint32) == 2);
  CHECK(register_count(RegisterType::float32) == 2);
}
