#pragma once
// Fixed-size vectors for N-DoF samples. std::array keeps them trivially copyable and heap-free.
#include <array>
#include <cmath>
#include <cstddef>

namespace lever {

template <typename T, std::size_t N>
using Vec = std::array<T, N>;

// Euclidean norm exactly as sqrt(sum of squares), no hypot: the codec's decision must match an
// independent implementation of the rule bit for bit, and hypot rounds differently.
template <typename T, std::size_t N>
constexpr T norm(const Vec<T, N>& v) noexcept {
  if constexpr (N == 1) {
    return std::fabs(v[0]);  // sqrt(x*x) == |x| in IEEE arithmetic; fabs saves the sqrt.
  } else {
    T sum = v[0] * v[0];
    for (std::size_t i = 1; i < N; ++i) sum += v[i] * v[i];
    return std::sqrt(sum);
  }
}

// A named function, not operator-: Vec is a std::array, so an operator here would be invisible to ADL.
template <typename T, std::size_t N>
constexpr Vec<T, N> difference(const Vec<T, N>& a, const Vec<T, N>& b) noexcept {
  Vec<T, N> out{};
  for (std::size_t i = 0; i < N; ++i) out[i] = a[i] - b[i];
  return out;
}

}  // namespace lever
