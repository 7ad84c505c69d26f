#include "lever/board/modbus_gauge.hpp"

#include <pthread.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <span>
#include <string>
#include <system_error>
#include <utility>
#include <variant>

#include "lever/board/latest_value.hpp"
#include "lever/board/modbus_failure.hpp"
#include "lever/board/modbus_register_decode.hpp"
#include "lever/board/monotonic_clock.hpp"
#include "modbus_context.hpp"

namespace lever::board {
namespace {

using Clock = std::chrono::steady_clock;

bool is_saturated(double raw, const GaugeRegisterMap& map) noexcept {
  return (map.saturation_raw_min && raw <= *map.saturation_raw_min) ||
         (map.saturation_raw_max && raw >= *map.saturation_raw_max);
}

void bump(std::atomic<std::uint64_t>& counter) noexcept { counter.fetch_add(1, std::memory_order_relaxed); }

}  // namespace

// Everything the poll thread touches lives here, on the heap, so the gauge object itself can move.
struct ModbusGauge::Shared {
  Shared(const ModbusGaugeConfig& gauge_config, ModbusContext modbus_context)
      : config(gauge_config), context(std::move(modbus_context)) {}

  void run(const std::stop_token& stop);
  bool connect();
  void poll_once();
  void record_failure(int errno_value) noexcept;
  bool back_off(const std::stop_token& stop);
  bool sleep_until(const std::stop_token& stop, Clock::time_point deadline);

  const ModbusGaugeConfig config;
  ModbusContext context;  // the poll thread's alone once it runs

  LatestValue<GaugeSample> latest;
  std::uint64_t published = 0;  // poll thread only

  std::atomic<std::uint64_t> polls{0};
  std::atomic<std::uint64_t> errors{0};
  std::atomic<std::uint64_t> timeouts{0};
  std::atomic<std::uint64_t> crc_errors{0};
  std::atomic<std::uint64_t> exceptions{0};
  std::atomic<std::uint64_t> invalid_values{0};
  std::atomic<std::uint64_t> connect_failures{0};
  std::atomic<std::uint64_t> reconnects{0};
  std::atomic<bool> connected{false};
  std::atomic<int> last_errno{0};
  std::atomic<std::int64_t> newest_failure_ns{0};  // CLOCK_MONOTONIC of the newest failed poll or connect

  // Poll thread only: the pacing and backoff state.
  const bool tcp = std::holds_alternative<ModbusTcpEndpoint>(config.transport);
  std::chrono::milliseconds backoff{config.reconnect_backoff_initial};
  bool waited_since_success = false;  // TCP reconnects at once after a success, and backs off from then on
  bool ever_connected = false;
  Clock::time_point next_poll{};

  // Sleeps wait on this, so a stop request ends them at once instead of after a period or a backoff.
  std::mutex sleep_mutex;
  std::condition_variable_any wake;
};

void ModbusGauge::Shared::run(const std::stop_token& stop) {
  while (!stop.stop_requested()) {
    if (!connected.load(std::memory_order_relaxed)) {
      if (!connect()) {
        if (!back_off(stop)) return;
        continue;
      }
      next_poll = Clock::now();
    }
    if (!sleep_until(stop, next_poll)) return;
    next_poll += std::chrono::duration_cast<Clock::duration>(config.poll_period);
    poll_once();
    if (!connected.load(std::memory_order_relaxed)) {
      if (!back_off(stop)) return;
      continue;
    }
    // A response slower than the period: poll again now rather than in a burst that catches up on the past.
    next_poll = std::max(next_poll, Clock::now());
  }
}

bool ModbusGauge::Shared::connect() {
  if (modbus_connect(context.get()) == -1) {
    record_failure(errno);
    bump(connect_failures);
    modbus_close(context.get());
    return false;
  }
  // Bytes an earlier connection left queued (a late answer in a tty's buffer) would be taken for our answer.
  modbus_flush(context.get());
  if (ever_connected) bump(reconnects);
  ever_connected = true;
  connected.store(true, std::memory_order_relaxed);
  return true;
}

void ModbusGauge::Shared::poll_once() {
  const GaugeRegisterMap& map = config.registers;
  const int count = register_count(map.type);
  std::array<std::uint16_t, 2> words{};
  bump(polls);
  const int got = map.function == RegisterFunction::holding
                      ? modbus_read_registers(context.get(), map.address, count, words.data())
                      : modbus_read_input_registers(context.get(), map.address, count, words.data());
  const std::int64_t arrived_ns = monotonic_ns();
  if (got != count) {
    const int errno_value = got == -1 ? errno : EMBBADDATA;
    record_failure(errno_value);
    const ModbusFailure failure = classify_modbus_errno(errno_value);
    if (failure == ModbusFailure::timeout) bump(timeouts);
    if (failure == ModbusFailure::bad_crc) bump(crc_errors);
    if (failure == ModbusFailure::exception) bump(exceptions);
    if (needs_reconnect(failure)) {
      modbus_close(context.get());
      connected.store(false, std::memory_order_relaxed);
    } else if (failure != ModbusFailure::exception) {
      modbus_flush(context.get());  // the rest of a garbled or late frame must not become the start of the next
    }
    return;
  }
  // The device answered: whatever went wrong before is over.
  backoff = config.reconnect_backoff_initial;
  waited_since_success = false;
  const std::optional<double> raw = decode_registers(
      std::span<const std::uint16_t>(words.data(), static_cast<std::size_t>(count)), map.type, map.word_order);
  if (!raw) {
    bump(errors);
    bump(invalid_values);
    return;
  }
  latest.publish(GaugeSample{
      .newtons = *raw * map.scale + map.offset,
      .raw = *raw,
      .monotonic_ns = arrived_ns,
      .sequence = ++published,
      .saturated = is_saturated(*raw, map),
  });
}

void ModbusGauge::Shared::record_failure(int errno_value) noexcept {
  bump(errors);
  last_errno.store(errno_value, std::memory_order_relaxed);
  newest_failure_ns.store(monotonic_ns(), std::memory_order_release);
}

bool ModbusGauge::Shared::back_off(const std::stop_token& stop) {
  // A TCP connection lost after good reads is reconnected at once: a missed poll costs only its timeout and a
  // connect (longest_gap). The waits are for a server that stays away.
  if (tcp && !waited_since_success) {
    waited_since_success = true;
    return !stop.stop_requested();
  }
  waited_since_success = true;
  const bool running = sleep_until(stop, Clock::now() + backoff);
  backoff = std::min(backoff * 2, config.reconnect_backoff_max);
  return running;
}

bool ModbusGauge::Shared::sleep_until(const std::stop_token& stop, Clock::time_point deadline) {
  std::unique_lock lock(sleep_mutex);
  wake.wait_until(lock, stop, deadline, [] { return false; });
  return !stop.stop_requested();
}

Result<ModbusGauge> ModbusGauge::open(const ModbusGaugeConfig& config) {
  if (auto problem = validate(config)) return Error{"modbus gauge: " + *problem, EINVAL};
  auto context = make_modbus_context(config);
  if (!context) return context.error();
  try {
    return ModbusGauge(std::make_unique<Shared>(config, std::move(context).value()));
  } catch (const std::system_error& failure) {  // std::jthread's way to say the thread could not start
    return Error{std::string("modbus gauge: cannot start the poll thread: ") + failure.what(), failure.code().value()};
  }
}

ModbusGauge::ModbusGauge(std::unique_ptr<Shared> shared)
    : shared_(std::move(shared)), poller_([state = shared_.get()](std::stop_token stop) { state->run(stop); }) {
  // Visible in top and gdb; at most 15 characters.
  ::pthread_setname_np(poller_.native_handle(), "lever-gauge");
}

ModbusGauge::ModbusGauge(ModbusGauge&& other) noexcept = default;

ModbusGauge& ModbusGauge::operator=(ModbusGauge&& other) noexcept {
  if (this != &other) {
    stop();  // our thread must be gone before the state it uses is released below
    poller_ = std::move(other.poller_);
    shared_ = std::move(other.shared_);
  }
  return *this;
}

ModbusGauge::~ModbusGauge() { stop(); }

void ModbusGauge::stop() noexcept {
  if (poller_.joinable()) {
    poller_.request_stop();
    poller_.join();
  }
}

std::optional<GaugeSample> ModbusGauge::latest() const noexcept { return shared_->latest.load(); }

std::int64_t ModbusGauge::newest_failure_ns() const noexcept {
  return shared_->newest_failure_ns.load(std::memory_order_acquire);
}

GaugeCounters ModbusGauge::counters() const noexcept {
  const Shared& s = *shared_;
  constexpr auto relaxed = std::memory_order_relaxed;
  return GaugeCounters{
      .polls = s.polls.load(relaxed),
      .errors = s.errors.load(relaxed),
      .timeouts = s.timeouts.load(relaxed),
      .crc_errors = s.crc_errors.load(relaxed),
      .exceptions = s.exceptions.load(relaxed),
      .invalid_values = s.invalid_values.load(relaxed),
      .connect_failures = s.connect_failures.load(relaxed),
      .reconnects = s.reconnects.load(relaxed),
      .connected = s.connected.load(relaxed),
      .last_errno = s.last_errno.load(relaxed),
  };
}

const ModbusGaugeConfig& ModbusGauge::config() const noexcept { return shared_->config; }

}  // namespace lever::board
