#pragma once
// What lever-hil run and lever-hil serve measure on every tick both levers are armed, and how it becomes the
// report's rates and errors: one place, so both report the same quantities the same way.
#include <algorithm>
#include <cmath>
#include <cstdint>

namespace lever::hil {

class RunMetrics {
 public:
  RunMetrics(double jnd, double jnd_absolute_n) : jnd_(jnd), jnd_absolute_n_(jnd_absolute_n) {}

  // One armed tick: the data frames sent in it, the TOP's angle less the HSI's, the force the HSI displays and
  // the one the TOP measured, and the wall's contact force (positive: touching).
  void add_armed_tick(std::uint64_t motion_frames, std::uint64_t force_frames, double position_error_rad,
                      double displayed_n, double measured_n, double contact_n) {
    ++armed_ticks_;
    motion_frames_ += motion_frames;
    force_frames_ += force_frames;
    sq_position_ += position_error_rad * position_error_rad;
    const double df = displayed_n - measured_n;
    sq_force_ += df * df;
    if (std::fabs(df) > std::max(jnd_ * std::fabs(measured_n), jnd_absolute_n_)) ++violations_;
    if (contact_n > 0.0) {
      ++contact_ticks_;
      contact_force_sum_ += contact_n;
    }
  }

  // Into the report's fields (SimResult or anything with the same names).
  template <typename Result>
  void finish(Result& r) const {
    r.armed_ticks = armed_ticks_;
    r.motion_frames = motion_frames_;
    r.force_frames = force_frames_;
    const double n = armed_ticks_ > 0 ? static_cast<double>(armed_ticks_) : 1.0;
    r.velocity_packet_rate = static_cast<double>(motion_frames_) / n;
    r.force_packet_rate = static_cast<double>(force_frames_) / n;
    r.position_rmse_rad = std::sqrt(sq_position_ / n);
    r.force_rmse_n = std::sqrt(sq_force_ / n);
    r.force_jnd_violation = static_cast<double>(violations_) / n;
    r.contact_share = static_cast<double>(contact_ticks_) / n;
    r.mean_contact_force_n = contact_ticks_ > 0 ? contact_force_sum_ / static_cast<double>(contact_ticks_) : 0.0;
  }

  std::uint64_t armed_ticks() const { return armed_ticks_; }
  std::uint64_t contact_ticks() const { return contact_ticks_; }
  std::uint64_t motion_frames() const { return motion_frames_; }
  std::uint64_t force_frames() const { return force_frames_; }

 private:
  double jnd_, jnd_absolute_n_;
  std::uint64_t armed_ticks_ = 0, motion_frames_ = 0, force_frames_ = 0, violations_ = 0, contact_ticks_ = 0;
  double sq_position_ = 0, sq_force_ = 0, contact_force_sum_ = 0;
};

}  // namespace lever::hil
