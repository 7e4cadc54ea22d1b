// SplitMix64's finaliser: a bijective mix of 64 bits. Counter-based randomness keys its streams
// with it (seed, shot, ray; seed, ground tile; seed, lattice node), so neighbouring keys get
// unrelated numbers.
#pragma once

#include <cstdint>

namespace glaswave {

constexpr std::uint64_t mix_bits(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

}  // namespace glaswave
