// Sine, cosine and atan2 by short polynomials, for inner loops that call them per
// object per frame (the tracked decoder calls three per marker). The C library's
// versions cost several times as much, for the last ulp and for special cases these
// callers never pass (NaN, infinities, huge angles).
#pragma once

#include <cmath>
#include <iterator>

#include "core/geometry.hpp"

namespace rilbed {

/// sin(a) and cos(a) for `a` in radians with |a| < 1e6, to within 1e-15 absolute of
/// std::sin and std::cos.
inline void fast_sincos(double a, double& sin_out, double& cos_out) {
  // The nearest quarter turn k (rounded by truncating a half away from zero); the rest
  // r lies in [-pi/4, pi/4], where the Taylor series to the 15th power (sine) and 16th
  // (cosine) are within 1e-16 of the truth.
  constexpr double kTwoOverPi = 2.0 / kPi;
  // pi/2 in two parts (Cody-Waite): k times the first is exact, so r keeps its digits.
  constexpr double kHalfPiHigh = 1.5707963267341256e+00, kHalfPiLow = 6.0771005065061922e-11;
  const double scaled = a * kTwoOverPi;
  const auto k = static_cast<long long>(scaled + (scaled >= 0.0 ? 0.5 : -0.5));
  const double r = (a - static_cast<double>(k) * kHalfPiHigh) - static_cast<double>(k) * kHalfPiLow;
  const double r2 = r * r;
  // Horner in r^2 with 1/n! coefficients.
  const double s =
      r * (1.0 + r2 * (-1.0 / 6 +
                       r2 * (1.0 / 120 +
                             r2 * (-1.0 / 5040 + r2 * (1.0 / 362880 +
                                                       r2 * (-1.0 / 39916800 + r2 * (1.0 / 6227020800 +
                                                                                     r2 * (-1.0 / 1307674368000))))))));
  const double c =
      1.0 +
      r2 * (-0.5 + r2 * (1.0 / 24 +
                         r2 * (-1.0 / 720 + r2 * (1.0 / 40320 +
                                                  r2 * (-1.0 / 3628800 + r2 * (1.0 / 479001600 +
                                                                               r2 * (-1.0 / 87178291200 +
                                                                                     r2 * (1.0 / 20922789888000))))))));
  switch (k & 3) {  // two's complement: k & 3 is k mod 4 for negative k too
    case 0:
      sin_out = s;
      cos_out = c;
      break;
    case 1:
      sin_out = c;
      cos_out = -s;
      break;
    case 2:
      sin_out = -s;
      cos_out = -c;
      break;
    default:
      sin_out = -c;
      cos_out = s;
      break;
  }
}

/// atan2(y, x) in radians, in [-pi, pi], to within 1e-12 of std::atan2 for finite
/// inputs; 0 when both are 0.
inline double fast_atan2(double y, double x) {
  const double ax = std::abs(x), ay = std::abs(y);
  const double big = ax > ay ? ax : ay, small = ax > ay ? ay : ax;
  if (!(big > 0.0)) return 0.0;
  // t = small / big in [0, 1]. Above tan(pi/8), atan t = pi/4 + atan((t - 1) / (t + 1))
  // brings it within tan(pi/8) of 0, where the alternating series t - t^3/3 + ... to
  // the 27th power is within the next term, tan(pi/8)^29 / 29 < 3e-13, of the truth.
  double t = small / big, offset = 0.0;
  constexpr double kTanPiOver8 = 0.41421356237309503;
  if (t > kTanPiOver8) {
    t = (t - 1.0) / (t + 1.0);
    offset = 0.25 * kPi;
  }
  const double t2 = t * t;
  // (-1)^j / (2j + 1) for the powers 1, 3, ..., 27, summed by Horner in t^2.
  constexpr double kSeries[] = {1.0,       -1.0 / 3, 1.0 / 5,   -1.0 / 7, 1.0 / 9,   -1.0 / 11, 1.0 / 13,
                                -1.0 / 15, 1.0 / 17, -1.0 / 19, 1.0 / 21, -1.0 / 23, 1.0 / 25,  -1.0 / 27};
  double p = 0.0;
  for (int j = static_cast<int>(std::size(kSeries)) - 1; j >= 0; --j) p = kSeries[j] + t2 * p;
  double angle = offset + t * p;
  if (ay > ax) angle = 0.5 * kPi - angle;
  if (x < 0.0) angle = kPi - angle;
  return y < 0.0 ? -angle : angle;
}

}  // namespace rilbed
