#pragma once
// How to reach a weighing amplifier over Modbus and how to read its force register. A plain struct a config
// file parser fills in; validate() says what is wrong before anything is opened.
#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

namespace lever::board {

// Modbus TCP. The host must be a numeric IPv4 or IPv6 address: a name would need a resolver, which can block
// the poll thread (and so the gauge's destructor) for seconds when the network is down.
struct ModbusTcpEndpoint {
  std::string host = "127.0.0.1";
  int port = 502;     // 1..65535
  int unit_id = 255;  // 0..247 or 255; 255 addresses the device itself, 1..247 a gateway's serial slave
};

// Modbus RTU uses 8 data bits; the field exists so a config file can state it and be checked.
enum class Parity : char { none = 'N', even = 'E', odd = 'O' };
inline constexpr Parity kAllParities[] = {Parity::none, Parity::even, Parity::odd};
constexpr std::string_view name(Parity p) { return p == Parity::none ? "none" : p == Parity::even ? "even" : "odd"; }

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
inline constexpr RegisterFunction kAllRegisterFunctions[] = {RegisterFunction::holding, RegisterFunction::input};
constexpr std::string_view name(RegisterFunction f) { return f == RegisterFunction::holding ? "holding" : "input"; }

enum class RegisterType : std::uint8_t { int16, uint16, int32, uint32, float32 };
inline constexpr RegisterType kAllRegisterTypes[] = {RegisterType::int16, RegisterType::uint16, RegisterType::int32,
                                                     RegisterType::uint32, RegisterType::float32};
// A switch with no default: a new type fails the build until it has its name.
constexpr std::string_view name(RegisterType t) {
  switch (t) {
    case RegisterType::int16:
      return "int16";
    case RegisterType::uint16:
      return "uint16";
    case RegisterType::int32:
      return "int32";
    case RegisterType::uint32:
      return "uint32";
    case RegisterType::float32:
      return "float32";
  }
  return "?";
}

// Which register of a 32-bit pair holds the more significant 16 bits. The bytes inside one register are
// always big-endian (the Modbus wire order), so only the word order varies between devices.
enum class WordOrder : std::uint8_t {
  high_first,  // "ABCD": the lower address holds the high word
  low_first,   // "CDAB": the lower address holds the low word
};
inline constexpr WordOrder kAllWordOrders[] = {WordOrder::high_first, WordOrder::low_first};
constexpr std::string_view name(WordOrder w) { return w == WordOrder::high_first ? "high_first" : "low_first"; }

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
  // destructor can wait for a read in progress, and a TCP connect. 10 ms: an RTU exchange at 115200 baud
  // takes 1.5 ms on the wire, a LAN well under 1 ms; the rest is the amplifier's.
  std::chrono::microseconds response_timeout{10'000};
  // After a failure that costs the connection (a timeout, a lost link): reconnect, waiting this long first,
  // doubled while it keeps failing up to the maximum; a successful read resets it. TCP's first reconnect after
  // a good read is at once (a new connection cannot carry a late answer; the wait is for a server that stays
  // away); RTU's first reopen waits, so that an answer later than the timeout lands while the port is closed
  // and is flushed, never taken for the next request's. Initial 1 ms..max; max up to 60 s.
  std::chrono::milliseconds reconnect_backoff_initial{10};
  std::chrono::milliseconds reconnect_backoff_max{2'000};
};

// The longest time between two readings when `missed_polls` polls in a row fail and the next one answers:
// a poll begins at most a period after the reading before it; each failed attempt ends within the response
// timeout (a timeout; a reset or refused connection fails sooner), and is followed by the reconnect: on TCP a
// connect at once, which libmodbus bounds by the response timeout; on RTU a wait of reconnect_backoff_initial
// and a reopen of the port; the answer comes within the response timeout:
//   poll_period + (missed_polls + 1) x response_timeout + missed_polls x reconnect
//   reconnect = response_timeout (TCP) or reconnect_backoff_initial (RTU)
// A staleness window longer than this outlasts `missed_polls` failed polls (docs/modbus-gauge.md, "Timing").
std::chrono::microseconds longest_gap(const ModbusGaugeConfig& config, int missed_polls);

// The register types' value ranges, as decode_registers() returns them.
double lowest_value(RegisterType type) noexcept;
double highest_value(RegisterType type) noexcept;

// Registers one value of `type` occupies (1 or 2).
int register_count(RegisterType type) noexcept;

// The first problem found, as "field: problem" (e.g. "rtu.baud: 12345 is not a standard rate"); empty when
// the config is usable.
std::optional<std::string> validate(const ModbusGaugeConfig& config);

}  // namespace lever::board
