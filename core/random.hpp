// The one counter-based random keying of glaswave, as pbrt's samplers key theirs: a stream is
// fixed by (seed, shot, ray) and the purpose that draws from it, and its successive draws are
// the dimensions. A shot's numbers are then the same bits for any thread count and any split of
// the track. The transport keys rays by (seed, shot, ray); the detector bins by (seed, shot,
// band and bin); the photon-counting receiver its events by (seed, shot, beam and bin); stands
// tiles by (seed, tile, kind of canopy); roughness lattice nodes by (seed, node, zone); the sun's
// photons of `brf` by (seed, batch, photon).
#pragma once

#include <cstdint>
#include <pcg_random.hpp>

namespace glaswave {

// SplitMix64's finaliser: a bijective mix of 64 bits, so that neighbouring keys get unrelated
// streams.
constexpr std::uint64_t mix_bits(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Who draws: each purpose has streams of its own under the same seed. The transport's is 0, so
// its streams are keyed by the seed itself.
enum class RandomPurpose : std::uint64_t {
  transport = 0,
  detector = 0xd37ec70b5eed5a17ULL,
  stand = 0x57a9d7ee5c0ffee1ULL,
  roughness = 0x2009e1a7715ce5adULL,
  sun = 0x5a7b1e55f0c0ffeeULL,          // `brf`: photons traced from the sun
  beam_points = 0xb3a9501b01c0ffeeULL,  // the transport's scrambling of a shot's Sobol' points
  photons = 0x9407025c0a7e1a5eULL,      // photon counting: a shot's photon events by (beam, bin)
};

// Two signed indices (a 2-D grid's row and column, each within +-2^31) as one key.
constexpr std::uint64_t pair_key(std::int64_t high, std::int64_t low) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(high)) << 32) |
         static_cast<std::uint32_t>(low);
}

class RandomStream {
 public:
  RandomStream(std::uint64_t seed, std::uint64_t shot, std::uint64_t ray,
               RandomPurpose purpose = RandomPurpose::transport)
      : engine_(keyed(seed ^ static_cast<std::uint64_t>(purpose), shot, ray)) {}

  // Uniform in [0, 1): one dimension, two 32-bit draws.
  double uniform() {
    const std::uint64_t bits = (static_cast<std::uint64_t>(engine_()) << 21) ^ engine_();
    return static_cast<double>(bits & ((1ULL << 53) - 1)) * 0x1.0p-53;
  }

 private:
  static pcg32 keyed(std::uint64_t key, std::uint64_t shot, std::uint64_t ray) {
    pcg32 engine(mix_bits(key ^ mix_bits(shot)),
                 mix_bits(shot + 0x9e3779b97f4a7c15ULL * (key + 1)));
    engine.advance(ray << 32);  // 2^32 numbers a ray before streams could overlap
    return engine;
  }

  pcg32 engine_;
};

// The transport's name for its ray streams.
using RayRandom = RandomStream;

}  // namespace glaswave
