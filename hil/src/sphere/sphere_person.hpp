#pragma once
// The person at the sphere-3dof's device: the physiological tremor of their hand, and what they intend to do with
// the stylus.
#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <cstdint>
#include <numbers>

#include "lever/common/rng.hpp"
#include "lever/hil/sphere3dof.hpp"
#include "lever/math/elementary.hpp"
#include "sphere_vec.hpp"

namespace lever::hil {

constexpr double kSphereTick = 1e-3;  // s: the device and the environment both run at 1 kHz

// Physiological tremor as a force: a sum of sinusoids in the tremor band per axis, each scaled by the free
// hand-and-device impedance at its frequency, so the free hand moves by the published displacement.
class Tremor {
 public:
  Tremor(const HandParams& h, double device_mass, Rng& rng) {
    const int k = std::max(h.tremor_components, 1);
    const double axis_rms = h.tremor_rms_m / std::sqrt(3.0);
    const double amplitude = axis_rms * std::sqrt(2.0 / k);
    const double m = h.mass_kg + device_mass;
    for (std::size_t axis = 0; axis < 3; ++axis) {
      for (int i = 0; i < k && i < kMax; ++i) {
        const double w = 2.0 * std::numbers::pi * rng.uniform(h.tremor_low_hz, h.tremor_high_hz);
        const double phase = rng.uniform(0.0, 2.0 * std::numbers::pi);
        const std::complex<double> impedance(h.stiffness - m * w * w, h.damping * w);
        Component& c = components_[axis][static_cast<std::size_t>(i)];
        c.phasor = impedance * std::complex<double>(amplitude * math::cos(phase), amplitude * math::sin(phase));
        c.step = std::complex<double>(math::cos(w * kSphereTick), math::sin(w * kSphereTick));
      }
      count_ = std::min(k, kMax);
    }
    enabled_ = h.tremor_rms_m > 0.0;
  }

  // The force now; advances by one tick.
  Vec3 next() {
    Vec3 f{};
    if (!enabled_) return f;
    for (std::size_t axis = 0; axis < 3; ++axis)
      for (int i = 0; i < count_; ++i) {
        Component& c = components_[axis][static_cast<std::size_t>(i)];
        f[axis] += c.phasor.real();
        c.phasor *= c.step;
      }
    return f;
  }

 private:
  static constexpr int kMax = 16;
  struct Component {
    std::complex<double> phasor{};
    std::complex<double> step{1.0, 0.0};
  };
  std::array<std::array<Component, kMax>, 3> components_{};
  int count_ = 0;
  bool enabled_ = false;
};

// What the person intends: strokes over the side of the sphere facing them, at a light force, now and then a
// firmer press, and after a few strokes lifting off and coming down somewhere else. Directions are great
// circles, radii and angles follow minimum-jerk profiles (Flash and Hogan), as the 1-DoF operator's reaches.
class Explorer {
 public:
  Explorer(const HandParams& h, const SphereParams& s, std::uint64_t seed) : h_(h), s_(s), rng_(seed) {
    n_from_ = n_to_ = {0.0, 0.0, 1.0};
    rho_from_ = rho_to_ = s.radius_m + 0.5 * (h.lift_min_m + h.lift_max_m);
    omega_ = 0.0;
    duration_ = 0.0;
  }

  Vec3 start() const { return add(s_.centre, scale(n_from_, rho_from_)); }

  Vec3 intent(double t) {
    if (!h_.explore) return start();
    while (t >= start_ + duration_) next_segment(start_ + duration_);
    const double tau = (t - start_) / duration_;
    const double s = tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
    Vec3 n;
    if (omega_ < 1e-9) {
      n = n_from_;
    } else {
      const double a = math::sin((1.0 - s) * omega_) / sin_omega_;
      const double b = math::sin(s * omega_) / sin_omega_;
      n = add(scale(n_from_, a), scale(n_to_, b));
    }
    return add(s_.centre, scale(n, rho_from_ + (rho_to_ - rho_from_) * s));
  }

 private:
  enum class Phase : std::uint8_t { descend, stroke, lift, hover };

  // Where the hand aims so a hand spring and the sphere in series settle at this force.
  double press_radius(double force) const { return s_.radius_m - force * (1.0 / h_.stiffness + 1.0 / s_.stiffness); }

  Vec3 random_direction() {
    const double cos_theta = 1.0 - rng_.uniform() * (1.0 - math::cos(h_.cap_half_angle_rad));
    const double sin_theta = std::sqrt(std::max(0.0, 1.0 - cos_theta * cos_theta));
    const double phi = rng_.uniform(0.0, 2.0 * std::numbers::pi);
    return {sin_theta * math::cos(phi), sin_theta * math::sin(phi), cos_theta};
  }

  // A call to go() takes one draw in its arguments at most, the duration being drawn before: C++ leaves the order of
  // arguments open, and GCC evaluates them right to left on x86-64 and left to right on Arm, which made the same seed
  // another run there. Drawing the last argument first keeps x86-64's runs what they were.
  void go(const Vec3& n_to, double rho_to, double duration) {
    n_from_ = n_to_;
    rho_from_ = rho_to_;
    n_to_ = n_to;
    rho_to_ = rho_to;
    omega_ = math::acos(std::clamp(dot(n_from_, n_to_), -1.0, 1.0));
    sin_omega_ = math::sin(omega_);
    duration_ = duration;
  }

  // A move over the surface at a speed a person strokes with; never shorter than a quick flick.
  double travel_time(const Vec3& n_to, double radius) {
    const double arc = math::acos(std::clamp(dot(n_to_, n_to), -1.0, 1.0)) * radius;
    return std::max(0.3, arc / rng_.uniform(h_.stroke_speed_min_mps, h_.stroke_speed_max_mps));
  }

  void next_segment(double now) {
    start_ = now;
    switch (phase_) {
      case Phase::descend: {
        const double duration = rng_.uniform(0.2, 0.4);  // drawn first: see go()
        go(n_to_, press_radius(rng_.uniform(h_.stroke_force_min_n, h_.stroke_force_max_n)), duration);
        strokes_left_ = 2 + static_cast<int>(rng_.next() % 4);
        press_before_ = static_cast<int>(rng_.next() % static_cast<std::uint64_t>(strokes_left_));
        pressed_ = false;
        phase_ = Phase::stroke;
        return;
      }
      case Phase::stroke: {
        if (!pressed_ && strokes_left_ == press_before_) {
          pressed_ = true;
          const double duration = rng_.uniform(0.3, 0.8);
          go(n_to_, press_radius(rng_.uniform(h_.press_force_min_n, h_.press_force_max_n)), duration);
          return;
        }
        if (strokes_left_ > 0) {
          --strokes_left_;
          const Vec3 n = random_direction();
          const double duration = travel_time(n, s_.radius_m);
          go(n, press_radius(rng_.uniform(h_.stroke_force_min_n, h_.stroke_force_max_n)), duration);
          return;
        }
        const double duration = rng_.uniform(0.2, 0.4);
        go(n_to_, s_.radius_m + rng_.uniform(h_.lift_min_m, h_.lift_max_m), duration);
        phase_ = Phase::lift;
        return;
      }
      case Phase::lift: {
        const Vec3 n = random_direction();
        go(n, rho_to_, travel_time(n, rho_to_));
        phase_ = Phase::hover;
        return;
      }
      case Phase::hover:
        phase_ = Phase::descend;
        next_segment(now);
        return;
    }
  }

  HandParams h_;
  SphereParams s_;
  Rng rng_;
  Phase phase_ = Phase::descend;
  int strokes_left_ = 0, press_before_ = 0;
  bool pressed_ = false;
  Vec3 n_from_{}, n_to_{};
  double rho_from_ = 0.0, rho_to_ = 0.0;
  double omega_ = 0.0, sin_omega_ = 1.0;
  double start_ = 0.0, duration_ = 0.0;
};

}  // namespace lever::hil
