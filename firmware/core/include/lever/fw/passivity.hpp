#pragma once
// Time-domain passivity (Ryu and Hannaford; the energy-based, per-port form of IEEE 1918.1.1's kinesthetic
// codec) at one end of the link: the observer integrates the energy flowing in and out of this lever's port of
// the communication channel, the peer's input energy arrives in energy frames, and the controller scales the
// port's output (the displayed force at the HSI, the commanded velocity at the TOP) so that the energy this port
// has put out never exceeds what the peer has put in. docs/firmware.md, "Passivity under delay".
//
// Bounded cost: a handful of multiplications per tick, no loop, no heap.
#include <cstdint>
#include <optional>

#include "lever/fw/tick.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

// Stable names (config, command line): off sends and observes nothing; observe runs the observer and sends
// energy frames but never acts (to measure what the channel does); tdpa also acts.
enum class PassivityMode : std::uint8_t { off, observe, tdpa };

inline constexpr PassivityMode kAllPassivityModes[] = {PassivityMode::off, PassivityMode::observe, PassivityMode::tdpa};
constexpr const char* name(PassivityMode m) noexcept {
  return m == PassivityMode::tdpa ? "tdpa" : m == PassivityMode::observe ? "observe" : "off";
}

struct PassivityConfig {
  PassivityMode mode = PassivityMode::off;
  // TOP: the rate (1/s) at which the passive reference is pulled toward the HSI's position that rides on every
  // motion frame; in contact no further past the lever than the motor can press (top_role.hpp). It closes the gap
  // a contact leaves; 10/s closes it within half a second for few extra contact onsets (docs/firmware.md,
  // "Position drift").
  double drift_gain_per_s = 10.0;
  // Of its own input energy, the port keeps up to this much for its own output instead of passing it to the peer
  // (0: the literature's per-port TDPA). tau_max^2 / (2 k_p), what the TOP's position spring holds at the torque
  // limit: the most a press against a stiff wall stores (docs/firmware.md, "Local reserve").
  double reserve_j = 0.0125;
  // Of each joule the port takes in, the share that may go to its reserve while it has room; the rest goes to the
  // peer at once. Filling the reserve first (1) starved the peer of a hand's push; the value is measured
  // (docs/firmware.md, "Reserve share").
  double reserve_share = 0.8;
  // HSI: the display spends what its port holds at most at (held energy) / (this time), so that the displayed force
  // fades as the hand yields instead of switching whole on the sign of its velocity. 40 ms is the hand's time
  // constant on the lever (docs/hil-model.md); 0 spends at once (the literature's controller). The TOP always
  // spends at once: its impact on the wall needs its reserve within milliseconds (docs/firmware.md).
  double display_spend_time_s = 0.040;
};

constexpr bool is_valid(const PassivityConfig& c) noexcept {
  return c.mode <= PassivityMode::tdpa && c.drift_gain_per_s >= 0.0 && c.drift_gain_per_s < 1000.0 &&
         c.reserve_j >= 0.0 && c.reserve_j < 1000.0 && c.reserve_share >= 0.0 && c.reserve_share <= 1.0 &&
         c.display_spend_time_s >= 0.0 && c.display_spend_time_s <= 10.0;
}

// The peer's input energy as received: only ever grows within an epoch (protocol/messages.hpp, EnergyMessage).
class ReceivedEnergy {
 public:
  // Returns true when the frame began a new epoch (the peer armed again): the caller restarts its own output.
  constexpr bool accept(const protocol::EnergyMessage& m) noexcept {
    if (!started_ || static_cast<std::int8_t>(static_cast<std::uint8_t>(m.epoch - epoch_)) > 0) {
      const bool renewed = started_;
      started_ = true;
      epoch_ = m.epoch;
      last_ = m.energy;
      // The first frame after this lever armed, or of a new epoch, is the baseline: the peer's energy before
      // it belongs to an account this lever no longer keeps, so counting it would be the optimistic side.
      energy_j_ = 0.0;
      return renewed;
    }
    if (m.epoch != epoch_) return false;  // older epoch
    const auto delta = static_cast<std::uint32_t>(m.energy - last_);
    if (delta >= (1u << 31)) return false;  // older than a frame already used
    last_ = m.energy;
    energy_j_ += static_cast<double>(delta) * protocol::kEnergyLsbJ;
    return false;
  }
  constexpr void reset() noexcept { *this = {}; }
  constexpr double energy_j() const noexcept { return energy_j_; }

 private:
  bool started_ = false;
  std::uint8_t epoch_ = 0;
  std::uint32_t last_ = 0;
  double energy_j_ = 0.0;
};

class PassivityPort {
 public:
  struct State {
    double input_j = 0.0;       // into the channel through this port, since arming
    double output_j = 0.0;      // out of the channel through this port, after the controller
    double received_j = 0.0;    // what the peer port passed to this one, as received
    double passed_j = 0.0;      // of input_j, what this port passed to the peer (all of it but the reserve)
    double kept_j = 0.0;        // of input_j, what the port holds for its own output: at most the reserve
    double dissipated_j = 0.0;  // what the controller took out
    // received + input - passed - output: the energy this port may still put out. Kept at or above zero by
    // tdpa at both ports, the channel's own energy (both inputs less both outputs) is too: each port puts out
    // or passes on only what came in through it or from the peer, and the peer passed only what it had.
    double observed_j = 0.0;
    double scale = 1.0;  // this tick's factor on the port's output
  };

  constexpr PassivityPort() noexcept : PassivityPort(PassivityConfig{}) {}
  explicit constexpr PassivityPort(const PassivityConfig& c) noexcept : config_(c) {}
  constexpr const PassivityConfig& config() const noexcept { return config_; }
  constexpr const State& state() const noexcept { return state_; }
  constexpr bool enabled() const noexcept { return config_.mode != PassivityMode::off; }
  constexpr bool acts() const noexcept { return config_.mode == PassivityMode::tdpa; }

  // This lever armed: a new epoch of its own account, and the peer's energy counts from its next frame.
  constexpr void on_armed() noexcept {
    state_ = {};
    received_.reset();
    ++epoch_;
    sent_code_ = 0;
    sent_any_ = false;
  }

  constexpr void receive(const protocol::EnergyMessage& m) noexcept {
    if (!enabled()) return;
    if (received_.accept(m)) {
      // The peer armed again: its input counts from zero, and so does what this port put out against it.
      state_.output_j = 0.0;
    }
    state_.received_j = received_.energy_j();
    state_.observed_j = available();
  }

  // out_w: the power this tick's output would carry out of the channel into this lever's side (negative: the
  // lever's side pushes energy in). Returns the factor in [0, 1] on the port's output (the force or velocity
  // whose product with its conjugate gave out_w): 1 unless the output would exceed the peer's input energy.
  // spend_time_s > dt: this tick may spend at most dt / spend_time_s of what the port holds (an exponential
  // drain, never more than the hard cut allows, so the bound on the channel's energy is unchanged).
  constexpr double limit(double out_w, double dt, double spend_time_s = 0.0) noexcept {
    state_.scale = 1.0;
    if (!enabled() || !(out_w == out_w)) return 1.0;
    const double requested = out_w * dt;
    if (requested <= 0.0) {
      take_in(-requested);
    } else {
      const double held = available();
      const double budget = spend_time_s > dt ? held * (dt / spend_time_s) : held;
      double allowed = requested;
      if (acts() && requested > budget) {
        allowed = budget > 0.0 ? budget : 0.0;
        state_.scale = allowed / requested;
        state_.dissipated_j += requested - allowed;
      }
      state_.output_j += allowed;
      // The port's own kept input goes first, so the peer's energy waits for when the reserve has run out.
      state_.kept_j = state_.kept_j > allowed ? state_.kept_j - allowed : 0.0;
    }
    state_.observed_j = available();
    return state_.scale;
  }

  // An energy frame to go out with this tick's data frame: when the input grew since the last, or with a refresh.
  constexpr std::optional<protocol::EnergyMessage> frame(Tick now, bool refresh) noexcept {
    if (!enabled()) return std::nullopt;
    // Rounded down, so the peer never credits more than came in; modulo 2^32 by the wrap rule.
    const double units = state_.passed_j / protocol::kEnergyLsbJ;
    const auto code = static_cast<std::uint32_t>(static_cast<std::uint64_t>(units) & 0xFFFFFFFFu);
    if (sent_any_ && code == sent_code_ && !refresh) return std::nullopt;
    sent_any_ = true;
    sent_code_ = code;
    return protocol::EnergyMessage{code, static_cast<std::uint16_t>(now & 0xFFFFu), epoch_};
  }

 private:
  constexpr double available() const noexcept {
    return state_.received_j + state_.input_j - state_.passed_j - state_.output_j;
  }
  // Under tdpa the input refills the port's reserve (its reserve_share of it, while there is room) and the rest
  // goes to the peer, so a hand that yields to the display and pushes back spends and refills mostly the same few
  // millijoules instead of handing each push-back to the peer, a round trip away from coming back. Only the port's own
  // input is ever passed (the peer's energy is spent here, never bounced back), and never energy the port has put out:
  // kept shrinks with every output. Under observe the output is not bounded, and the input goes on as it came (all of
  // it beyond the reserve), so the peer's observer sees the channel as it is.
  constexpr void take_in(double energy_j) noexcept {
    state_.input_j += energy_j;
    if (acts()) {
      const double room = config_.reserve_j - state_.kept_j;
      const double offered = energy_j * config_.reserve_share;
      const double keep = room <= 0.0 ? 0.0 : offered < room ? offered : room;
      state_.kept_j += keep;
      state_.passed_j += energy_j - keep;
    } else {
      const double target = state_.input_j - config_.reserve_j;
      if (target > state_.passed_j) state_.passed_j = target;
    }
  }

  PassivityConfig config_;
  State state_;
  ReceivedEnergy received_;
  std::uint8_t epoch_ = 0;
  std::uint32_t sent_code_ = 0;
  bool sent_any_ = false;
};

}  // namespace lever::fw
