// The normal and Poisson samplers against the moments and probabilities of their distributions.
// Each check allows 4 standard errors of its estimate (5 where one test makes many checks), so a
// correct sampler fails it with a probability under 1e-4 at any seed.
#include "core/samplers.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/random.hpp"

namespace glaswave {
namespace {

constexpr int kSamples = 200000;

// Var(x^2) = 2 for a standard normal; P(|x| < 1) = erf(1 / sqrt 2) = 0.682689492.
TEST(StandardNormal, HasTheMomentsAndTheOneSigmaProbability) {
  double sum = 0.0, sum_sq = 0.0, within = 0.0;
  for (int i = 0; i < kSamples; ++i) {
    RandomStream random(5, 1, i);
    const double x = standard_normal(random);
    sum += x;
    sum_sq += x * x;
    within += std::abs(x) < 1.0;
  }
  const double n = kSamples, p = 0.682689492;
  EXPECT_NEAR(sum / n, 0.0, 4.0 / std::sqrt(n));
  EXPECT_NEAR(sum_sq / n, 1.0, 4.0 * std::sqrt(2.0 / n));
  EXPECT_NEAR(within / n, p, 4.0 * std::sqrt(p * (1.0 - p) / n));
}

// Mean mu and variance mu on both sides of the switch to PTRS (10), and far beyond it: the
// sample variance has a standard error of sqrt((mu + 2 mu^2) / n) for Poisson counts.
TEST(Poisson, HasMeanAndVarianceMuForSmallAndLargeMeans) {
  for (double mu : {0.3, 4.0, 9.99, 10.0, 37.5, 1.0e4, 1.0e9}) {
    SCOPED_TRACE(mu);
    double sum = 0.0, sum_sq = 0.0;
    bool whole = true;
    for (int i = 0; i < kSamples; ++i) {
      RandomStream random(6, 2, i);
      const double k = poisson(random, mu);
      whole = whole && k >= 0.0 && k == std::floor(k);
      sum += k;
      sum_sq += (k - mu) * (k - mu);
    }
    const double n = kSamples;
    EXPECT_TRUE(whole);
    EXPECT_NEAR(sum / n, mu, 4.0 * std::sqrt(mu / n));
    EXPECT_NEAR(sum_sq / n, mu, 4.0 * std::sqrt((mu + 2.0 * mu * mu) / n));
  }
  RandomStream random(6, 3, 0);
  EXPECT_EQ(poisson(random, 0.0), 0.0);
  EXPECT_EQ(poisson(random, -1.0), 0.0);
}

// The probability of each count within two sigmas of the mean against e^-mu mu^k / k!, for a mean
// of each branch; 5 standard errors of a binomial frequency, as there are many counts.
TEST(Poisson, GivesEachCountItsProbability) {
  for (double mu : {3.0, 25.0}) {
    SCOPED_TRACE(mu);
    std::vector<double> counts(200, 0.0);
    for (int i = 0; i < kSamples; ++i) {
      RandomStream random(8, 4, i);
      counts[static_cast<std::size_t>(poisson(random, mu))] += 1.0;
    }
    const double n = kSamples;
    for (int k = static_cast<int>(mu - 2.0 * std::sqrt(mu)); k <= mu + 2.0 * std::sqrt(mu); ++k) {
      if (k < 0) continue;
      const double p = std::exp(-mu + k * std::log(mu) - std::lgamma(k + 1.0));
      EXPECT_NEAR(counts[k] / n, p, 5.0 * std::sqrt(p * (1.0 - p) / n)) << "k = " << k;
    }
  }
}

}  // namespace
}  // namespace glaswave
