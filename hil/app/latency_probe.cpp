#include "latency_probe.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cmath>

namespace lever::hil {

namespace {

constexpr std::int64_t kNsPerMs = 1'000'000;

// The nearest-rank percentile of sorted values.
double percentile(const std::vector<double>& sorted, double q) {
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(sorted.size())));
  return sorted[std::min(sorted.size(), std::max<std::size_t>(rank, 1)) - 1];
}

// The lever-pwm-sim controller behind a lever's motor, or nullopt after naming why there is none.
std::optional<devices::PwmControllerState> open_controller(const app::FwConfig& config, const char* role) {
  const auto motor = app::motor_config(config.board);
  auto found = devices::PwmControllerState::find(motor.sysfs_root, motor.pwm_chip, motor.pwm_channel);
  if (found && *found) return std::move(*found).value();
  fmt::print(stderr, "lever-hil serve: --latency-probe: the {} motor's pwmchip{} under {}: {}\n", role, motor.pwm_chip,
             motor.sysfs_root,
             found ? found->error().message
                   : "not a PWM controller of the kernel rig (tools/kernel-rig/run-in-guest --pwm-sim)");
  return std::nullopt;
}

}  // namespace

std::int64_t LatencyProbe::now_ns() {
  // steady_clock is CLOCK_MONOTONIC on Linux, the clock of the controllers', the encoder's and the gauge's stamps.
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

bool LatencyProbe::attach(const app::FwConfig& hsi, const app::FwConfig& top, const LeverDevices& hsi_devices,
                          const LeverDevices& top_devices) {
  if (!top_devices.gauge) {
    fmt::print(stderr, "lever-hil serve: --latency-probe: the TOP has no gauge to step\n");
    return false;
  }
  hsi_pwm_ = open_controller(hsi, "HSI");
  top_pwm_ = open_controller(top, "TOP");
  if (!hsi_pwm_ || !top_pwm_) return false;
  hsi_ = &hsi_devices;
  top_ = &top_devices;
  force_n_ = options_.force_base_n;
  return true;
}

void LatencyProbe::top_gauge_set(fw::Tick, std::uint64_t replies_before) {
  // The first gauge setting after a force probe fired is the one that carries its step.
  if (phase_ == Phase::fired && kind_ == Kind::force && !replies_before_) replies_before_ = replies_before;
}

void LatencyProbe::tick_done(fw::Tick, bool scenario) {
  if (!scenario) return;
  holding_ = true;
  const std::int64_t now = now_ns();
  if (next_probe_ns_ == 0) next_probe_ns_ = now + options_.interval_ms * kNsPerMs;
  const auto out = answering().read();
  if (!out) return;
  switch (phase_) {
    case Phase::waiting:
      if (now < next_probe_ns_) return;
      if (now - out->last_apply_ns < options_.quiet_ms * kNsPerMs) {
        ++series().postponed;
        next_probe_ns_ = now + options_.quiet_ms * kNsPerMs / 2;
        return;
      }
      fire(now, out->applies);
      return;
    case Phase::fired:
      if (!stimulus_out()) {
        if (now - fired_ns_ > options_.timeout_ms * kNsPerMs) finish(now, Outcome::missed);
        return;
      }
      phase_ = Phase::stimulus_out;
      [[fallthrough]];
    case Phase::stimulus_out:
      if (stimulus_ns_ == 0) {
        finish(now, Outcome::unresolved);  // when the stimulus left is not known
      } else if (out->applies > applies_before_) {
        const auto latency = answer_after_stimulus();
        finish(now, latency ? Outcome::measured : Outcome::unresolved, latency.value_or(0.0));
      } else if (now - fired_ns_ > options_.timeout_ms * kNsPerMs) {
        finish(now, Outcome::missed);
      }
      return;
  }
}

void LatencyProbe::fire(std::int64_t now_ns, std::uint64_t applies) {
  applies_before_ = applies;
  fired_ns_ = now_ns;
  phase_ = Phase::fired;
  if (kind_ == Kind::motion) {
    edges_before_ = hsi_->encoder->stats().edges;  // hands off: the next edge is the probe's
    count_offset_ = count_offset_ == 0 ? 1 : 0;
  } else {
    replies_before_.reset();
    stepped_ = !stepped_;
    force_n_ = options_.force_base_n + (stepped_ ? options_.force_step_n : 0.0);
  }
}

// The stimulus has left serve: the HSI's line has moved, or the TOP's gauge has answered with the new force.
bool LatencyProbe::stimulus_out() {
  if (kind_ == Kind::motion) {
    const auto stats = hsi_->encoder->stats();
    if (stats.edges <= edges_before_) return false;
    // One edge since: its time is the newest edge's. More (the world moved the lever too): not known, 0.
    stimulus_ns_ = stats.edges == edges_before_ + 1 ? stats.last_edge_ns : 0;
    return true;
  }
  const auto counters = top_->gauge->counters();
  if (!replies_before_ || counters.replies <= *replies_before_) return false;
  // Polled every few milliseconds and looked at every one: one answer since, whose time is the newest's.
  stimulus_ns_ = counters.replies == *replies_before_ + 1 ? counters.last_reply_ns : 0;
  return true;
}

// The first state the answering controller got after the stimulus, from its own log of time-stamped states;
// nothing when that state came before the stimulus was out (the lever moved on its own) or the log moved on.
std::optional<double> LatencyProbe::answer_after_stimulus() const {
  for (const auto& applied : answering().apply_log()) {
    if (applied.number == applies_before_ + 1 && applied.time_ns >= stimulus_ns_) {
      return static_cast<double>(applied.time_ns - stimulus_ns_) / kNsPerMs;
    }
  }
  return std::nullopt;
}

void LatencyProbe::finish(std::int64_t now_ns, Outcome outcome, double latency_ms) {
  switch (outcome) {
    case Outcome::measured:
      series().latencies_ms.push_back(latency_ms);
      break;
    case Outcome::missed:
      ++series().missed;
      break;
    case Outcome::unresolved:
      ++series().unresolved;
      break;
  }
  phase_ = Phase::waiting;
  kind_ = kind_ == Kind::motion ? Kind::force : Kind::motion;
  next_probe_ns_ = std::max(now_ns, fired_ns_ + options_.interval_ms * kNsPerMs);
}

void LatencyProbe::report(nlohmann::json& report) const {
  const auto summary = [](const Series& s) {
    nlohmann::json j{
        {"n", s.latencies_ms.size()}, {"missed", s.missed}, {"unresolved", s.unresolved}, {"postponed", s.postponed}};
    if (s.latencies_ms.empty()) {
      j["p25"] = j["p50"] = j["p99"] = j["max"] = nullptr;
    } else {
      std::vector<double> sorted = s.latencies_ms;
      std::sort(sorted.begin(), sorted.end());
      j["p25"] = percentile(sorted, 0.25);
      j["p50"] = percentile(sorted, 0.50);
      j["p99"] = percentile(sorted, 0.99);
      j["max"] = sorted.back();
    }
    return j;
  };
  report["latency"] = {{"encoder_edge_to_top_pwm_ms", summary(motion_)},
                       {"gauge_reply_to_hsi_pwm_ms", summary(force_)}};
}

}  // namespace lever::hil
