#pragma once
// Sending side of the perceptual deadband: decides per sample whether the change would be noticeable
// (Weber's law, N-DoF isotropic deadzone) and keeps the model the receiver will run.
#include <array>
#include <cstddef>

#include "lever/codec/config.hpp"
#include "lever/codec/prefilter.hpp"
#include "lever/codec/quantizer.hpp"
#include "lever/codec/reference_model.hpp"
#include "lever/common/vec.hpp"

namespace lever::codec {

// The transmit rule: ||ref - v|| > max(p ||ref||, floor), strict, Euclidean over the DoF.
template <typename T, std::size_t N>
constexpr bool exceeds_deadzone(const Vec<T, N>& reference, const Vec<T, N>& value, T p, T floor) noexcept {
  const T relative = p * norm(reference);
  const T threshold = relative > floor ? relative : floor;
  return norm(difference(reference, value)) > threshold;
}

template <typename T, std::size_t N, typename Q = IdentityQuantizer<T>>
requires Quantizer<Q, T>
class DeadbandSender {
 public:
  using Wire = std::array<typename Q::wire_type, N>;

  struct Decision {
    bool send = false;
    // The deadband rule alone sends this sample (always the first after a reset), forced or not: what the paper
    // counts as a packet, while a forced send the rule would not have made is the link's own.
    bool exceeded = false;
    bool saturated = false;  // the wire value was clipped at the quantizer's range
    Vec<T, N> value{};       // what the receiver holds at this sample (decoded value if sent, else its reference)
    Wire wire{};             // valid when send
  };

  explicit constexpr DeadbandSender(const Config<T>& config = {}, Q quantizer = {}) noexcept
      : config_(config), quantizer_(quantizer), prefilter_(config.filter_hz), model_(config.mode) {}

  constexpr const Config<T>& config() const noexcept { return config_; }
  constexpr const ReferenceModel<T, N>& model() const noexcept { return model_; }
  constexpr const LowPassPrefilter<T, N>& prefilter() const noexcept { return prefilter_; }
  constexpr const Q& quantizer() const noexcept { return quantizer_; }

  // New parameters from the next offer() on. The transmitted history stays, so a receiver that applies the
  // same change before decoding the same sample stays coherent. A new cut-off restarts the prefilter.
  constexpr void reconfigure(const Config<T>& config) noexcept {
    if (config.filter_hz != config_.filter_hz) prefilter_ = LowPassPrefilter<T, N>(config.filter_hz);
    config_ = config;
    model_.set_mode(config.mode);
  }

  // Start over as if nothing had been sent (the next sample is transmitted).
  constexpr void reset() noexcept {
    prefilter_.reset();
    model_.reset();
  }

  // One sample at time t (strictly increasing). force_send transmits regardless of the deadband, which the
  // link uses to refresh the receiver's reference after a silence.
  // The decision is made on exactly what the receiver would decode: deciding on the unquantized value sent
  // frames whose wire code equalled the previous one (21 % of velocity frames at p = 10 %), changes no
  // receiver can see.
  Decision offer(T t, const Vec<T, N>& measured, bool force_send = false) noexcept {
    const Vec<T, N> value = prefilter_.enabled() ? prefilter_.apply(t, measured) : measured;
    Decision d;
    Vec<T, N> decoded{};
    for (std::size_t i = 0; i < N; ++i) {
      d.wire[i] = quantizer_.encode(value[i], d.saturated);
      decoded[i] = quantizer_.decode(d.wire[i]);
    }
    d.exceeded = true;
    if (!model_.empty()) {
      const Vec<T, N> reference = model_.at(t);
      d.exceeded = exceeds_deadzone(reference, decoded, config_.p, config_.floor);
      if (!d.exceeded && !force_send) {
        d.value = reference;
        d.saturated = false;
        return d;
      }
    }
    d.send = true;
    d.value = decoded;
    model_.accept(t, d.value);
    return d;
  }

 private:
  Config<T> config_;
  Q quantizer_;
  LowPassPrefilter<T, N> prefilter_;
  ReferenceModel<T, N> model_;
};

}  // namespace lever::codec
