// Random numbers for the world's noise models. Written out instead of using the
// standard library's engines and distributions, whose output the standard leaves to
// each library: one seed gives the same bits from the generators everywhere, and the
// same normals wherever the C library's exp and log round alike (glibc's do on every
// CPU it runs on), so a recorded run replays identically on another machine.
//
// The world draws its noise from many short streams rather than one long one: each
// robot's noise at each instant comes from a generator keyed by (run seed, robot id,
// time, purpose). What a robot reads then does not depend on which other robots sensed
// before it, in what order, or on which thread, so a run stepped on N threads gives the
// same result as on one.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <span>
#include <utility>

namespace rilbed::environment {

/// SplitMix64's finaliser: a bijective mix of 64 bits (Steele, Lea, Flood 2014).
constexpr std::uint64_t mix64(std::uint64_t z) {
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// What a keyed noise stream is for, so that two uses at the same (robot, time) never
/// share numbers.
enum class NoisePurpose : std::uint64_t {
  kSensing = 1,  ///< a robot's virtual sensors at an instant
  kWheels = 2,   ///< a robot's wheel slip over a world step
};

/// A small, fast generator (xoshiro256**, Blackman and Vigna 2018): 256 bits of state,
/// about 1 ns per 64-bit draw, period 2^256 - 1. Meets UniformRandomBitGenerator. A value
/// type: copy it to fork a stream.
class NoiseRng {
 public:
  using result_type = std::uint64_t;
  static constexpr result_type min() { return 0; }
  static constexpr result_type max() { return std::numeric_limits<result_type>::max(); }

  /// A stream from one 64-bit seed (its state filled by SplitMix64, never all zero).
  explicit NoiseRng(std::uint64_t seed = 0) {
    std::uint64_t x = seed;
    for (auto& word : state_) {
      x += 0x9e3779b97f4a7c15ULL;
      word = mix64(x);
    }
  }

  /// The stream for one (seed, robot, time, purpose): a pure function of the four, so
  /// that whoever asks, in whatever order, gets the same numbers.
  static NoiseRng keyed(std::uint64_t seed, std::int64_t robot_id, std::int64_t t_us, NoisePurpose purpose) {
    std::uint64_t h = mix64(seed ^ 0x6e6f697365ULL);
    h = mix64(h ^ static_cast<std::uint64_t>(robot_id));
    h = mix64(h ^ static_cast<std::uint64_t>(t_us));
    h = mix64(h ^ static_cast<std::uint64_t>(purpose));
    return NoiseRng(h);
  }

  /// The next 64 random bits.
  result_type operator()() {
    const std::uint64_t result = rotl(state_[1] * 5, 7) * 9;
    const std::uint64_t t = state_[1] << 17;
    state_[2] ^= state_[0];
    state_[3] ^= state_[1];
    state_[1] ^= state_[2];
    state_[0] ^= state_[3];
    state_[2] ^= t;
    state_[3] = rotl(state_[3], 45);
    return result;
  }

 private:
  static constexpr std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::array<std::uint64_t, 4> state_{};
};

/// A uniform number in [0, 1) made of 53 random bits from one 64-bit draw of `rng`.
template <class Rng>
inline double uniform01(Rng& rng) {
  static_assert(Rng::max() == std::numeric_limits<std::uint64_t>::max() && Rng::min() == 0,
                "needs 64 random bits per draw");
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

/// Two independent standard normal numbers (mean 0, standard deviation 1), by
/// Marsaglia's polar method. Returning the pair (rather than caching the second number
/// somewhere) keeps the draw a pure function of the generator's state.
template <class Rng>
inline std::pair<double, double> standard_normal_pair(Rng& rng) {
  for (;;) {
    const double u = 2.0 * uniform01(rng) - 1.0;
    const double v = 2.0 * uniform01(rng) - 1.0;
    const double s = u * u + v * v;
    if (s > 0.0 && s < 1.0) {
      const double f = std::sqrt(-2.0 * std::log(s) / s);
      return {u * f, v * f};
    }
  }
}

/// One standard normal number (draws a pair and drops the second).
template <class Rng>
inline double standard_normal(Rng& rng) {
  return standard_normal_pair(rng).first;
}

namespace detail {
/// Doornik's ZIGNOR tables (128 layers): x[i] the layers' right edges, ratio[i] =
/// x[i+1]/x[i]. Built once, thread-safely (a function-local static).
struct ZigguratTables {
  static constexpr int kLayers = 128;
  static constexpr double kTailStart = 3.442619855899;       // R
  static constexpr double kLayerArea = 9.91256303526217e-3;  // V
  std::array<double, kLayers + 1> x{};
  std::array<double, kLayers> ratio{};
  ZigguratTables() {
    double f = std::exp(-0.5 * kTailStart * kTailStart);
    x[0] = kLayerArea / f;  // the bottom layer, base and tail together
    x[1] = kTailStart;
    x[kLayers] = 0.0;
    for (int i = 2; i < kLayers; ++i) {
      x[static_cast<std::size_t>(i)] = std::sqrt(-2.0 * std::log(kLayerArea / x[static_cast<std::size_t>(i - 1)] + f));
      f = std::exp(-0.5 * x[static_cast<std::size_t>(i)] * x[static_cast<std::size_t>(i)]);
    }
    for (std::size_t i = 0; i < static_cast<std::size_t>(kLayers); ++i) ratio[i] = x[i + 1] / x[i];
  }
};
inline const ZigguratTables& ziggurat_tables() {
  static const ZigguratTables tables;
  return tables;
}
/// A uniform number in (0, 1), never 0 (for logarithms).
template <class Rng>
inline double uniform_open01(Rng& rng) {
  return (static_cast<double>(rng() >> 11) + 0.5) * 0x1.0p-53;
}
}  // namespace detail

namespace detail {
template <class Rng>
inline double fast_normal(Rng& rng, const ZigguratTables& z) {
  for (;;) {
    const std::uint64_t bits = rng();
    const double u = 2.0 * (static_cast<double>(bits >> 11) * 0x1.0p-53) - 1.0;  // top 53 bits
    const std::size_t i = bits & 0x7f;                                           // low 7 bits
    if (std::abs(u) < z.ratio[i]) return u * z.x[i];                             // inside the layer's rectangle
    if (i == 0) {
      // The bottom layer's tail beyond R (Marsaglia 1964).
      double x, y;
      do {
        x = std::log(uniform_open01(rng)) / ZigguratTables::kTailStart;
        y = std::log(uniform_open01(rng));
      } while (-2.0 * y < x * x);
      return u < 0.0 ? x - ZigguratTables::kTailStart : ZigguratTables::kTailStart - x;
    }
    // The wedge between this layer's rectangle and the curve.
    const double x = u * z.x[i];
    const double f0 = std::exp(-0.5 * (z.x[i] * z.x[i] - x * x));
    const double f1 = std::exp(-0.5 * (z.x[i + 1] * z.x[i + 1] - x * x));
    if (f1 + uniform01(rng) * (f0 - f1) < 1.0) return x;
  }
}
}  // namespace detail

/// One standard normal number by the ziggurat method (Marsaglia and Tsang 2000, in
/// Doornik's 2005 form, which takes the layer from bits independent of the uniform):
/// exactly normal, and about 99 % of draws cost one 64-bit draw and a multiply, against a
/// logarithm and a square root per pair for the polar method. The run's sensor and wheel
/// noise use it.
template <class Rng>
inline double fast_normal(Rng& rng) {
  return detail::fast_normal(rng, detail::ziggurat_tables());
}

/// Fills `out` with standard normals: the same numbers as out.size() calls of
/// fast_normal, drawn with the generator's state and the tables held locally.
template <class Rng>
inline void fast_normals(Rng& rng, std::span<double> out) {
  const detail::ZigguratTables& z = detail::ziggurat_tables();
  Rng local = rng;
  for (double& v : out) v = detail::fast_normal(local, z);
  rng = local;
}

}  // namespace rilbed::environment
