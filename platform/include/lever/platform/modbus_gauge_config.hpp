#pragma once
// How to reach a weighing amplifier over Modbus and how to read its force register. A plain struct a config
// file parser fills in; validate() says what is wrong before anything is opened.
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>

namespace lever::platform {

// Modbus TCP. The host must be a numeric IPv4 or IPv6 address: a name would need a resolver, which can block
// the poll thread (and so the gauge's destructor) for seconds when the network is down.
struct ModbusTcpEndpoint {
  std::string host = "127.0.0.1";
  int port = 502;     // 1..65535
  int unit_id = 255;  // 0..247 or 255; 255 addresses the device itself, 1..247 a gateway's serial slave
};

// Modbus RTU uses 8 data bits; the field exists so a config file can state it and be checked.
enum class Parity : char { none = 'N', even = 'E', odd = 'O' };

struct ModbusRtuEndpoint {
  std::string device = "/dev/ttyUSB0";
  int baud = 115200;  // one of the standard rates, 1200..921600
  Parity parity = Parity::none;
  int data_bits = 8;  // RTU frames carry whole bytes: must be 8
  int stop_bits = 1;  // 1 or 2 (the Modbus spec asks for 2 without parity; many amplifiers use 1)
  int slave_id = 1;   // 1..247; 0 is broadcast, which no device answers
};

using ModbusTransport = std::variant<ModbusTcpEndpoint, ModbusRtuEndpoint>;

enum class RegisterFunction : std::uint8_t {
  holding,  // function code 3
  input,    // function code 4
};

enum class RegisterType : std::uint8_t { int16, uint16, int32, uint32, float32 };

// Which register of a 32-bit pair holds the more significant 16 bits. The bytes inside one register are
// always big-endian (the Modbus wire order), so only the word order varies between devices.
enum class WordOrder : std::uint8_t {
  high_first,  // "ABCD": the lower address holds the high word
  low_first,   // "CDAB": the lower address holds the low word
};

// Where the force is and how to turn it into newtons: newtons = raw * scale + offset.
struct GaugeRegisterMap {
  RegisterFunction function = RegisterFunction::holding;
  int address = 0;  // protocol address, 0-based (a manual's "40001" is holding register 0)
  RegisterType type = RegisterType::int16;
  WordOrder word_order = WordOrder::high_first;  // ignored for 16-bit types
  double scale = 1.0;                            // newtons per raw unit; finite, non-zero
  double offset = 0.0;                           // newtons; finite
  // A raw value at or beyond either bound is flagged saturated (the amplifier's range end or overload code).
  std::optional<double> saturation_raw_min = std::nullopt;
  std::optional<double> saturation_raw_max = std::nullopt;
};

struct ModbusGaugeConfig {
  ModbusTransport transport = ModbusTcpEndpoint{};
  GaugeRegisterMap registers;
  // One read request per period (default 5 ms: up to 200 reads/s); 100 us..10 s.
  std::chrono::microseconds poll_period{5'000};
  // How long a whole response may take, first byte to last; 1 ms..1 s. It also bounds how long the gauge's
  // destructor can wait for a read in progress.
  std::chrono::microseconds response_timeout{20'000};
  // After a lost connection: wait, reconnect, and double the wait up to the maximum while it keeps failing.
  // A successful read resets it. Initial 1 ms..max; max up to 60 s.
  std::chrono::milliseconds reconnect_backoff_initial{50};
  std::chrono::milliseconds reconnect_backoff_max{2'000};
};

// Registers one value of `type` occupies (1 or 2).
int register_count(RegisterType type) noexcept;

// The first problem found, as "field: problem" (e.g. "rtu.baud: 12345 is not a standard rate"); empty when
// the config is usable.
std::optional<std::string> validate(const ModbusGaugeConfig& config);

}  // namespace lever::platform
