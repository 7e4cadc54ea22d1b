// The shot's quasi-random points: Sobol's direction numbers as published, the nets they make,
// and scrambled coordinates that stay in [0, 1) and depend only on (seed, shot, ray).
#include "pipeline/transport/sobol_points.hpp"

#include <gtest/gtest.h>

#include <set>
#include <vector>

namespace glaswave {
namespace {

// Point 2^k of a dimension is its direction number v_k = m_k / 2^(k+1). The m_k of the
// second and third dimensions (polynomials x + 1 and x^2 + x + 1, initial m = 1 and 1, 3 as
// Joe and Kuo list them) worked by hand from Bratley and Fox's recurrence
// m_k = 2 a_1 m_{k-1} ^ ... ^ 2^s m_{k-s} ^ m_{k-s}.
TEST(SobolPoints, DirectionNumbersAreJoeAndKuos) {
  const std::vector<std::uint32_t> second = {1, 3, 5, 15, 17, 51};
  const std::vector<std::uint32_t> third = {1, 3, 3, 9, 29, 23};
  for (int k = 0; k < 6; ++k) {
    EXPECT_EQ(SobolPoints::bits(1ull << k, 0), 1u << (31 - k)) << k;
    EXPECT_EQ(SobolPoints::bits(1ull << k, 1), second[k] << (31 - k)) << k;
    EXPECT_EQ(SobolPoints::bits(1ull << k, 2), third[k] << (31 - k)) << k;
  }
  // Point 3 is points 1 and 2 combined (Sobol's digital construction).
  EXPECT_EQ(SobolPoints::bits(3, 2), SobolPoints::bits(1, 2) ^ SobolPoints::bits(2, 2));
}

// The first 2^m points of dimensions 0 and 1 form a (0, m, 2)-net: every box of 2^-a by 2^-b
// with a + b = m holds one point. Each dimension alone puts one point in each 2^-m interval.
TEST(SobolPoints, FirstTwoDimensionsFormANet) {
  constexpr int m = 10;
  auto top = [](std::uint32_t x, int bits) { return bits == 0 ? 0u : x >> (32 - bits); };
  for (int a = 0; a <= m; ++a) {
    std::set<std::pair<std::uint32_t, std::uint32_t>> boxes;
    for (std::uint64_t i = 0; i < (1u << m); ++i)
      boxes.insert({top(SobolPoints::bits(i, 0), a), top(SobolPoints::bits(i, 1), m - a)});
    EXPECT_EQ(boxes.size(), 1u << m) << a;
  }
  for (int dimension = 0; dimension < SobolPoints::dimensions; ++dimension) {
    std::set<std::uint32_t> intervals;
    for (std::uint64_t i = 0; i < (1u << m); ++i)
      intervals.insert(SobolPoints::bits(i, dimension) >> (32 - m));
    EXPECT_EQ(intervals.size(), 1u << m) << dimension;
  }
}

TEST(SobolPoints, ScrambledCoordinatesAreInTheUnitIntervalAndKeyedByShotAndRay) {
  const SobolPoints points(7, 3), again(7, 3), other_shot(7, 4);
  bool differs = false;
  for (std::uint64_t ray = 0; ray < 256; ++ray) {
    for (int use = 0; use < SobolPoints::uses; ++use) {
      RandomStream a(7, 3, ray), b(7, 3, ray), c(7, 3, ray);
      const auto u = static_cast<SobolPoints::Use>(use);
      const double x = points.coordinate(ray, u, a);
      EXPECT_GE(x, 0.0);
      EXPECT_LT(x, 1.0);
      EXPECT_EQ(x, again.coordinate(ray, u, b));
      differs = differs || x != other_shot.coordinate(ray, u, c);
    }
  }
  EXPECT_TRUE(differs);
}

}  // namespace
}  // namespace glaswave
