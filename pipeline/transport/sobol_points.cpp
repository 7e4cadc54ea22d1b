// Sobol' points: direction numbers of the first three dimensions.
#include "pipeline/transport/sobol_points.hpp"

namespace glaswave {
namespace {

// Direction numbers v_k (k = 0..31) of a dimension from its primitive polynomial of degree s
// (x + 1: s = 1; x^2 + x + 1: s = 2, a = 1) and initial numbers m_1..m_s (Joe and Kuo 2008):
// v_k = v_{k-1} (if a) ^ v_{k-s} ^ (v_{k-s} >> s). The first dimension is van der Corput's.
struct DirectionNumbers {
  std::array<std::array<std::uint32_t, 32>, SobolPoints::dimensions> v{};
  DirectionNumbers() {
    for (int k = 0; k < 32; ++k) v[0][k] = 1u << (31 - k);
    v[1][0] = 1u << 31;  // x + 1, m_1 = 1
    for (int k = 1; k < 32; ++k) v[1][k] = v[1][k - 1] ^ (v[1][k - 1] >> 1);
    v[2][0] = 1u << 31;  // x^2 + x + 1, m = 1, 3
    v[2][1] = 3u << 30;
    for (int k = 2; k < 32; ++k) v[2][k] = v[2][k - 1] ^ v[2][k - 2] ^ (v[2][k - 2] >> 2);
  }
};

const DirectionNumbers direction_numbers;

}  // namespace

SobolPoints::SobolPoints(std::uint64_t seed, std::uint64_t shot) {
  RandomStream random(seed, shot, 0, RandomPurpose::beam_points);
  for (std::uint32_t& shift : shift_)
    shift = static_cast<std::uint32_t>(random.uniform() * 0x1.0p32);
}

std::uint32_t SobolPoints::bits(std::uint64_t index, int dimension) {
  const std::array<std::uint32_t, 32>& v = direction_numbers.v[dimension];
  std::uint32_t x = 0;
  auto i = static_cast<std::uint32_t>(index);
  for (int k = 0; i != 0; ++k, i >>= 1)
    if (i & 1u) x ^= v[k];
  return x;
}

}  // namespace glaswave
