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
    violations_ += violates(displayed_n, measured_n);
    if (contact_n > 0.0) {
      ++contact_ticks_;
      contact_force_sum_ += contact_n;
    }
    // An onset needs the lever to have left the wall entirely (zero force) and then to press past the
    // firmware's own contact threshold (ForceDisplay's 0.1 N, ten times the gauge's noise): a lever resting on
    // the wall grazes it at micronewtons from one physics substep to the next, which is no new contact.
    if (contact_n <= 0.0) {
      if (touching_) last_end_tick_ = armed_ticks_;
      touching_ = false;
    } else if (!touching_ && contact_n > kContactOnsetN) {
      touching_ = true;
      ++contact_onsets_;
      // A hand's tap on a stiff wall may bounce once; a bounce of a bounce is the loop's, not the hand's
      // (docs/hil-model.md, "The contact check").
      const bool rebound = contact_onsets_ > 1 && armed_ticks_ - last_end_tick_ <= kReboundTicks;
      contact_rebounds_ += rebound;
      contact_rebounds_of_rebounds_ += rebound && last_onset_was_rebound_;
      last_onset_was_rebound_ = rebound;
    }
  }

  // The displayed force's distortion by cause, for a run that can see inside the TOP's sender (not serve):
  // against the measurement of `nominal delay` ticks earlier (the codec, the filter and the link's loss and
  // jitter; the transport delay itself excluded), the codec alone (what a lossless receiver without delay would
  // hold, against the prefiltered force the codec was given), and the prefilter alone (its output against its
  // input).
  void add_force_causes(double displayed_n, double measured_delayed_n, double lossless_n, double filtered_n,
                        double measured_n) {
    ++cause_ticks_;
    violations_link_ += violates(displayed_n, measured_delayed_n);
    violations_codec_ += violates(lossless_n, filtered_n);
    violations_filter_ += violates(filtered_n, measured_n);
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
    const double c = cause_ticks_ > 0 ? static_cast<double>(cause_ticks_) : 1.0;
    r.force_jnd_violation_link = static_cast<double>(violations_link_) / c;
    r.force_jnd_violation_codec = static_cast<double>(violations_codec_) / c;
    r.force_jnd_violation_filter = static_cast<double>(violations_filter_) / c;
    r.contact_share = static_cast<double>(contact_ticks_) / n;
    r.contact_onsets_per_s = static_cast<double>(contact_onsets_) / (n * 1e-3);
    r.mean_contact_force_n = contact_ticks_ > 0 ? contact_force_sum_ / static_cast<double>(contact_ticks_) : 0.0;
  }

  std::uint64_t armed_ticks() const { return armed_ticks_; }
  std::uint64_t contact_ticks() const { return contact_ticks_; }
  std::uint64_t contact_onsets() const { return contact_onsets_; }
  // Onsets within kReboundTicks of the last contact's end, and those of them whose last contact was one too.
  std::uint64_t contact_rebounds() const { return contact_rebounds_; }
  std::uint64_t contact_rebounds_of_rebounds() const { return contact_rebounds_of_rebounds_; }

  static constexpr double kContactOnsetN = 0.1;
  static constexpr std::uint64_t kReboundTicks = 30;
  std::uint64_t motion_frames() const { return motion_frames_; }
  std::uint64_t force_frames() const { return force_frames_; }

 private:
  // Off by more than a just noticeable difference: Weber's fraction of the reference, never below the absolute
  // detection threshold.
  bool violates(double shown, double reference) const {
    return std::fabs(shown - reference) > std::max(jnd_ * std::fabs(reference), jnd_absolute_n_);
  }

  double jnd_, jnd_absolute_n_;
  std::uint64_t cause_ticks_ = 0, violations_link_ = 0, violations_codec_ = 0, violations_filter_ = 0;
  std::uint64_t armed_ticks_ = 0, motion_frames_ = 0, force_frames_ = 0, violations_ = 0, contact_ticks_ = 0;
  double sq_position_ = 0, sq_force_ = 0, contact_force_sum_ = 0;
  std::uint64_t contact_onsets_ = 0, contact_rebounds_ = 0, contact_rebounds_of_rebounds_ = 0;
  std::uint64_t last_end_tick_ = 0;
  bool touching_ = false, last_onset_was_rebound_ = false;
};

}  // namespace lever::hil
