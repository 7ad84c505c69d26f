#include "lever/app/board_runner.hpp"

#include <fmt/format.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <optional>
#include <stop_token>
#include <thread>

#include "lever/app/gauge_port.hpp"
#include "lever/app/motor_state.hpp"
#include "lever/app/stats_line.hpp"
#include "lever/board/board_can_port.hpp"
#include "lever/board/gpio_encoder.hpp"
#include "lever/board/kernel_preemption.hpp"
#include "lever/board/latest_value.hpp"
#include "lever/board/loop_watchdog.hpp"
#include "lever/board/modbus_gauge.hpp"
#include "lever/board/motor_guard.hpp"
#include "lever/board/motor_stop_signals.hpp"
#include "lever/board/pwm_motor.hpp"
#include "lever/board/realtime_loop.hpp"
#include "lever/fw/lever.hpp"
#include "lever/program/text.hpp"

namespace lever::app {
namespace {

constexpr int kRuntimeFailure = 1;

struct BoardHal : fw::Ports<board::GpioEncoder, GaugePort, board::PwmMotor, board::BoardCanPort> {
  std::uint64_t monotonic_ns() const { return static_cast<std::uint64_t>(board::monotonic_ns()); }
};
static_assert(fw::LeverHal<BoardHal>);
static_assert(fw::HasStepClock<BoardHal>);

// What the printing thread shows of the loop itself, taken by the loop (its statistics are its own to read).
struct LoopSample {
  double p50_us = 0, p99_us = 0, max_us = 0;
  double step_p50_us = 0, step_p99_us = 0, step_max_us = 0;
  long minor_faults = 0;  // of the loop's thread since the loop started
};

long thread_minor_faults() noexcept {
  rusage usage{};
  return getrusage(RUSAGE_THREAD, &usage) == 0 ? usage.ru_minflt : 0;
}

template <typename T>
std::optional<T> opened(board::Result<T>&& r, std::string_view what) {
  if (!r) {
    fmt::print(stderr, "lever-fw: cannot open the {}: {}\n", what, program::printable(r.error().message, 400));
    return std::nullopt;
  }
  return std::move(r).value();
}

template <typename Role>
int run_lever(const FwConfig& config, BoardHal& hal, std::optional<board::ModbusGauge>& gauge, board::MotorGuard& guard,
              bool json_lines, const std::atomic<bool>& stop_flag) {
  // The watchdog's thread and the printer start before the loop raises this thread to SCHED_FIFO with
  // SCHED_RESET_ON_FORK: started after, they would run SCHED_OTHER; started now they keep the service's own
  // scheduling (FIFO 50 in lever-fw@.service), below the loop, ahead of ordinary load.
  auto watchdog = board::LoopWatchdog::open(config.board.watchdog);
  if (!watchdog) {
    fmt::print(stderr, "lever-fw: {}\n", program::printable(watchdog.error().message, 400));
    return kRuntimeFailure;
  }
  fmt::print(stderr, "lever-fw: {}\n", watchdog.value().description());

  // The loop publishes a snapshot every 100 ms; this thread prints one a second, so the loop never formats,
  // allocates or writes to a pipe that might block.
  board::LatestValue<Snapshot> latest;
  board::LatestValue<LoopSample> loop_sample;
  std::jthread printer([&](std::stop_token token) {
    while (!token.stop_requested()) {
      for (int i = 0; i < 10 && !token.stop_requested(); ++i)
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const auto s = latest.load();
      if (!s) continue;
      BoardStats b;
      if (const auto l = loop_sample.load()) {
        b.wakeup_p50_us = l->p50_us;
        b.wakeup_p99_us = l->p99_us;
        b.wakeup_max_us = l->max_us;
        b.step_p50_us = l->step_p50_us;
        b.step_p99_us = l->step_p99_us;
        b.step_max_us = l->step_max_us;
        b.minor_faults = static_cast<std::uint64_t>(l->minor_faults);
      }
      if (gauge) {
        const auto c = gauge->counters();
        b.modbus_polls = c.polls;
        b.modbus_errors = c.errors;
        b.modbus_timeouts = c.timeouts;
        b.modbus_crc_errors = c.crc_errors;
        b.modbus_exceptions = c.exceptions;
        b.modbus_reconnects = c.reconnects;
      }
      const auto line = stats_json(*s, b);
      if (json_lines) {
        fmt::print("{}\n", line.dump());
      } else {
        fmt::print("{} {} position {:+.4f} rad{} torque {:+.3f} N m faults {}\n", line["role"].get<std::string>(),
                   line["state"].get<std::string>(), s->position_rad, s->position_valid ? "" : " (not homed)",
                   s->torque_nm, line["faults"].dump());
      }
      std::fflush(stdout);
    }
  });

  // Under the unit /proc/cmdline is hidden (ProcSubset=pid) and the model may be unknown: its ExecStartPre says it
  // then, unsandboxed (--kernel-check). Only a model known to be voluntary is worth a word here.
  if (config.board.realtime.fifo_priority > 0) {
    const auto sources = board::read_kernel_preemption_sources();
    if (board::preemption_of(sources) == board::Preemption::voluntary)
      fmt::print(stderr, "lever-fw: {}\n", board::describe(sources));
  }
  auto loop_result = board::RealtimeLoop::open(realtime_config(config.board));
  if (!loop_result) {
    fmt::print(stderr, "lever-fw: cannot set up the real-time loop: {}\n", loop_result.error().message);
    return kRuntimeFailure;
  }
  auto& loop = loop_result.value();
  if (!loop.privileged()) fmt::print(stderr, "lever-fw: warning: {}\n", loop.warning());
  fw::Lever<BoardHal, Role> lever(hal, config.lever);

  std::stop_source stop;
  long faults_at_start = -1;
  loop.run(
      [&](fw::Tick now) {
        if (stop_flag.load(std::memory_order_relaxed) || board::stop_signal_received() != 0 ||
            board::MotorGuard::lost()) {
          stop.request_stop();
        }
        // The guard stopped the motor while this loop did not step: the hardware no longer holds what the motor
        // last wrote (the step itself finds the gap and latches TIMING).
        if (guard.take_trip()) hal.motor_.note_external_stop();
        hal.force_.now_tick = now;
        hal.force_.now_ns = board::monotonic_ns();
        lever.step(now);
        watchdog.value().advanced(now);  // after the step: only a step that ended feeds the watchdogs
        guard.stepped(hal.force_.now_ns);
        if (now % 100 == 0) latest.publish(snapshot(lever, now));
        if (now % 1000 == 0) {  // once a second: a histogram walk and one system call
          const long faults = thread_minor_faults();
          if (faults_at_start < 0) faults_at_start = faults;
          const auto us = [](std::uint64_t v) { return static_cast<double>(v); };
          const auto& h = loop.stats().wake_latency;
          const auto& d = loop.stats().step_duration;
          loop_sample.publish({us(h.percentile_us(0.50)), us(h.percentile_us(0.99)), us(h.max_us()),
                               us(d.percentile_us(0.50)), us(d.percentile_us(0.99)), us(d.max_us()),
                               faults - faults_at_start});
        }
      },
      stop.get_token());
  guard.loop_ended();  // what follows takes longer than its deadline, and is not the loop
  printer.request_stop();
  hal.motor_.command({0.0, false});  // the safe state before the objects go (their destructors stop it again)
  watchdog.value().stop();
  if (board::MotorGuard::lost()) {
    // Restarted by the service manager (exit 1), the lever comes back with a guard of its own.
    fmt::print(stderr, "lever-fw: the motor guard (pid {}) ended: motor stopped; exit 1\n", guard.pid());
    return kRuntimeFailure;
  }
  fmt::print(stderr, "lever-fw: stopped; motor at zero torque and disabled\n");
  return 0;
}

}  // namespace

int run_board(const FwConfig& config, bool json_lines, const std::string& motor_state, const std::atomic<bool>& stop) {
  // Before anything is opened: however this run ends, --motor-off finds the motor named.
  if (!motor_state.empty()) {
    if (const auto error = write_motor_state(motor_state, config); !error.empty()) {
      fmt::print(stderr, "lever-fw: the motor state for --motor-off: {}\n", error);
      return kRuntimeFailure;
    }
  }
  // The motor first, and its guard with it: from here on, whatever happens to this process stops the motor.
  auto motor = opened(board::PwmMotor::open(motor_config(config.board)), "motor");
  if (!motor) return kRuntimeFailure;
  if (auto installed = board::install_motor_stop_signal_handlers(); !installed) {
    fmt::print(stderr, "lever-fw: cannot install the signal handlers: {}\n", installed.error().message);
    return kRuntimeFailure;
  }
  board::MotorGuardConfig guard_config;
  // One above the loop: a loop spinning at its own priority on a single CPU cannot starve its guard.
  if (config.board.realtime.fifo_priority > 0) {
    guard_config.fifo_priority = std::min(config.board.realtime.fifo_priority + 1, 99);
  }
  auto guard = opened(board::MotorGuard::start(guard_config, motor->guard_handles()), "motor guard");
  if (!guard) return kRuntimeFailure;
  fmt::print(stderr, "lever-fw: {}\n", guard->description());
  auto encoder = opened(board::GpioEncoder::open(config.board.encoder), "encoder");
  if (!encoder) return kRuntimeFailure;
  std::optional<board::ModbusGauge> gauge;
  const bool uses_gauge =
      config.lever.role == protocol::Role::top || (config.lever.use_force_sensor && config.lever.display.closed_loop);
  if (uses_gauge) {
    gauge = opened(board::ModbusGauge::open(gauge_config(config.board)), "strain gauge");
    if (!gauge) return kRuntimeFailure;
  }
  auto can = opened(board::BoardCanPort::open(can_config(config)), "CAN port");
  if (!can) return kRuntimeFailure;
  BoardHal hal{{std::move(*encoder), GaugePort{gauge ? &*gauge : nullptr}, std::move(*motor), std::move(*can)}};
  fmt::print(stderr, "lever-fw: {} lever, pair {}, on {}: encoder {}, motor {}\n",
             config.lever.role == protocol::Role::hsi ? "HSI" : "TOP", config.lever.pair, config.board.can.interface,
             hal.encoder_.description(), hal.motor_.description());
  return config.lever.role == protocol::Role::hsi
             ? run_lever<fw::HsiRole>(config, hal, gauge, *guard, json_lines, stop)
             : run_lever<fw::TopRole>(config, hal, gauge, *guard, json_lines, stop);
}

}  // namespace lever::app
