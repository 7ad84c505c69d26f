#pragma once
// Receiving side: reconstructs a sample every tick from the transmitted ones, with the same model the sender
// used for its decision (zero-order hold or linear predictor).
#include <array>
#include <cstddef>
#include <optional>

#include "lever/codec/config.hpp"
#include "lever/codec/quantizer.hpp"
#include "lever/codec/reference_model.hpp"
#include "lever/common/vec.hpp"

namespace lever::codec {

template <typename T, std::size_t N, typename Q = IdentityQuantizer<T>>
requires Quantizer<Q, T>
class DeadbandReceiver {
 public:
  using Wire = std::array<typename Q::wire_type, N>;

  explicit constexpr DeadbandReceiver(Mode mode = Mode::deadband, Q quantizer = {}) noexcept
      : quantizer_(quantizer), model_(mode) {}

  constexpr const ReferenceModel<T, N>& model() const noexcept { return model_; }
  constexpr void set_mode(Mode mode) noexcept { model_.set_mode(mode); }
  constexpr void reset() noexcept { model_.reset(); }

  // A transmitted sample of time t arrived.
  constexpr void receive(T t, const Wire& wire) noexcept {
    Vec<T, N> decoded{};
    for (std::size_t i = 0; i < N; ++i) decoded[i] = quantizer_.decode(wire[i]);
    model_.accept(t, decoded);
  }

  // The reconstruction at time t; nothing until the first sample arrived, so no caller can mistake
  // "never heard" for zero.
  constexpr std::optional<Vec<T, N>> reconstruct(T t) const noexcept {
    if (model_.empty()) return std::nullopt;
    return model_.at(t);
  }

 private:
  Q quantizer_;
  ReferenceModel<T, N> model_;
};

}  // namespace lever::codec
