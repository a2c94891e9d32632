// The world's noise: keyed streams, and the ziggurat normal against the normal law.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <vector>

#include "environment/random.hpp"

namespace rilbed::environment {
namespace {

TEST(NoiseRng, KeyedStreamsArePureFunctionsOfTheirKey) {
  NoiseRng a = NoiseRng::keyed(7, 3, 100'000, NoisePurpose::kSensing);
  NoiseRng b = NoiseRng::keyed(7, 3, 100'000, NoisePurpose::kSensing);
  for (int i = 0; i < 100; ++i) EXPECT_EQ(a(), b());
  // Any part of the key changes the stream.
  std::set<std::uint64_t> firsts;
  for (const std::uint64_t seed : {7ULL, 8ULL})
    for (const int id : {3, 4})
      for (const std::int64_t t : {std::int64_t{100000}, std::int64_t{200000}})
        for (const NoisePurpose p : {NoisePurpose::kSensing, NoisePurpose::kWheels})
          firsts.insert(NoiseRng::keyed(seed, id, t, p)());
  EXPECT_EQ(firsts.size(), 16u);
}

TEST(NoiseRng, UniformNumbersFillTheUnitInterval) {
  NoiseRng rng(42);
  std::vector<int> bins(20, 0);
  const int n = 200'000;
  for (int i = 0; i < n; ++i) {
    const double u = uniform01(rng);
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    ++bins[static_cast<std::size_t>(u * 20)];
  }
  for (const int count : bins) EXPECT_NEAR(count, n / 20, 5 * std::sqrt(n / 20.0));
}

// The ziggurat's draws against the standard normal law: moments, tails, and the largest
// gap between the empirical and the true distribution function (Kolmogorov-Smirnov).
TEST(FastNormal, DrawsFollowTheStandardNormalLaw) {
  for (const std::uint64_t seed : {1ULL, 99ULL, 123456789ULL}) {
    NoiseRng rng(seed);
    const int n = 400'000;
    std::vector<double> x(n);
    double sum = 0.0, sum_sq = 0.0, sum_4 = 0.0;
    int beyond_2 = 0, beyond_3 = 0, beyond_tail = 0;
    for (double& v : x) {
      v = fast_normal(rng);
      ASSERT_TRUE(std::isfinite(v));
      sum += v;
      sum_sq += v * v;
      sum_4 += v * v * v * v;
      beyond_2 += std::abs(v) > 2.0;
      beyond_3 += std::abs(v) > 3.0;
      beyond_tail += std::abs(v) > 3.442619855899;  // drawn by the tail algorithm
    }
    const double mean = sum / n, var = sum_sq / n - mean * mean;
    EXPECT_NEAR(mean, 0.0, 5.0 / std::sqrt(n)) << "seed " << seed;
    EXPECT_NEAR(var, 1.0, 5.0 * std::sqrt(2.0 / n)) << "seed " << seed;
    EXPECT_NEAR(sum_4 / n, 3.0, 0.06) << "seed " << seed;  // kurtosis
    const double p2 = std::erfc(2.0 / std::sqrt(2.0)), p3 = std::erfc(3.0 / std::sqrt(2.0));
    EXPECT_NEAR(beyond_2, n * p2, 5 * std::sqrt(n * p2)) << "seed " << seed;
    EXPECT_NEAR(beyond_3, n * p3, 5 * std::sqrt(n * p3)) << "seed " << seed;
    EXPECT_GT(beyond_tail, 0) << "seed " << seed;
    std::sort(x.begin(), x.end());
    double ks = 0.0;
    for (int i = 0; i < n; ++i) {
      const double cdf = 0.5 * std::erfc(-x[static_cast<std::size_t>(i)] / std::sqrt(2.0));
      ks = std::max({ks, std::abs(cdf - static_cast<double>(i) / n), std::abs(cdf - static_cast<double>(i + 1) / n)});
    }
    // The 0.1 % critical value of the KS statistic is 1.95 / sqrt(n).
    EXPECT_LT(ks, 1.95 / std::sqrt(n)) << "seed " << seed;
  }
}

}  // namespace
}  // namespace rilbed::environment
