#pragma once
// The safety state machine. Every transition is an explicit method; faults latch and only a re-arm whose
// checks pass clears them (docs/can-protocol.md, "What clears a fault").
//
//   init --boot_complete--> disarmed --arm (no fault active or latched)--> armed
//   disarmed --home (no fault active)--> homing --found--> disarmed
//   armed|homing --any fault--> fault     (safe behaviour starts in the same tick)
//   armed|fault|homing --disarm--> disarmed (latched faults stay latched)
//   fault|disarmed --rearm (no fault active)--> armed, latched faults cleared
// A lever in fault leaves it only by an explicit disarm (the host has seen the fault; the faults stay latched)
// or re-arm (the host clears them): a home meant for another lever must not set a faulted one moving.
// Position validity is the lever's to check before arm and rearm (an unhomed lever may not arm).
#include <cstdint>

#include "lever/fw/tick.hpp"
#include "lever/protocol/faults.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

using protocol::bit;
using protocol::Fault;
using protocol::FaultBits;
using protocol::has;
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

  // Faults found active this tick. Latched in any state; they end an armed run or a homing at once.
  constexpr void report(FaultBits active, Tick now) noexcept {
    if (active == 0) return;
    latched_ = static_cast<FaultBits>(latched_ | active);
    if (state_ == LeverState::armed || state_ == LeverState::homing) {
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
    if (state_ != LeverState::armed && state_ != LeverState::fault && state_ != LeverState::homing) return false;
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

  // Homing drives the motor, so it starts only from disarmed (never straight out of fault, whose safe
  // behaviour only a disarm or a re-arm ends), and only while none of the faults that would stop it holds;
  // latched faults stay latched (a re-arm clears them).
  constexpr bool home(FaultBits active) noexcept {
    if (state_ != LeverState::disarmed) return false;
    if (active != 0) return false;
    state_ = LeverState::homing;
    return true;
  }

  constexpr void homing_done() noexcept {
    if (state_ == LeverState::homing) state_ = LeverState::disarmed;
  }

 private:
  LeverState state_ = LeverState::init;
  FaultBits latched_ = 0;
  Tick fault_since_ = 0;
};

}  // namespace lever::fw
