#pragma once
// A strain gauge behind a weighing amplifier: gain and offset, white noise, an ADC of finite bits that
// saturates, and a sample rate of its own (often below the firmware's 1 kHz).
#include <cmath>
#include <cstdint>
#include <optional>

#include "lever/common/rng.hpp"
#include "lever/fw/strain_gauge.hpp"

namespace lever::hil {

struct StrainGaugeParams {
  double newton_per_count = 100.0 / 65536.0;  // 16-bit over +-50 N: what the firmware's calibration expects
  double offset_counts = 0.0;                 // the amplifier's zero error, removed by a tare
  double gain_error = 0.0;                    // relative calibration error
  double noise_n = 0.01;                      // N rms: 0.01 % of full scale, an ordinary amplifier
  int adc_bits = 16;
  double sample_rate_hz = 1000.0;
};

class StrainGaugeModel {
 public:
  StrainGaugeModel(const StrainGaugeParams& p, std::uint64_t seed) : p_(p), rng_(seed) {}

  // Called once per firmware tick with the true force; takes a new sample when the amplifier's clock says so.
  void update(double true_force, fw::Tick now) {
    const double now_s = static_cast<double>(now) * 1e-3;
    if (frozen_ || now_s + 1e-12 < next_sample_s_) return;
    next_sample_s_ += 1.0 / p_.sample_rate_hz;
    if (next_sample_s_ < now_s) next_sample_s_ = now_s + 1.0 / p_.sample_rate_hz;
    const double max_code = std::ldexp(1.0, p_.adc_bits - 1) - 1.0;
    double code = true_force * (1.0 + p_.gain_error) / p_.newton_per_count + p_.offset_counts +
                  p_.noise_n / p_.newton_per_count * rng_.normal();
    code = std::round(code);
    if (force_saturated_) code = max_code;
    code = code > max_code ? max_code : code < -max_code - 1.0 ? -max_code - 1.0 : code;
    reading_ = fw::ForceReading{code, now - clock_offset_, false};
  }

  // Readings are stamped on the firmware's clock, which starts again at a reboot: tick - offset.
  void set_clock_offset(fw::Tick offset) { clock_offset_ = offset; }

  // Fault injection: the amplifier stops answering (readings age), or reads at its limit.
  void set_frozen(bool frozen) { frozen_ = frozen; }
  void set_saturated(bool saturated) { force_saturated_ = saturated; }

  // ForcePort
  std::optional<fw::ForceReading> latest() const { return reading_; }

 private:
  StrainGaugeParams p_;
  Rng rng_;
  double next_sample_s_ = 0.0;
  fw::Tick clock_offset_ = 0;
  bool frozen_ = false;
  bool force_saturated_ = false;
  std::optional<fw::ForceReading> reading_;
};

}  // namespace lever::hil
