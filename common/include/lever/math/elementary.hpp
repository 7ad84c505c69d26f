#pragma once
// exp, log, sin, cos and acos in double precision from +, -, *, / and sqrt alone, so that they give the same bits on
// every machine: the platform's libm does not (glibc uses FMA on arm64 and not on x86-64, newlib differs again), and
// a seeded simulation whose closed loop amplifies a last-bit difference must mean the same run everywhere. Accurate
// to about 1 ulp (tests/common/test_elementary.cpp measures it against libm), freestanding, no tables.
// The same bits need the same operations: the project compiles with -ffp-contract=off (lever_target_defaults), since
// GCC would otherwise fuse a*b+c into one FMA instruction on arm64 and not on x86-64.
// Method: argument reduction by Cody and Waite (a constant split so that its products with small integers are
// exact), then the Taylor series on the reduced range, summed by Horner's rule to beyond double precision.
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

namespace lever::math {

namespace detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kInf = std::numeric_limits<double>::infinity();

// 2^k for a k that keeps the result normal.
constexpr double pow2(int k) noexcept { return std::bit_cast<double>(static_cast<std::uint64_t>(k + 1023) << 52); }

// ln 2 = kLn2Hi + kLn2Lo, kLn2Hi with 42 significant bits: k * kLn2Hi is exact for |k| < 2^11.
inline constexpr double kLn2Hi = 0x1.62e42fefa3800p-1;
inline constexpr double kLn2Lo = 0x1.ef35793c76730p-45;
inline constexpr double kInvLn2 = 0x1.71547652b82fep+0;

// pi/2 = kPio2_1 + kPio2_2 + kPio2_3, the first two with 33 significant bits: n * each is exact for |n| < 2^20.
inline constexpr double kPio2_1 = 0x1.921fb54400000p+0;
inline constexpr double kPio2_2 = 0x1.0b4611a600000p-34;
inline constexpr double kPio2_3 = 0x1.3198a2e037073p-69;
inline constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
// pi/2 and pi as the nearest double and the remainder.
inline constexpr double kPio2Hi = 0x1.921fb54442d18p+0;
inline constexpr double kPio2Lo = 0x1.1a62633145c07p-54;
inline constexpr double kPiHi = 0x1.921fb54442d18p+1;
inline constexpr double kPiLo = 0x1.1a62633145c07p-53;
// sin and cos reduce by whole quarter turns up to here; beyond, their results would be noise anyway.
inline constexpr double kMaxTrigArgument = 0x1.0p20 * kPio2Hi;

// c[0] + x (c[1] + x (c[2] + ...)), innermost first.
template <int N>
constexpr double horner(double x, const double (&c)[N]) noexcept {
  double p = c[N - 1];
  for (int i = N - 2; i >= 0; --i) p = c[i] + x * p;
  return p;
}

// Nearest integer of x (ties away from zero) for |x| < 2^62, by conversion, which every machine does alike.
constexpr std::int64_t nearest(double x) noexcept { return static_cast<std::int64_t>(x < 0.0 ? x - 0.5 : x + 0.5); }

// sin r and cos r for |r| <= pi/4 (Taylor terms to r^17 and r^18: the next is below 2^-56 of the result).
constexpr double sin_kernel(double r) noexcept {
  const double z = r * r;
  constexpr double c[] = {-0x1.5555555555555p-3,  0x1.1111111111111p-7,  -0x1.a01a01a01a01ap-13, 0x1.71de3a556c734p-19,
                          -0x1.ae64567f544e4p-26, 0x1.6124613a86d09p-33, -0x1.ae7f3e733b81fp-41, 0x1.952c77030ad4ap-49};
  const double p = horner(z, c);
  return r + r * (z * p);
}
constexpr double cos_kernel(double r) noexcept {
  const double z = r * r;
  constexpr double c[] = {0x1.5555555555555p-5,  -0x1.6c16c16c16c17p-10, 0x1.a01a01a01a01ap-16, -0x1.27e4fb7789f5cp-22,
                          0x1.1eed8eff8d898p-29, -0x1.93974a8c07c9dp-37, 0x1.ae7f3e733b81fp-45, -0x1.6827863b97d97p-53};
  const double q = horner(z, c);
  return 1.0 - (0.5 * z - z * (z * q));
}

// asin x for |x| <= 1/2 (Taylor terms to x^51: the next is below 2^-56 of the result).
constexpr double asin_kernel(double x) noexcept {
  constexpr double c[] = {
      0x1.5555555555555p-3, 0x1.3333333333333p-4, 0x1.6db6db6db6db7p-5, 0x1.f1c71c71c71c7p-6, 0x1.6e8ba2e8ba2e9p-6,
      0x1.1c4ec4ec4ec4fp-6, 0x1.c99999999999ap-7, 0x1.7a87878787878p-7, 0x1.3fde50d79435ep-7, 0x1.12ef3cf3cf3cfp-7,
      0x1.df3bd37a6f4dfp-8, 0x1.a6863d70a3d71p-8, 0x1.782dda12f684cp-8, 0x1.51ba308d3dcb1p-8, 0x1.31683bdef7bdfp-8,
      0x1.15ee9d45d1746p-8, 0x1.fcaf8fb6db6dbp-9, 0x1.d3d2a8e0dd67dp-9, 0x1.b026f57b13b14p-9, 0x1.90cb77f60c7cep-9,
      0x1.750de64d7d05fp-9, 0x1.5c5f56efaaaabp-9, 0x1.464c0950f7d47p-9, 0x1.3275586c5f2f0p-9, 0x1.208d3570ae5a6p-9};
  const double z = x * x;
  return x + x * (z * horner(z, c));
}

}  // namespace detail

// e^x.
constexpr double exp(double x) noexcept {
  using namespace detail;
  if (x != x) return x;
  if (x > 0x1.62e42fefa39efp+9) return kInf;  // above ln(DBL_MAX)
  if (x < -0x1.74910d52d3052p+9) return 0.0;  // below ln of the smallest subnormal / 2
  // x = k ln2 + r, |r| <= ln2 / 2 (a little more where the rounding of x / ln2 goes the other way).
  const std::int64_t k = nearest(x * kInvLn2);
  const double kd = static_cast<double>(k);
  const double r = (x - kd * kLn2Hi) - kd * kLn2Lo;
  // e^r by its Taylor series to r^14 (the next term is below 2^-57).
  constexpr double c[] = {0x1.0000000000000p-1,  0x1.5555555555555p-3,  0x1.5555555555555p-5,  0x1.1111111111111p-7,
                          0x1.6c16c16c16c17p-10, 0x1.a01a01a01a01ap-13, 0x1.a01a01a01a01ap-16, 0x1.71de3a556c734p-19,
                          0x1.27e4fb7789f5cp-22, 0x1.ae64567f544e4p-26, 0x1.1eed8eff8d898p-29, 0x1.6124613a86d09p-33,
                          0x1.93974a8c07c9dp-37};
  const double p = horner(r, c);
  const double er = 1.0 + (r + r * (r * p));
  // Times 2^k in two steps where 2^k itself is not a normal double.
  const int ki = static_cast<int>(k);
  if (ki > 1023) return er * pow2(1023) * pow2(ki - 1023);
  if (ki < -1022) return er * pow2(ki + 1022) * pow2(-1022);
  return er * pow2(ki);
}

// The natural logarithm.
constexpr double log(double x) noexcept {
  using namespace detail;
  if (x != x) return x;
  if (x < 0.0) return kNaN;
  if (x == 0.0) return -kInf;
  if (x == kInf) return x;
  int e = 0;
  if (x < 0x1.0p-1022) {  // subnormal: make it normal first
    x *= 0x1.0p54;
    e = -54;
  }
  // x = 2^e m, m in [sqrt(2)/2, sqrt(2)).
  std::uint64_t bits = std::bit_cast<std::uint64_t>(x);
  e += static_cast<int>(bits >> 52) - 1023;
  bits = (bits & 0x000f'ffff'ffff'ffffULL) | 0x3ff0'0000'0000'0000ULL;
  double m = std::bit_cast<double>(bits);
  if (m > 0x1.6a09e667f3bcdp+0) {
    m *= 0.5;
    ++e;
  }
  // log m = log(1 + f) = 2 atanh s = 2s + 2s^3/3 + ..., s = f / (2 + f), |s| < 0.172; 2s = f - s f. Taylor terms to
  // s^23 (the next is below 2^-58 of the result).
  const double f = m - 1.0;
  const double s = f / (2.0 + f);
  const double z = s * s;
  constexpr double c[] = {0x1.5555555555555p-1, 0x1.999999999999ap-2, 0x1.2492492492492p-2, 0x1.c71c71c71c71cp-3,
                          0x1.745d1745d1746p-3, 0x1.3b13b13b13b14p-3, 0x1.1111111111111p-3, 0x1.e1e1e1e1e1e1ep-4,
                          0x1.af286bca1af28p-4, 0x1.8618618618618p-4, 0x1.642c8590b2164p-4};
  const double big_r = z * horner(z, c);
  const double log_m = f - s * (f - big_r);
  const double ed = static_cast<double>(e);
  return ed * kLn2Hi + (log_m + ed * kLn2Lo);
}

// sin x and cos x for |x| <= 2^20 pi/2; NaN beyond, where a double's spacing is a sizeable part of a turn.
constexpr double sin(double x) noexcept {
  using namespace detail;
  if (!(x >= -kMaxTrigArgument && x <= kMaxTrigArgument)) return kNaN;
  if (x == 0.0) return x;  // -0 stays -0
  // x = n pi/2 + r, |r| <= pi/4 (a little more where the rounding of x / (pi/2) goes the other way).
  const std::int64_t n = nearest(x * kTwoOverPi);
  const double nd = static_cast<double>(n);
  const double r = ((x - nd * kPio2_1) - nd * kPio2_2) - nd * kPio2_3;
  switch (n & 3) {
    case 0:
      return sin_kernel(r);
    case 1:
      return cos_kernel(r);
    case 2:
      return -sin_kernel(r);
    default:
      return -cos_kernel(r);
  }
}
constexpr double cos(double x) noexcept {
  using namespace detail;
  if (!(x >= -kMaxTrigArgument && x <= kMaxTrigArgument)) return kNaN;
  const std::int64_t n = nearest(x * kTwoOverPi);
  const double nd = static_cast<double>(n);
  const double r = ((x - nd * kPio2_1) - nd * kPio2_2) - nd * kPio2_3;
  switch (n & 3) {
    case 0:
      return cos_kernel(r);
    case 1:
      return -sin_kernel(r);
    case 2:
      return -cos_kernel(r);
    default:
      return sin_kernel(r);
  }
}

// arccos x in [0, pi]; NaN outside [-1, 1].
inline double acos(double x) noexcept {
  using namespace detail;
  if (!(x >= -1.0 && x <= 1.0)) return kNaN;
  if (x <= 0.5 && x >= -0.5) return kPio2Hi - (asin_kernel(x) - kPio2Lo);
  // acos x = 2 asin sqrt((1 - x) / 2), and acos(-x) = pi - acos x; 1 - |x| is exact here.
  const double a = 2.0 * asin_kernel(std::sqrt(0.5 * (1.0 - std::fabs(x))));
  return x > 0.0 ? a : kPiHi - (a - kPiLo);
}

}  // namespace lever::math
