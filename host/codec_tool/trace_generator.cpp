#include "trace_generator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <numbers>
#include <string_view>

#include "lever/common/rng.hpp"

namespace lever::tool {
namespace {

constexpr double kSamplePeriod = 1e-3;  // the testbed's 1 kHz
constexpr int kSubsteps = 10;           // physics at 10 kHz: the wall's 50 Hz mode needs it
constexpr double kStep = kSamplePeriod / kSubsteps;

// Minimum-jerk blend s(0)=0, s(1)=1 with zero velocity and acceleration at both ends: how human reaching
// movements look (Flash and Hogan 1985).
double minimum_jerk(double tau) {
  tau = std::clamp(tau, 0.0, 1.0);
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}

// A target that moves between waypoints with minimum-jerk segments, each followed by a dwell.
template <typename Point, typename NextWaypoint>
class IntentPlanner {
 public:
  IntentPlanner(Point start, NextWaypoint next) : from_(start), to_(start), next_(next) {}

  Point at(double t) {
    while (t >= dwell_end_) {
      from_ = to_;
      const auto segment = next_(from_);
      to_ = segment.target;
      move_start_ = dwell_end_;
      move_end_ = move_start_ + segment.move_s;
      dwell_end_ = move_end_ + segment.dwell_s;
    }
    const double s = minimum_jerk((t - move_start_) / (move_end_ - move_start_));
    return from_ + (to_ - from_) * s;
  }

 private:
  Point from_, to_;
  NextWaypoint next_;
  double move_start_ = 0.0, move_end_ = 1e-9, dwell_end_ = 0.0;
};

struct Segment1 {
  double target, move_s, dwell_s;
};

// The paper's 1-DoF rig: a lever (arm 0.1 m) that the operator pushes against a stiff wall at the TOP.
// Values are a small desktop haptic lever; docs/codec.md says why.
struct LeverWall {
  static constexpr double inertia = 2.0e-3;        // kg m^2, lever plus the hand it carries
  static constexpr double viscous = 0.02;          // N m s/rad
  static constexpr double arm = 0.1;               // m, pivot to strain gauge / contact point
  static constexpr double wall_angle = 0.35;       // rad
  static constexpr double wall_stiffness = 200.0;  // N m/rad = 20 kN/m at the tip
  static constexpr double wall_damping = 0.4;      // N m s/rad
  static constexpr double hand_stiffness = 3.0;    // N m/rad = 300 N/m at the tip, a relaxed arm
  static constexpr double hand_damping = 0.15;     // N m s/rad, near critical for the hand on the lever
  static constexpr double counts_per_rev = 4096.0 * 4.0;
  static constexpr double gauge_noise_n = 0.01;  // N rms
  static constexpr double gauge_range_n = 50.0;  // +-, 16-bit ADC
};

Trace lever_wall_trace(const GeneratorOptions& options) {
  Rng rng(options.seed);
  // Tap, press and hold, release: 70 % of moves from free space go into the wall.
  auto next = [&rng](double from) {
    const bool in_contact = from > LeverWall::wall_angle;
    const bool press = in_contact ? rng.uniform() < 0.3 : rng.uniform() < 0.7;
    const bool tap = press && rng.uniform() < 0.4;
    Segment1 s;
    s.target = press ? LeverWall::wall_angle + rng.uniform(0.02, 0.12) : rng.uniform(0.05, 0.30);
    s.move_s = tap ? rng.uniform(0.12, 0.25) : rng.uniform(0.25, 0.8);
    s.dwell_s = tap ? rng.uniform(0.0, 0.05) : rng.uniform(0.1, 0.6);
    return s;
  };
  IntentPlanner<double, decltype(next)> intent(0.15, next);

  const double count = 2.0 * std::numbers::pi / LeverWall::counts_per_rev;
  const double adc_lsb = 2.0 * LeverWall::gauge_range_n / 65536.0;
  double angle = 0.15, speed = 0.0, wall_torque = 0.0;
  double previous_counts = std::floor(angle / count);

  Trace trace;
  trace.dof = 1;
  const auto samples = static_cast<std::size_t>(std::llround(options.duration_s / kSamplePeriod));
  for (std::size_t k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) / 1000.0;
    for (int i = 0; i < kSubsteps; ++i) {
      const double target = intent.at(t + i * kStep);
      const double hand = LeverWall::hand_stiffness * (target - angle) - LeverWall::hand_damping * speed;
      const double penetration = angle - LeverWall::wall_angle;
      // A wall pushes, never pulls: the damper may not make it sticky on the way out.
      wall_torque = penetration > 0.0
                        ? std::max(0.0, LeverWall::wall_stiffness * penetration + LeverWall::wall_damping * speed)
                        : 0.0;
      speed += (hand - wall_torque - LeverWall::viscous * speed) / LeverWall::inertia * kStep;
      angle += speed * kStep;  // semi-implicit Euler: position from the new speed keeps the wall passive
    }
    trace.t.push_back(t);
    if (options.kind == TraceKind::velocity) {
      const double counts = std::floor(angle / count);
      trace.values.push_back(k == 0 ? 0.0 : (counts - previous_counts) * count / kSamplePeriod);
      previous_counts = counts;
    } else {
      const double force = wall_torque / LeverWall::arm + LeverWall::gauge_noise_n * rng.normal();
      const double code = std::clamp(std::round(force / adc_lsb), -32768.0, 32767.0);
      trace.values.push_back(code * adc_lsb);
    }
  }
  return trace;
}

struct P3 {
  double x = 0, y = 0, z = 0;
  P3 operator+(const P3& o) const { return {x + o.x, y + o.y, z + o.z}; }
  P3 operator-(const P3& o) const { return {x - o.x, y - o.y, z - o.z}; }
  P3 operator*(double s) const { return {x * s, y * s, z * s}; }
  double length() const { return std::sqrt(x * x + y * y + z * z); }
};

struct Segment3 {
  P3 target;
  double move_s, dwell_s;
};

// The paper's 3-DoF task: a cursor exploring a rigid sphere in a virtual environment, force by eq. (11).
struct SphereScene {
  static constexpr double radius = 0.05;         // m
  static constexpr double stiffness = 300.0;     // N/m, within what a desktop 3-DoF device renders stably
  static constexpr double position_lsb = 55e-6;  // m, a desktop device's nominal position resolution
};

Trace sphere_trace(const GeneratorOptions& options) {
  Rng rng(options.seed);
  auto random_direction = [&rng]() {
    while (true) {
      const P3 p{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 1)};
      const double len = p.length();
      if (len > 0.1 && len <= 1.0) return p * (1.0 / len);
    }
  };
  // The subjects in the paper were in contact about 87 % of the time: most waypoints lie inside the surface.
  auto next = [&](const P3& from) {
    const P3 direction = (from * (1.0 / from.length()) + random_direction() * 0.6);
    const bool contact = rng.uniform() < 0.85;
    const double distance = SphereScene::radius + (contact ? -rng.uniform(0.001, 0.008) : rng.uniform(0.003, 0.02));
    return Segment3{direction * (distance / direction.length()), rng.uniform(0.3, 0.9), rng.uniform(0.05, 0.4)};
  };
  const P3 start{0.0, 0.0, SphereScene::radius + 0.01};
  IntentPlanner<P3, decltype(next)> intent(start, next);

  Trace trace;
  trace.dof = 3;
  const auto samples = static_cast<std::size_t>(std::llround(options.duration_s / kSamplePeriod));
  for (std::size_t k = 0; k < samples; ++k) {
    const double t = static_cast<double>(k) / 1000.0;
    P3 cursor = intent.at(t);
    auto quantize = [](double v) { return std::round(v / SphereScene::position_lsb) * SphereScene::position_lsb; };
    cursor = {quantize(cursor.x), quantize(cursor.y), quantize(cursor.z)};
    const double distance = cursor.length();
    P3 force{};
    if (distance < SphereScene::radius && distance > 0.0)
      force = cursor * ((SphereScene::radius - distance) * SphereScene::stiffness / distance);
    trace.t.push_back(t);
    trace.values.insert(trace.values.end(), {force.x, force.y, force.z});
  }
  return trace;
}

}  // namespace

Trace generate_trace(const GeneratorOptions& options) {
  return options.kind == TraceKind::force3 ? sphere_trace(options) : lever_wall_trace(options);
}

std::string format_trace_csv(const Trace& trace) {
  std::string all;
  write_trace_csv(trace, [&all](std::string_view chunk) { all += chunk; });
  return all;
}

void write_trace_csv(const Trace& trace, const std::function<void(std::string_view)>& sink) {
  fmt::memory_buffer out;
  const std::string_view header = trace.dof == 1 ? "t,x\n" : "t,x,y,z\n";
  out.append(header.data(), header.data() + header.size());
  for (std::size_t i = 0; i < trace.samples(); ++i) {
    fmt::format_to(std::back_inserter(out), "{}", trace.t[i]);
    for (std::size_t d = 0; d < trace.dof; ++d) fmt::format_to(std::back_inserter(out), ",{}", trace.row(i)[d]);
    out.push_back('\n');
    if (out.size() > 64 * 1024) {
      sink({out.data(), out.size()});
      out.clear();
    }
  }
  sink({out.data(), out.size()});
}

}  // namespace lever::tool
