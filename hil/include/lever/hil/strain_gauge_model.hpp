#pragma once
// A load cell behind a weighing amplifier, after the Flintec DAD 141.1 (docs/hil-model.md, "The strain-gauge
// amplifier"): the bridge signal plus white noise converted at the ADC's rate, the amplifier's 2nd-order IIR
// low-pass, the mean of 2^UR conversions as its output rate, quantization to the display step, saturation at
// the configured maximum, and a clock of its own (600 conversions per second against the firmware's 1 kHz).
#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>

#include "lever/common/rng.hpp"
#include "lever/fw/strain_gauge.hpp"
#include "lever/math/elementary.hpp"

namespace lever::hil {

struct StrainGaugeParams {
  double adc_rate_hz = 600.0;      // conversions per second; the DAD's rate in its IIR mode
  double filter_hz = 18.0;         // IIR -3 dB cut-off (FL 1, its fastest filter); 0: unfiltered
  int averaging = 1;               // conversions averaged per reading (2^UR): output rate adc_rate_hz / averaging
  double noise_n = 0.0168;         // N rms per conversion, white, before the filter: the approval's 10 000 d at FL 7
  double step_n = 50.0 / 20000.0;  // N per display step: factory 20 000 d at 2 mV/V, a 50 N, 2 mV/V cell
  double range_n = 50.0;           // maximum output (CM, CI): the cell's capacity; beyond it reads saturated
  double offset_counts = 0.0;      // the amplifier's zero error, removed by a tare
  double gain_error = 0.0;         // relative calibration error

  double output_rate_hz() const { return adc_rate_hz / averaging; }
  double max_code() const { return std::round(range_n / step_n); }
  // The pole of each of the filter's two equal real sections: -3 dB at filter_hz overall.
  double pole_hz() const { return filter_hz / std::sqrt(std::sqrt(2.0) - 1.0); }
  // Finite, positive where it must be, the filter below the conversions' Nyquist frequency.
  bool valid() const {
    return std::isfinite(adc_rate_hz) && adc_rate_hz > 0.0 && std::isfinite(filter_hz) && filter_hz >= 0.0 &&
           filter_hz < adc_rate_hz / 2 && averaging >= 1 && std::isfinite(noise_n) && noise_n >= 0.0 &&
           std::isfinite(step_n) && step_n > 0.0 && std::isfinite(range_n) && range_n >= step_n;
  }
};

// The paper's chain (docs/hil-model.md, "The assumed AD620 chain"): the same 50 N, 2 mV/V cell excited at 10 V, an
// AD620 instrumentation amplifier at gain 495 and a 16-bit ADC over +-10 V read once per 1 kHz control tick, with no
// filter: the AD620's 9 nV/rtHz and the bridge's 2.4 nV/rtHz over the amplifier's 24 kHz, aliased into the samples.
inline StrainGaugeParams paper_adc_gauge() {
  constexpr double volt_per_newton = 2e-3 * 10.0 / 50.0;                  // the bridge's output: 0.4 mV/N
  constexpr double gain = 1.0 + 49.4e3 / 100.0;                           // AD620 at R_G = 100 ohm
  const double noise_density = std::sqrt(9e-9 * 9e-9 + 2.4e-9 * 2.4e-9);  // V/rtHz, referred to the input
  const double noise_v = noise_density * std::sqrt(std::numbers::pi / 2.0 * 24e3);
  StrainGaugeParams p;
  p.adc_rate_hz = 1000.0;
  p.filter_hz = 0.0;
  p.averaging = 1;
  p.noise_n = noise_v / volt_per_newton;
  p.step_n = 20.0 / 65536.0 / gain / volt_per_newton;
  p.range_n = 50.0;
  return p;
}

// The firmware's calibration for this amplifier, as a board's lever-fw configuration is set for its own: codes to
// newtons, the codes at which it reads saturated, and a staleness window of at least two output periods.
inline void calibrate_for(fw::StrainGauge::Config& c, const StrainGaugeParams& p) {
  c.newton_per_count = p.step_n;
  c.raw_max = p.max_code();
  c.raw_min = -p.max_code();
  const auto two_periods = static_cast<fw::Tick>(std::ceil(2000.0 / p.output_rate_hz()));
  if (c.stale_after < two_periods) c.stale_after = two_periods;
}

class StrainGaugeModel {
 public:
  StrainGaugeModel(const StrainGaugeParams& p, std::uint64_t seed) : p_(p), rng_(seed), period_s_(1.0 / p.adc_rate_hz) {
    if (p.filter_hz > 0.0) {
      const double h_over_tau = 2.0 * std::numbers::pi * p.pole_hz() * period_s_;
      decay_ = math::exp(-h_over_tau);
      coupling_ = h_over_tau * decay_;
    }
  }

  // The noise from here on is this seed's, whatever was drawn before.
  void reseed(std::uint64_t seed) noexcept { rng_ = Rng(seed); }

  // Called once per firmware tick with the true force; converts every sample the amplifier's clock has due
  // since the last call, and publishes a reading each time `averaging` conversions are in.
  void update(double true_force, fw::Tick now) {
    const double now_s = static_cast<double>(now) * 1e-3;
    if (next_sample_s_ + 1.0 < now_s) {  // first called late: no burst of old samples
      clock_start_s_ = now_s;
      conversions_ = 0;
      next_sample_s_ = now_s;
    }
    while (next_sample_s_ <= now_s + 1e-12) {
      // The n-th conversion at start + n periods, not a running sum, whose rounding drifts across tick boundaries
      // (an ADC read once a tick missed 3 ticks in 100 000).
      next_sample_s_ = clock_start_s_ + static_cast<double>(++conversions_) * period_s_;
      convert(true_force, now);
    }
  }

  // Readings are stamped on the firmware's clock, which starts again at a reboot: tick - offset.
  void set_clock_offset(fw::Tick offset) { clock_offset_ = offset; }

  // Fault injection: the amplifier stops answering (readings age; it goes on converting), or reads at its limit.
  void set_frozen(bool frozen) { frozen_ = frozen; }
  void set_saturated(bool saturated) { force_saturated_ = saturated; }

  // ForcePort
  std::optional<fw::ForceReading> latest() const { return reading_; }

 private:
  void convert(double true_force, fw::Tick now) {
    const double signal = true_force * (1.0 + p_.gain_error);
    const double x = signal + (p_.noise_n > 0.0 ? p_.noise_n * rng_.normal() : 0.0);
    if (!started_) {  // the amplifier has been on long before the simulation starts: settled on the signal
      stage1_ = stage2_ = signal;
      started_ = true;
    }
    // The two poles, exact for an input held over the conversion period (step invariant), so the response at
    // the conversions is the continuous filter's.
    stage2_ = decay_ * stage2_ + coupling_ * stage1_ + (1.0 - decay_ - coupling_) * x;
    stage1_ = decay_ * stage1_ + (1.0 - decay_) * x;
    sum_ += stage2_;
    if (++count_ < p_.averaging) return;
    const double mean = sum_ / count_;
    sum_ = 0.0;
    count_ = 0;
    const double max_code = p_.max_code();
    double code = std::round(mean / p_.step_n + p_.offset_counts);
    if (force_saturated_) code = max_code;
    code = code > max_code ? max_code : code < -max_code ? -max_code : code;
    if (!frozen_) reading_ = fw::ForceReading{code, now - clock_offset_, false};
  }

  StrainGaugeParams p_;
  Rng rng_;
  double decay_ = 0.0;     // exp(-h / tau) per conversion; 0 with the filter off passes the input through
  double coupling_ = 0.0;  // (h / tau) exp(-h / tau): the first pole's share in the second over a period
  double period_s_;        // between conversions
  double next_sample_s_ = 0.0;
  double clock_start_s_ = 0.0;
  std::uint64_t conversions_ = 0;
  double stage1_ = 0.0, stage2_ = 0.0;
  bool started_ = false;
  double sum_ = 0.0;
  int count_ = 0;
  fw::Tick clock_offset_ = 0;
  bool frozen_ = false;
  bool force_saturated_ = false;
  std::optional<fw::ForceReading> reading_;
};

}  // namespace lever::hil
