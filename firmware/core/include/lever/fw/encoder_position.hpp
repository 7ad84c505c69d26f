#pragma once
// Where the lever is, and whether that is known. An incremental encoder counts from wherever the lever was at
// power-up, so its count means nothing in lever coordinates until a reference is found (homing: a hard stop
// or the index line); an absolute encoder is referenced from the start. Lost edges or illegal transitions make
// the count untrustworthy again. Limits, arming and the TOP's hold all ask valid() first.
#include <cstdint>
#include <numbers>

namespace lever::fw {

class EncoderPosition {
 public:
  constexpr EncoderPosition(double counts_per_rev, bool absolute) noexcept
      : rad_per_count_(2.0 * std::numbers::pi / counts_per_rev), valid_(absolute) {}

  // The encoder's count this tick (decoder or unwrapped counter).
  constexpr void update(std::int64_t counts) noexcept { counts_ = counts; }

  constexpr std::int64_t counts() const noexcept { return counts_; }
  constexpr double rad_per_count() const noexcept { return rad_per_count_; }
  // Angle since power-up, continuous whatever homing does: what velocity estimation differentiates.
  constexpr double raw_angle() const noexcept { return static_cast<double>(counts_) * rad_per_count_; }
  constexpr double raw_angle_at(std::int64_t counts) const noexcept {
    return static_cast<double>(counts) * rad_per_count_;
  }
  // Lever coordinates; meaningful only while valid().
  constexpr double position() const noexcept { return raw_angle() - offset_; }
  constexpr bool valid() const noexcept { return valid_; }
  constexpr double offset() const noexcept { return offset_; }

  // The lever was at `position` (lever coordinates) when the encoder's raw angle was `raw_angle`.
  constexpr void reference(double raw_angle, double position) noexcept {
    offset_ = raw_angle - position;
    valid_ = true;
  }
  constexpr void invalidate() noexcept { valid_ = false; }

 private:
  double rad_per_count_;
  std::int64_t counts_ = 0;
  double offset_ = 0.0;
  bool valid_;
};

}  // namespace lever::fw
