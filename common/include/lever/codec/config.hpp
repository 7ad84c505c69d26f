#pragma once
// Parameters of the perceptual deadband codec (paper sections III-A to III-E).
#include <cmath>
#include <cstdint>
#include <string_view>

namespace lever::codec {

// Stable numbers: the mode travels in CAN command frames.
enum class Mode : std::uint8_t {
  deadband = 0,    // reference = last transmitted value (zero-order hold), eq. (2)/(3)
  predictive = 1,  // reference = linear extrapolation of the last two transmitted values, section III-D
};

inline constexpr Mode kAllModes[] = {Mode::deadband, Mode::predictive};

// The one spelling of each mode: options, configuration files, logs, JSON and the views parse and print it.
constexpr std::string_view name(Mode m) noexcept {
  switch (m) {
    case Mode::deadband:
      return "deadband";
    case Mode::predictive:
      return "predictive";
  }
  return "unknown";
}

template <typename T>
struct Config {
  Mode mode = Mode::deadband;
  T p = T(0.1);        // Weber fraction: relative deadband width
  T floor = T(0);      // absolute deadband floor; 0 is the paper's rule
  T filter_hz = T(0);  // prefilter cut-off; 0 switches the prefilter off
};

template <typename T>
constexpr bool is_valid(const Config<T>& c) noexcept {
  return (c.mode == Mode::deadband || c.mode == Mode::predictive) && std::isfinite(c.p) && c.p >= T(0) &&
         std::isfinite(c.floor) && c.floor >= T(0) && std::isfinite(c.filter_hz) && c.filter_hz >= T(0);
}

// A Weber fraction is below 1: at 1 a fall to zero, the lever stopping, is never noticeable (|v_ref - 0| > p |v_ref|
// never holds).
inline constexpr double kWeberFractionLimit = 1.0;

// What a codec sampled at `rate_hz` runs as its settings say: valid, a Weber fraction below the limit, and a prefilter
// cut-off below the Nyquist frequency. The levers hold every setting they take, from a file or a raw CAN frame, to
// it, and the programs' options (codec_cli) refuse the same.
template <typename T>
constexpr bool runs_at(const Config<T>& c, double rate_hz) noexcept {
  return is_valid(c) && c.p < T(kWeberFractionLimit) && c.filter_hz < T(0.5 * rate_hz);
}

}  // namespace lever::codec
