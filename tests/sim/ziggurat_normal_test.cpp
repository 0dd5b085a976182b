// The ziggurat sampler draws standard normal deviates: moments, tail probabilities and the
// whole distribution (Kolmogorov-Smirnov) match N(0, 1); the same stream gives the same numbers.
#include "sim/ziggurat_normal.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

using namespace posefuse::sim;

namespace {

double normal_cdf(double x) { return 0.5 * std::erfc(-x / std::sqrt(2.0)); }

std::vector<double> draws(std::uint64_t seed, std::size_t n) {
  SimRng rng(seed, "ziggurat_test");
  std::vector<double> out(n);
  for (double& x : out) x = ziggurat_normal(rng);
  return out;
}

}  // namespace

TEST(ZigguratNormal, MomentsAndTailsOfAStandardNormal) {
  const std::size_t n = 2'000'000;
  const std::vector<double> x = draws(3, n);
  double sum = 0, sum2 = 0, sum4 = 0;
  std::size_t beyond2 = 0, beyond3 = 0, beyond_tail = 0;
  for (const double v : x) {
    sum += v;
    sum2 += v * v;
    sum4 += v * v * v * v;
    beyond2 += std::abs(v) > 2.0;
    beyond3 += std::abs(v) > 3.0;
    beyond_tail += std::abs(v) > 3.442619855899;  // drawn by the tail method
  }
  const double mean = sum / n, variance = sum2 / n - mean * mean;
  // Standard errors: mean 1/sqrt(n) = 7e-4, variance sqrt(2/n) = 1e-3, 4th moment sqrt(96/n) = 7e-3.
  EXPECT_NEAR(mean, 0.0, 4e-3);
  EXPECT_NEAR(variance, 1.0, 5e-3);
  EXPECT_NEAR(sum4 / n, 3.0, 0.035);
  // P(|x| > 2) = 0.0455, P(|x| > 3) = 0.0027, P(|x| > r) = 5.76e-4; tolerances ~5 binomial sigmas.
  EXPECT_NEAR(static_cast<double>(beyond2) / n, 2 * normal_cdf(-2.0), 7e-4);
  EXPECT_NEAR(static_cast<double>(beyond3) / n, 2 * normal_cdf(-3.0), 1.8e-4);
  EXPECT_NEAR(static_cast<double>(beyond_tail) / n, 2 * normal_cdf(-3.442619855899), 9e-5);
}

TEST(ZigguratNormal, KolmogorovSmirnovAgainstTheNormalCdf) {
  const std::size_t n = 200'000;
  std::vector<double> x = draws(11, n);
  std::sort(x.begin(), x.end());
  double distance = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double cdf = normal_cdf(x[i]);
    distance = std::max({distance, cdf - static_cast<double>(i) / n, static_cast<double>(i + 1) / n - cdf});
  }
  // 1 % critical value 1.63 / sqrt(n) = 3.6e-3.
  EXPECT_LT(distance, 1.63 / std::sqrt(static_cast<double>(n)));
}

TEST(ZigguratNormal, SameStreamSameNumbers) {
  EXPECT_EQ(draws(5, 1000), draws(5, 1000));
  EXPECT_NE(draws(5, 1000), draws(6, 1000));
}
