// Counter-based random numbers: the stream of a ray depends only on (seed, shot, ray), as
// pbrt's samplers do (stream = hash(seed, shot), offset = ray index), so a shot's result is
// the same bits for any thread count and any split of the track.
#pragma once

#include <cstdint>
#include <pcg_random.hpp>

#include "core/bit_mix.hpp"

namespace glaswave {

class RayRandom {
 public:
  RayRandom(std::uint64_t seed, std::uint64_t shot, std::uint64_t ray)
      : engine_(mix(seed ^ mix(shot)), mix(shot + 0x9e3779b97f4a7c15ULL * (seed + 1))) {
    engine_.advance(ray << 32);  // 2^32 numbers a ray before streams could overlap
  }

  // Uniform in [0, 1).
  double uniform() {
    const std::uint64_t bits = (static_cast<std::uint64_t>(engine_()) << 21) ^ engine_();
    return static_cast<double>(bits & ((1ULL << 53) - 1)) * 0x1.0p-53;
  }

 private:
  // Neighbouring seeds and shots get unrelated streams.
  static constexpr auto mix = mix_bits;

  pcg32 engine_;
};

}  // namespace glaswave
