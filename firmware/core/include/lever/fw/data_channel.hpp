#pragma once
// One direction of deadband-coded data (HSI velocity, or TOP force) on top of the codec: sequence numbers,
// the periodic refresh that heals a lost update, and coherent parameter changes.
#include <cstdint>
#include <optional>

#include "lever/codec/codec.hpp"
#include "lever/fw/link.hpp"

namespace lever::fw {

template <typename WireInt>
using WireQuantizer = codec::FixedPointQuantizer<double, WireInt>;

inline constexpr double kSecondsPerTick = 1e-3;

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
    bool refresh = false;  // sent because of the refresh period (or a reconfiguration), not the deadband
    WireInt code = 0;
    std::uint8_t seq = 0;
    codec::Mode mode = codec::Mode::deadband;
  };

  constexpr DataSender(const codec::Config<double>& config, WireQuantizer<WireInt> quantizer, Tick refresh_period)
      : sender_(in_tick_units(config), quantizer), config_(config), refresh_period_(refresh_period) {}

  // In user units (cut-off in Hz).
  constexpr const codec::Config<double>& config() const noexcept { return config_; }
  constexpr std::uint8_t last_seq() const noexcept { return static_cast<std::uint8_t>(seq_ - 1u); }
  constexpr const Sender& codec_sender() const noexcept { return sender_; }

  constexpr void reconfigure(const codec::Config<double>& config) noexcept {
    config_ = config;
    sender_.reconfigure(in_tick_units(config));
    force_next_ = true;
  }
  // Start a fresh stream (arming): the next sample is transmitted.
  constexpr void restart() noexcept {
    sender_.reset();
    force_next_ = true;
  }

  Output offer(Tick now, double value) noexcept {
    const bool refresh_due = force_next_ || now - last_sent_ >= refresh_period_;
    const auto d = sender_.offer(static_cast<double>(now), {value}, refresh_due);
    Output out;
    if (!d.send) return out;
    // Whether the deadband alone would have sent is not known once forced; a forced send is a refresh.
    out = {true, d.saturated, refresh_due, d.wire[0], seq_++, config_.mode};
    last_sent_ = now;
    force_next_ = false;
    return out;
  }

 private:
  Sender sender_;
  codec::Config<double> config_;
  Tick refresh_period_;
  Tick last_sent_ = 0;
  bool force_next_ = true;
  std::uint8_t seq_ = 0;
};

// Receiving end: reconstructs a value every tick in the sender's time base, estimated as the sample's tick
// plus the local ticks since it arrived (the transmission delay is what the paper calls unavoidable).
template <typename WireInt>
class DataReceiver {
 public:
  explicit constexpr DataReceiver(WireQuantizer<WireInt> quantizer) : receiver_(codec::Mode::deadband, quantizer) {}

  // Returns false when the frame must not be used (duplicate or reordered).
  bool accept(Tick now, std::uint16_t tick, std::uint8_t seq, codec::Mode mode, WireInt code) noexcept {
    if (sequence_.observe(seq) == SequenceTracker::Verdict::stale) return false;
    const Tick sender_tick = unwrapper_.unwrap(tick);
    if (receiver_.model().samples_held() > 0 && !(sender_tick > newest_tick_)) {
      // The sender's clock went back (it restarted): its old samples say nothing about the new stream.
      receiver_.reset();
    }
    newest_tick_ = sender_tick;
    arrival_ = now;
    receiver_.set_mode(mode);
    receiver_.receive(static_cast<double>(sender_tick), {code});
    return true;
  }

  // The reconstructed value at local tick `now`; nothing before the first sample, and nothing once the
  // newest sample is older than max_age: a sender that stopped (disarmed, faulted) while its heartbeats go on
  // must not leave the receiver holding, or worse extrapolating, its last value forever.
  std::optional<double> value_at(Tick now, Tick max_age) const noexcept {
    if (now - arrival_ > max_age) return std::nullopt;
    const auto v = receiver_.reconstruct(static_cast<double>(newest_tick_ + (now - arrival_)));
    if (!v) return std::nullopt;
    return (*v)[0];
  }

  constexpr const SequenceTracker& sequence() const noexcept { return sequence_; }
  constexpr Tick last_arrival() const noexcept { return arrival_; }
  constexpr bool has_value() const noexcept { return !receiver_.model().empty(); }
  constexpr const codec::DeadbandReceiver<double, 1, WireQuantizer<WireInt>>& codec_receiver() const noexcept {
    return receiver_;
  }

 private:
  codec::DeadbandReceiver<double, 1, WireQuantizer<WireInt>> receiver_;
  SequenceTracker sequence_;
  TickUnwrapper unwrapper_;
  Tick newest_tick_ = 0;
  Tick arrival_ = 0;
};

}  // namespace lever::fw
