#include "serve.hpp"

#include <fmt/format.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <optional>

#include "bus_watch.hpp"
#include "lever/program/exit_codes.hpp"
#include "lever/program/output_file.hpp"
#include "report.hpp"
#include "serve_devices.hpp"
#include "serve_metrics.hpp"
#include "serve_pair.hpp"
#include "serve_report.hpp"
#include "serve_world.hpp"
#include "wall_clock_pacer.hpp"

namespace lever::hil {
namespace {

using Clock = WallClockPacer::Clock;
// A lever heard within this is alive; lever-fw's heartbeat period is 25 ms by default, and the guest's
// emulated clock stretches it.
constexpr std::int64_t kHeardWindowMs = 250;

// The tick loop: the wall clock, the buses watched, the world stepped, the scenario measured and traced.
class ServeLoop {
 public:
  ServeLoop(const ServeOptions& o, const SimConfig& sim, ServeWorld& world, LeverDevices& hsi, LeverDevices& top,
            BusWatch& watch, program::OutputFile* trace, ServeProbe* probe)
      : o_(o), world_(world), hsi_(hsi), top_(top), watch_(watch), trace_(trace), probe_(probe), metrics_(sim) {}

  // Until the scenario's duration or `stop`; false when the levers were not armed within the arm timeout.
  bool run(const std::atomic<bool>& stop);
  ServeSummary finish(const SimConfig& sim) const;
  const ServeMetrics& metrics() const { return metrics_; }

 private:
  PairHeard hear() const;
  bool await_arming(const PairHeard& heard);
  bool measure(const PairHeard& heard, const ServeTick& s, std::uint64_t motion_sent, std::uint64_t force_sent);

  const ServeOptions& o_;
  ServeWorld& world_;
  LeverDevices &hsi_, &top_;
  BusWatch& watch_;
  program::OutputFile* trace_;
  ServeProbe* probe_;
  ServeMetrics metrics_;
  WallClockPacer pacer_;
  fw::Tick tick_ = 0;
  std::optional<fw::Tick> scenario_start_;
  double homed_at_s_ = 0.0;
};

// SIGUSR1 stops the TOP's gauge server, SIGUSR2 starts it again: a fault a test injects from outside, as it
// would pull an amplifier's cable.
std::atomic<int> g_gauge_signal{0};
extern "C" void on_gauge_signal(int signal) { g_gauge_signal.store(signal, std::memory_order_relaxed); }

bool ServeLoop::run(const std::atomic<bool>& stop) {
  while (!stop.load(std::memory_order_relaxed)) {
    ++tick_;
    pacer_.wait();
    if (const int signal = g_gauge_signal.exchange(0, std::memory_order_relaxed)) {
      if (signal == SIGUSR1) top_.stop_gauge();
      if (signal == SIGUSR2 && !top_.start_gauge()) return false;
      // Stamped once the server is closed and its thread joined, a reply in flight sent: the fault's own moment,
      // from which a test times the TOP's response (serve, an ordinary process, takes the signal a tick or more
      // after it was sent).
      const auto stamp_ns =
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch());
      fmt::print(stderr, "lever-hil serve: the TOP's gauge {} (CLOCK_MONOTONIC {} ns)\n",
                 top_.gauge ? "serves again" : "stopped", stamp_ns.count());
    }
    watch_.poll(static_cast<std::int64_t>(tick_));
    const PairHeard heard = hear();
    if (!scenario_start_ && !await_arming(heard)) return false;
    const ServeTick s = world_.step(tick_, !heard.hsi_homing, hsi_, top_, probe_);
    // Frames sent before the scenario (homing, arming) are not the scenario's: taken every tick, counted in it.
    const auto motion_sent = watch_.take_motion_frames();
    const auto force_sent = watch_.take_force_frames();
    const bool done = scenario_start_ && measure(heard, s, motion_sent, force_sent);
    if (probe_) probe_->tick_done(tick_, scenario_start_.has_value());
    if (done) break;
  }
  return true;
}

PairHeard ServeLoop::hear() const {
  const auto now_ms = static_cast<std::int64_t>(tick_);
  PairHeard h;
  h.hsi = watch_.heard_within(watch_.hsi(), now_ms, kHeardWindowMs);
  h.top = watch_.heard_within(watch_.top(), now_ms, kHeardWindowMs);
  h.both_armed = h.hsi && h.top && watch_.hsi().armed() && watch_.top().armed();
  h.hsi_homing = h.hsi && watch_.hsi().heartbeat->state == protocol::LeverState::homing;
  return h;
}

// Before the scenario: it starts once both levers are armed, and the operator takes the handle then.
bool ServeLoop::await_arming(const PairHeard& heard) {
  if (heard.both_armed) {
    scenario_start_ = tick_;
    world_.reseed_noise(o_.seed);
    homed_at_s_ = std::chrono::duration<double>(Clock::now() - pacer_.start()).count();
    if (!o_.hands_off) world_.start_operator(tick_);
    fmt::print(stderr, "lever-hil serve: both levers armed after {:.1f} s; {}\n", homed_at_s_,
               o_.hands_off ? "hands off" : "the operator takes the handle");
  } else if (Clock::now() - pacer_.start() > std::chrono::duration<double>(o_.arm_timeout_s)) {
    fmt::print(stderr, "lever-hil serve: the levers were not armed within {} s (HSI {}, TOP {})\n", o_.arm_timeout_s,
               state_name(watch_.hsi()), state_name(watch_.top()));
    return false;
  }
  return true;
}

// One scenario tick measured and traced; true once the scenario's duration is served.
bool ServeLoop::measure(const PairHeard& heard, const ServeTick& s, std::uint64_t motion_sent,
                        std::uint64_t force_sent) {
  const fw::Tick t_ticks = tick_ - *scenario_start_;
  const double t = static_cast<double>(t_ticks) * 1e-3;
  const double displayed = watch_.force_at_hsi().value_or(0.0);
  metrics_.step(heard, s, world_.world(), motion_sent, force_sent, displayed);
  if (trace_)
    trace_->write(trace_csv_row(serve_trace_row(t, world_.world(), watch_, s, displayed, motion_sent, force_sent)));
  if (t_ticks % 1000 == 0)
    print_status_line(t, watch_, world_.world(), s, displayed, metrics_.run(), pacer_.max_lag_ms());
  const auto scenario_ticks = static_cast<fw::Tick>(std::llround(o_.duration_s * 1000.0));
  return scenario_ticks > 0 && t_ticks >= scenario_ticks;
}

ServeSummary ServeLoop::finish(const SimConfig& sim) const {
  ServeSummary s{sim,
                 {},
                 pacer_.slips(),
                 pacer_.max_lag_ms(),
                 hsi_.encoder->stats(),
                 top_.encoder->stats(),
                 top_.gauge_requests(),
                 watch_.frames_read()};
  metrics_.finish(s.result);
  s.result.homed_at_s = homed_at_s_;
  s.result.wall_time_s = std::chrono::duration<double>(Clock::now() - pacer_.start()).count();
  const double scenario_s = scenario_start_ ? static_cast<double>(tick_ - *scenario_start_) * 1e-3 : 0.0;
  s.result.realtime_factor = s.result.wall_time_s > 0 ? (homed_at_s_ + scenario_s) / s.result.wall_time_s : 0.0;
  s.sim.duration_s = scenario_s;
  return s;
}

void print_powered_up(const ServeWorld& world, const ServePair& pair) {
  const auto& hsi_can = pair.hsi.board.can.interface;
  const auto& top_can = pair.top.board.can.interface;
  fmt::print(stderr,
             "lever-hil serve: levers powered up at {:+.3f} rad (HSI) and {:+.3f} rad (TOP); waiting for both to be "
             "armed on {}{}\n",
             world.hsi_angle(), world.top_angle(), hsi_can, hsi_can == top_can ? "" : " and " + top_can);
}

}  // namespace

int run_serve(const ServeOptions& o, const std::atomic<bool>& stop, ServeProbe* probe) {
  const auto pair = load_serve_pair(o);
  if (!pair) return program::kBadInput;
  // Checked before any device is opened. Written as the run goes and renamed into place when it ends (by its
  // duration or a signal).
  std::optional<program::OutputFile> trace;
  if (!o.trace.empty()) {
    trace.emplace(o.trace, "--trace");
    trace->write(trace_csv_header());
  }
  const SimConfig sim = serve_sim_config(o, *pair);
  ServeWorld world(sim, o.seed);
  auto hsi = open_devices(pair->hsi, world.hsi_angle(), o.max_edge_rate_hz);
  if (!hsi) return program::kRuntimeFailure;
  auto top = open_devices(pair->top, world.top_angle(), o.max_edge_rate_hz);
  if (!top) return program::kRuntimeFailure;
  auto watch = BusWatch::open(pair->hsi.board.can.interface, pair->top.board.can.interface, pair->hsi.lever.pair);
  if (!watch) {
    fmt::print(stderr, "lever-hil serve: cannot watch the CAN bus: {}\n", watch.error().message);
    return program::kRuntimeFailure;
  }
  if (probe && !probe->attach(pair->hsi, pair->top, *hsi, *top)) return program::kRuntimeFailure;
  std::signal(SIGUSR1, on_gauge_signal);
  std::signal(SIGUSR2, on_gauge_signal);
  print_powered_up(world, *pair);

  ServeLoop loop(o, sim, world, *hsi, *top, watch.value(), trace ? &*trace : nullptr, probe);
  if (!loop.run(stop)) return program::kRuntimeFailure;
  if (trace) trace->commit();
  print_serve_report(o, loop.finish(sim), loop.metrics(), probe, trace && trace->is_stdout() ? stderr : stdout);
  return 0;
}

}  // namespace lever::hil
