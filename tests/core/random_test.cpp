// The counter-based keying: the transport's streams pinned to the bits they have always had (a
// change would change every waveform), the purposes and keys apart, and uniforms that are
// uniform.
#include "core/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace glaswave {
namespace {

// Drawn with RayRandom before it moved to core/ (commit 531541b): the first three uniforms of
// three streams. The detector's key was then the seed XOR 0xd37ec70b5eed5a17.
TEST(RandomStream, TransportAndDetectorStreamsKeepTheirBits) {
  RandomStream ray(1, 2, 3);
  EXPECT_EQ(ray.uniform(), 0x1.0110efe6f5d66p-1);
  EXPECT_EQ(ray.uniform(), 0x1.c6ee36600366ap-2);
  EXPECT_EQ(ray.uniform(), 0x1.57e54bfa936d8p-3);
  RandomStream far_ray(3, 0, 199999);
  EXPECT_EQ(far_ray.uniform(), 0x1.0e78528ca17bap-2);
  EXPECT_EQ(far_ray.uniform(), 0x1.f8cc90c865daep-1);
  RandomStream bin(7, 5, (1u << 24) | 17, RandomPurpose::detector);
  EXPECT_EQ(bin.uniform(), 0x1.51203cd67ec3dp-1);
  EXPECT_EQ(bin.uniform(), 0x1.0ebbc4265f226p-1);
  EXPECT_EQ(bin.uniform(), 0x1.e85ae5de42449p-1);
}

TEST(RandomStream, DependsOnEveryPartOfItsKeyAndNothingElse) {
  const double first = RandomStream(1, 2, 3).uniform();
  EXPECT_EQ(first, RandomStream(1, 2, 3).uniform());
  std::set<double> others;
  for (const RandomStream& other :
       {RandomStream(1, 2, 4), RandomStream(1, 3, 3), RandomStream(2, 2, 3),
        RandomStream(1, 2, 3, RandomPurpose::detector), RandomStream(1, 2, 3, RandomPurpose::stand),
        RandomStream(1, 2, 3, RandomPurpose::roughness)})
    others.insert(RandomStream(other).uniform());
  others.insert(first);
  EXPECT_EQ(others.size(), 7u);
}

TEST(PairKey, TellsSignedPairsApart) {
  std::set<std::uint64_t> keys;
  for (std::int64_t a = -3; a <= 3; ++a)
    for (std::int64_t b = -3; b <= 3; ++b) keys.insert(pair_key(a, b));
  EXPECT_EQ(keys.size(), 49u);
  EXPECT_EQ(pair_key(0, 5), 5u);
  EXPECT_EQ(pair_key(1, 0), std::uint64_t{1} << 32);
}

// U[0, 1): mean 1/2, variance 1/12; n = 400000 draws across 4000 streams, tolerances 4 standard
// errors (sqrt(1/12 / n) for the mean, sqrt(1/180 / n) for the variance: Var((U-1/2)^2) = 1/180).
TEST(RandomStream, UniformsHaveTheMomentsOfU01) {
  constexpr int streams = 4000, per_stream = 100;
  constexpr double n = static_cast<double>(streams) * per_stream;
  double sum = 0.0, sum_sq = 0.0, lowest = 1.0, highest = 0.0;
  for (int s = 0; s < streams; ++s) {
    RandomStream random(11, 0, s);
    for (int k = 0; k < per_stream; ++k) {
      const double u = random.uniform();
      sum += u;
      sum_sq += (u - 0.5) * (u - 0.5);
      lowest = std::min(lowest, u);
      highest = std::max(highest, u);
    }
  }
  EXPECT_NEAR(sum / n, 0.5, 4.0 * std::sqrt(1.0 / 12.0 / n));
  EXPECT_NEAR(sum_sq / n, 1.0 / 12.0, 4.0 * std::sqrt(1.0 / 180.0 / n));
  EXPECT_GE(lowest, 0.0);
  EXPECT_LT(highest, 1.0);
}

// RandomStreams steps from a ray's stream to the next's: each the same draws as RandomStream keyed
// afresh, over consecutive rays, gaps stepped over and gaps keyed afresh, a ray asked again, and
// rays whose shift reaches the top bits.
TEST(RandomStreams, AreTheKeyedStreams) {
  const std::uint64_t rays[] = {0,
                                1,
                                2,
                                3,
                                7,
                                8,
                                8,
                                9,
                                65535,
                                65536,
                                65537,  // runs, gaps, a ray asked again
                                65569,
                                65602,  // gaps of RandomStreams::most_steps and one more
                                (1ull << 31) - 1,
                                1ull << 31,
                                (1ull << 32) - 2,
                                (1ull << 32) - 1,
                                5};
  for (const std::uint64_t seed : {0ull, 42ull})
    for (const std::uint64_t shot : {0ull, 99ull})
      for (const RandomPurpose purpose : {RandomPurpose::transport, RandomPurpose::photons}) {
        RandomStreams streams(seed, shot, purpose);
        for (const std::uint64_t ray : rays) {
          RandomStream stepped = streams.at(ray);
          RandomStream keyed(seed, shot, ray, purpose);
          for (int draw = 0; draw < 4; ++draw)
            ASSERT_EQ(stepped.uniform(), keyed.uniform()) << seed << " " << shot << " " << ray;
        }
      }
}

// ShotStreams keys many shots at one ray with a step each: the same draws as RandomStream keyed
// afresh, for rays from 0 to the top bits' and shots from 0 to 2^64 - 1.
TEST(ShotStreams, AreTheKeyedStreams) {
  const std::uint64_t rays[] = {0, 1, 11, 62 + 64 * 2, 65537, (1ull << 32) - 1};
  const std::uint64_t shots[] = {0, 1, 2, 99, pair_key(-3, 7), pair_key(123456, -654321), ~0ull};
  for (const std::uint64_t seed : {0ull, 2009ull})
    for (const RandomPurpose purpose : {RandomPurpose::transport, RandomPurpose::roughness})
      for (const std::uint64_t ray : rays) {
        const ShotStreams streams(seed, ray, purpose);
        for (const std::uint64_t shot : shots) {
          RandomStream stepped = streams.at(shot);
          RandomStream keyed(seed, shot, ray, purpose);
          for (int draw = 0; draw < 4; ++draw)
            ASSERT_EQ(stepped.uniform(), keyed.uniform()) << seed << " " << shot << " " << ray;
        }
      }
}

}  // namespace
}  // namespace glaswave
