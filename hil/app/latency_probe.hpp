#pragma once
// `lever-hil serve --latency-probe`: the pair's end-to-end latency, measured from outside the firmware as a
// logic analyser with two probes would, on CLOCK_MONOTONIC (in the kernel rig's virtual time, the guest's).
//
// - Motion: the HSI's encoder lines are moved by one edge (added to what the world drives); the time from that
//   edge's write to the first state the TOP's PWM controller is programmed with after it.
// - Force: the TOP's gauge reads force_base_n, then steps by force_step_n and back (in place of the world's
//   amplifier, whose noise would change the answer on its own); the time from the first Modbus reply carrying a
//   step to the first state the HSI's PWM controller is programmed with after it.
//
// Once both levers are armed the world holds them still, as a bench measurement clamps them, so that the
// stimuli are the only changes they see; a probe fires only when the lever that must answer has been quiet (no
// new PWM state) for quiet_ms, so the first new state after the stimulus is its answer. Needs the kernel rig's PWM
// controllers (lever-pwm-sim), which time-stamp every state they are given.
#include <cstdint>
#include <optional>
#include <vector>

#include "lever/hil/devices/pwm_controller_state.hpp"
#include "serve_probe.hpp"

namespace lever::hil {

struct LatencyProbeOptions {
  std::int64_t interval_ms = 100;  // between probes, alternating motion and force
  std::int64_t quiet_ms = 20;      // the answering lever's PWM unchanged this long before a probe
  std::int64_t timeout_ms = 100;   // no answer within this: counted as missed
  double force_base_n = 1.0;       // the TOP's gauge reads this, or this plus the step
  double force_step_n = 0.5;       // above the force codec's floor and its p of the base
};

class LatencyProbe : public ServeProbe {
 public:
  explicit LatencyProbe(LatencyProbeOptions options = {}) : options_(options) {}

  bool attach(const app::FwConfig& hsi, const app::FwConfig& top, const LeverDevices& hsi_devices,
              const LeverDevices& top_devices) override;
  bool holds_levers() const override { return holding_; }
  std::int64_t hsi_count_offset() const override { return count_offset_; }
  std::optional<double> top_force_n() const override { return force_n_; }
  void top_gauge_set(fw::Tick, std::uint64_t replies_before) override;
  void tick_done(fw::Tick, bool scenario) override;
  // "latency": {"encoder_edge_to_top_pwm_ms": {...}, "gauge_reply_to_hsi_pwm_ms": {...}}, each with n, missed,
  // unresolved, postponed, p50, p99, max (null when none was measured).
  void report(nlohmann::json& report) const override;

 private:
  enum class Kind { motion, force };
  enum class Phase { waiting, fired, stimulus_out };
  struct Series {
    std::vector<double> latencies_ms;
    std::uint64_t missed = 0;      // no answer within timeout_ms
    std::uint64_t unresolved = 0;  // an answer, but when the stimulus left or which state answered is not known
    std::uint64_t postponed = 0;
  };

  static std::int64_t now_ns();
  const devices::PwmControllerState& answering() const { return kind_ == Kind::motion ? *top_pwm_ : *hsi_pwm_; }
  Series& series() { return kind_ == Kind::motion ? motion_ : force_; }
  void fire(std::int64_t now_ns, std::uint64_t applies);
  bool stimulus_out();
  std::optional<double> answer_after_stimulus() const;
  enum class Outcome { measured, missed, unresolved };
  void finish(std::int64_t now_ns, Outcome outcome, double latency_ms = 0.0);

  LatencyProbeOptions options_;
  std::optional<devices::PwmControllerState> hsi_pwm_, top_pwm_;
  const LeverDevices* hsi_ = nullptr;
  const LeverDevices* top_ = nullptr;
  std::int64_t count_offset_ = 0;
  std::optional<double> force_n_;  // from attach()
  Kind kind_ = Kind::motion;
  Phase phase_ = Phase::waiting;
  std::int64_t next_probe_ns_ = 0;
  std::int64_t fired_ns_ = 0;
  std::int64_t stimulus_ns_ = 0;
  std::uint64_t edges_before_ = 0;               // the HSI's encoder edges when the motion probe fired
  std::optional<std::uint64_t> replies_before_;  // the TOP's gauge answers before the force step was in it
  std::uint64_t applies_before_ = 0;             // the answering controller's states when the probe fired
  bool holding_ = false;                         // from the first tick of the scenario
  bool stepped_ = false;                         // the force probe's step is on
  Series motion_, force_;
};

}  // namespace lever::hil
