#include "lever/hil/omni_kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "lever/math/elementary.hpp"

namespace lever::hil {
namespace {

// atan2 on lever::math's acos (libm's atan2 differs in its last bits between machines): the angle of (c, s).
double angle(double s, double c) {
  const double r = std::sqrt(s * s + c * c);
  if (r == 0.0) return 0.0;
  const double a = math::acos(std::clamp(c / r, -1.0, 1.0));
  return s < 0.0 ? -a : a;
}

}  // namespace

OmniKinematics::OmniKinematics(const Vec<double, 3>& middle, double link_m, double counts_per_rev)
    : shoulder_{middle[0], middle[1] + link_m, middle[2] - link_m},
      l_(link_m),
      counts_per_rad_(counts_per_rev / (2.0 * std::numbers::pi)) {}

OmniJoints OmniKinematics::inverse(const Vec<double, 3>& tip) const {
  const double dx = tip[0] - shoulder_[0], dy = tip[1] - shoulder_[1], dz = tip[2] - shoulder_[2];
  const double reach = std::sqrt(dx * dx + dz * dz);  // horizontal, from the yaw axis
  OmniJoints q;
  q.yaw = angle(dx, dz);
  const double d = std::sqrt(reach * reach + dy * dy);
  // Two equal links: the upper arm sits half the elbow's opening above the line to the tip (elbow up).
  const double half_opening = math::acos(std::clamp(d / (2.0 * l_), -1.0, 1.0));
  q.shoulder = angle(dy, reach) + half_opening;
  const double fx = reach - l_ * math::cos(q.shoulder), fy = dy - l_ * math::sin(q.shoulder);
  q.forearm = angle(fx, -fy);
  return q;
}

Vec<double, 3> OmniKinematics::forward(const OmniJoints& q) const {
  const double reach = l_ * math::cos(q.shoulder) + l_ * math::sin(q.forearm);
  return {shoulder_[0] + reach * math::sin(q.yaw),
          shoulder_[1] + l_ * math::sin(q.shoulder) - l_ * math::cos(q.forearm),
          shoulder_[2] + reach * math::cos(q.yaw)};
}

OmniJoints OmniKinematics::quantized(const OmniJoints& q) const {
  auto whole = [&](double a) { return std::round(a * counts_per_rad_) / counts_per_rad_; };
  return {whole(q.yaw), whole(q.shoulder), whole(q.forearm)};
}

}  // namespace lever::hil
