#pragma once
// The few vector operations the sphere-3dof models need beyond lever/common/vec.hpp's.
#include <cmath>

#include "lever/hil/sphere3dof.hpp"

namespace lever::hil {

inline Vec3 add(const Vec3& a, const Vec3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
inline Vec3 scale(const Vec3& a, double k) { return {a[0] * k, a[1] * k, a[2] * k}; }
inline double dot(const Vec3& a, const Vec3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// The device can display no more than its peak force: the vector keeps its direction.
inline Vec3 saturate(const Vec3& f, double max_n) {
  const double m = norm(f);
  return m > max_n ? scale(f, max_n / m) : f;
}

inline Vec3 quantize(const Vec3& x, double resolution) {
  Vec3 q{};
  for (std::size_t i = 0; i < 3; ++i) q[i] = std::round(x[i] / resolution) * resolution;
  return q;
}

}  // namespace lever::hil
