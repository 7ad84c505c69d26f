#pragma once
// The strain-gauge amplifier over Modbus (RTU or TCP), polled in its own thread and handed to the real-time
// loop without locks. Modbus cannot keep up with a 1 kHz loop (RTU at 115200 baud manages roughly 100-200
// reads/s), so the loop takes whatever reading is newest and judges its age from the timestamp.
//
// Connecting is the poll thread's job, not the factory's: an amplifier that boots after the board, or a cable
// pulled and plugged back, is a stale force the firmware core already knows how to handle, not a reason for
// the board not to start. So open() fails only on a config it cannot use; the thread then connects, and
// reconnects with backoff for as long as the gauge lives. counters() says whether it is connected and why not.
#include <cstdint>
#include <memory>
#include <optional>
#include <thread>

#include "lever/board/modbus_gauge_config.hpp"
#include "lever/board/result.hpp"

namespace lever::board {

// One good reading. Failed reads produce none: the loop sees the previous sample grow old.
struct GaugeSample {
  double newtons = 0.0;           // raw * scale + offset
  double raw = 0.0;               // the register value as the amplifier sent it
  std::int64_t monotonic_ns = 0;  // CLOCK_MONOTONIC when the response had arrived
  std::uint64_t sequence = 0;     // 1 for the first sample, +1 for each one after
  bool saturated = false;         // raw at or beyond a configured saturation bound
};

struct GaugeCounters {
  std::uint64_t polls = 0;             // read requests made
  std::uint64_t errors = 0;            // every failure: the kinds below, failed connects and invalid values
  std::uint64_t timeouts = 0;          // no complete response within response_timeout
  std::uint64_t crc_errors = 0;        // RTU frames with a bad CRC
  std::uint64_t exceptions = 0;        // Modbus exception responses (illegal address, device busy, ...)
  std::uint64_t invalid_values = 0;    // responses whose value is not a number (float32 NaN or infinity)
  std::uint64_t connect_failures = 0;  // connection attempts that failed (refused, no such device, ...)
  std::uint64_t reconnects = 0;        // successful connections after the first
  bool connected = false;
  int last_errno = 0;  // of the newest failed libmodbus call; modbus_strerror() turns it into text
};

class ModbusGauge {
 public:
  // Validates the config and creates the Modbus context, then starts polling. Fails only on the config.
  static Result<ModbusGauge> open(const ModbusGaugeConfig& config);

  ModbusGauge(ModbusGauge&& other) noexcept;
  ModbusGauge& operator=(ModbusGauge&& other) noexcept;
  ModbusGauge(const ModbusGauge&) = delete;
  ModbusGauge& operator=(const ModbusGauge&) = delete;
  // Stops the poll thread and joins it: at once between reads, within one response_timeout during one.
  ~ModbusGauge();

  // The newest good reading; empty before the first. Never blocks, allocates or calls into libmodbus: the 1 kHz
  // loop calls it every tick. Safe from any thread.
  std::optional<GaugeSample> latest() const noexcept;

  // CLOCK_MONOTONIC when the newest failed poll or connect attempt ended; 0 before the first. A failure newer
  // than latest()'s sample means the newest attempt failed: the board runner hands it to the core as a
  // ForceReading with `error` set. Never blocks; safe from any thread.
  std::int64_t newest_failure_ns() const noexcept;

  // A snapshot for logs and tests; each field is exact, the set is not taken atomically.
  GaugeCounters counters() const noexcept;

  const ModbusGaugeConfig& config() const noexcept;

 private:
  struct Shared;
  explicit ModbusGauge(std::unique_ptr<Shared> shared);
  void stop() noexcept;

  // The thread uses `shared_`, so that member must outlive it; stop() joins before `shared_` is released.
  std::unique_ptr<Shared> shared_;
  std::jthread poller_;
};

}  // namespace lever::board
