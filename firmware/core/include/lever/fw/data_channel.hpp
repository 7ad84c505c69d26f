#pragma once
// One direction of deadband-coded data (HSI velocity, or TOP force) on top of the codec: sequence numbers,
// the periodic refresh that heals a lost update, stream restarts, and coherent parameter changes.
#include <cstdint>
#include <optional>

#include "lever/codec/codec.hpp"
#include "lever/fw/link.hpp"
#include "lever/fw/send_cause.hpp"
#include "lever/fw/tick.hpp"
#include "lever/protocol/messages.hpp"

namespace lever::fw {

template <typename WireInt>
using WireQuantizer = codec::FixedPointQuantizer<double, WireInt>;

// The message set's fixed-point fields (protocol/messages.hpp), as the codec's quantizers.
constexpr WireQuantizer<std::int16_t> velocity_wire() noexcept { return {protocol::kVelocityLsb}; }
constexpr WireQuantizer<std::int32_t> force_wire() noexcept {
  return {protocol::kForceLsb, protocol::kForceCodeMin, protocol::kForceCodeMax};
}
constexpr WireQuantizer<std::int16_t> position_wire() noexcept { return {protocol::kPositionLsbRad}; }

// A data frame a role hands to the lever to send, whether it is flagged a refresh, and why it goes.
struct OutgoingData {
  protocol::CanFrame frame;
  bool refresh = false;
  SendCause cause = SendCause::deadband;
};

// The codec runs in tick units: integer-valued doubles make every time difference exact, so the predictor's
// slope and extrapolation come out bit-identical at both ends even though the receiver only knows the
// sender's tick modulo 2^16 (an unknown base cancels out exactly). The prefilter's cut-off follows the unit.
constexpr codec::Config<double> in_tick_units(const codec::Config<double>& hz_config) noexcept {
  codec::Config<double> c = hz_config;
  c.filter_hz = hz_config.filter_hz * kSecondsPerTick;  // cycles per tick
  return c;
}

// Sending end. A parameter change takes effect at the next sample, which is always transmitted and carries
// the new mode, so the receiver switches at exactly that sample.
template <typename WireInt>
class DataSender {
 public:
  using Sender = codec::DeadbandSender<double, 1, WireQuantizer<WireInt>>;
  struct Output {
    bool send = false;
    bool saturated = false;
    bool refresh = false;  // forced: the refresh period, a restart, a reconfiguration or a rest repeat (the wire flag)
    bool restart = false;  // the first sample of a new stream
    SendCause cause = SendCause::deadband;
    WireInt code = 0;
    std::uint8_t seq = 0;
    codec::Mode mode = codec::Mode::deadband;
  };

  // rest_repeat: a frame that brings the stream to rest is sent once more this many ticks later (0: never).
  // At rest the deadband goes quiet, so a lost rest frame would otherwise leave the receiver holding the last
  // moving value until the refresh: at one encoder count per tick, 0.38 rad/s for 100 ms is 38 mrad of drift.
  constexpr DataSender(const codec::Config<double>& config, WireQuantizer<WireInt> quantizer, Tick refresh_period,
                       Tick rest_repeat = 0)
      : sender_(in_tick_units(config), quantizer),
        config_(config),
        refresh_period_(refresh_period),
        rest_repeat_(rest_repeat) {}

  // In user units (cut-off in Hz).
  constexpr const codec::Config<double>& config() const noexcept { return config_; }
  constexpr std::uint8_t last_seq() const noexcept { return static_cast<std::uint8_t>(seq_ - 1u); }
  constexpr const Sender& codec_sender() const noexcept { return sender_; }

  constexpr void reconfigure(const codec::Config<double>& config) noexcept {
    config_ = config;
    sender_.reconfigure(in_tick_units(config));
    force_next_ = true;
  }
  // Start a fresh stream (arming): the next sample is transmitted, flagged as a restart.
  constexpr void restart() noexcept {
    sender_.reset();
    force_next_ = true;
    restart_next_ = true;
    last_at_rest_ = false;  // a stream that starts at rest has arrived there: its first frame is repeated too
  }

  Output offer(Tick now, double value) noexcept {
    const bool repeat_due = rest_repeat_pending_ && now - last_sent_ >= rest_repeat_;
    const bool refresh_due = force_next_ || repeat_due || now - last_sent_ >= refresh_period_;
    const auto d = sender_.offer(static_cast<double>(now), {value}, refresh_due);
    Output out;
    if (!d.send) return out;
    // A forced send is flagged a refresh on the wire; the codec still says whether the rule alone sends it.
    const SendCause cause = d.exceeded ? SendCause::deadband : repeat_due ? SendCause::rest_repeat : SendCause::refresh;
    out = {true, d.saturated, refresh_due, restart_next_, cause, d.wire[0], seq_++, config_.mode};
    last_sent_ = now;
    force_next_ = false;
    restart_next_ = false;
    // Rest is where the deadband would stop sending: within the floor of zero (exactly zero under the paper's
    // rule). Only the frame that arrives there is repeated; the repeat itself, or a refresh, is not.
    const bool at_rest = d.value[0] <= config_.floor && -d.value[0] <= config_.floor;
    rest_repeat_pending_ = rest_repeat_ > 0 && at_rest && !last_at_rest_;
    last_at_rest_ = at_rest;
    return out;
  }

 private:
  Sender sender_;
  codec::Config<double> config_;
  Tick refresh_period_;
  Tick rest_repeat_;
  Tick last_sent_ = 0;
  bool rest_repeat_pending_ = false;
  bool last_at_rest_ = false;
  bool force_next_ = true;
  bool restart_next_ = true;
  std::uint8_t seq_ = 0;
};

// Receiving end: reconstructs a value every tick in the sender's time base, estimated as the sample's tick
// plus the local ticks since it arrived (the transmission delay is what the paper calls unavoidable).
template <typename WireInt>
class DataReceiver {
 public:
  using Receiver = codec::DeadbandReceiver<double, 1, WireQuantizer<WireInt>>;

  explicit constexpr DataReceiver(WireQuantizer<WireInt> quantizer) : receiver_(codec::Mode::deadband, quantizer) {}

  // Returns false when the frame must not be used (duplicate or reordered). A new stream is recognized before
  // any staleness check: a rebooted sender starts its sequence numbers anywhere, and judging them against the
  // old stream dropped up to 127 of its frames while the watchdog counted it alive.
  bool accept(Tick now, std::uint16_t tick, std::uint8_t seq, const protocol::DataFlags& flags, WireInt code) noexcept {
    // A restart frame seen twice (a duplicated datagram) is not a second restart.
    const bool repeated_restart = flags.restart && restart_seen_ && seq == restart_seq_ && tick == restart_tick_;
    if (repeated_restart) {
      sequence_.observe(seq);  // counted as the duplicate it is
      return false;
    }
    if (flags.restart) {
      restart_seen_ = true;
      restart_seq_ = seq;
      restart_tick_ = tick;
    }
    if (flags.restart || restart_pending_) restart_stream();
    if (sequence_.observe(seq) == SequenceTracker::Verdict::stale) return false;
    const auto t = unwrapper_.unwrap(tick);
    // No restart frame, yet the sender's clock did not advance: it restarted and that frame was lost.
    if (t.restarted) receiver_.reset();
    newest_tick_ = t.tick;
    arrival_ = now;
    expired_ = false;
    receiver_.set_mode(flags.mode);
    receiver_.receive(static_cast<double>(t.tick), {code});
    return true;
  }

  // The peer said (heartbeat) that it is not armed: whatever it sends next begins a new stream, even if its
  // restart frame is lost.
  constexpr void peer_stopped() noexcept { restart_pending_ = true; }

  // This lever (re)armed: nothing received before shows until the next frame. The samples themselves stay,
  // so a peer whose stream went on meanwhile stays coherent with this end.
  constexpr void expire() noexcept { expired_ = true; }

  // The reconstructed value at local tick `now`; nothing before the first sample, and nothing once the
  // newest sample is older than max_age: a sender that stopped (disarmed, faulted) while its heartbeats go on
  // must not leave the receiver holding, or worse extrapolating, its last value forever.
  std::optional<double> value_at(Tick now, Tick max_age) const noexcept {
    if (expired_ || now - arrival_ > max_age) return std::nullopt;
    const auto v = receiver_.reconstruct(static_cast<double>(newest_tick_ + (now - arrival_)));
    if (!v) return std::nullopt;
    return (*v)[0];
  }

  constexpr const SequenceTracker& sequence() const noexcept { return sequence_; }
  constexpr Tick last_arrival() const noexcept { return arrival_; }
  constexpr bool has_value() const noexcept { return !receiver_.model().empty(); }
  constexpr std::uint32_t restarts() const noexcept { return restarts_; }
  constexpr const Receiver& codec_receiver() const noexcept { return receiver_; }

 private:
  constexpr void restart_stream() noexcept {
    sequence_.restart();
    unwrapper_.reset();
    receiver_.reset();
    restart_pending_ = false;
    expired_ = true;
    ++restarts_;
  }

  Receiver receiver_;
  SequenceTracker sequence_;
  TickUnwrapper unwrapper_;
  Tick newest_tick_ = 0;
  Tick arrival_ = 0;
  std::uint32_t restarts_ = 0;
  std::uint16_t restart_tick_ = 0;
  std::uint8_t restart_seq_ = 0;
  bool restart_seen_ = false;
  bool restart_pending_ = false;
  bool expired_ = true;
};

}  // namespace lever::fw
