#pragma once
// The safety state machine. Every transition is an explicit method; faults latch and only a re-arm whose
// checks pass clears them.
//
//   init --boot_complete--> disarmed --arm (no fault active)--> armed
//   armed --any fault--> fault            (safe behaviour starts in the same tick)
//   armed|fault --disarm--> disarmed      (latched faults stay latched)
//   fault|disarmed --rearm (no fault active)--> armed, latched faults cleared
#include <cstdint>

#include "lever/fw/faults.hpp"
#include "lever/fw/strain_gauge.hpp"  // Tick
#include "lever/protocol/messages.hpp"

namespace lever::fw {

using protocol::LeverState;

class Supervisor {
 public:
  constexpr LeverState state() const noexcept { return state_; }
  constexpr FaultBits latched() const noexcept { return latched_; }
  constexpr Tick fault_since() const noexcept { return fault_since_; }
  constexpr bool armed() const noexcept { return state_ == LeverState::armed; }

  constexpr void boot_complete() noexcept {
    if (state_ == LeverState::init) state_ = LeverState::disarmed;
  }

  // Faults found active this tick. Latched in any state; they end an armed run at once.
  constexpr void report(FaultBits active, Tick now) noexcept {
    if (active == 0) return;
    latched_ = static_cast<FaultBits>(latched_ | active);
    if (state_ == LeverState::armed) {
      state_ = LeverState::fault;
      fault_since_ = now;
    }
  }

  // Returns whether the command was accepted. `active`: faults whose conditions hold right now.
  constexpr bool arm(FaultBits active) noexcept {
    if (state_ != LeverState::disarmed || latched_ != 0 || active != 0) return false;
    state_ = LeverState::armed;
    return true;
  }

  constexpr bool disarm() noexcept {
    if (state_ != LeverState::armed && state_ != LeverState::fault) return false;
    state_ = LeverState::disarmed;
    return true;
  }

  constexpr bool rearm(FaultBits active) noexcept {
    if (state_ != LeverState::fault && state_ != LeverState::disarmed) return false;
    if (active != 0) return false;
    latched_ = 0;
    state_ = LeverState::armed;
    return true;
  }

 private:
  LeverState state_ = LeverState::init;
  FaultBits latched_ = 0;
  Tick fault_since_ = 0;
};

}  // namespace lever::fw
