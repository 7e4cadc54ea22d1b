// Quasi-random points for a shot's rays: the first three dimensions of Sobol's sequence
// (Joe and Kuo's direction numbers), ray i taking point i. Each shot scrambles them by a
// random digital shift (an XOR of 32 bits per dimension, drawn from the shot's own stream)
// and each ray jitters its point below 2^-32 from its own stream, so every point is uniform
// on its own (the estimate stays unbiased) while a shot's points fill the unit cube evenly.
// A point depends only on (seed, shot, ray), for any thread count or split.
#pragma once

#include <array>
#include <cstdint>

#include "core/random.hpp"

namespace glaswave {

class SobolPoints {
 public:
  static constexpr int dimensions = 3;
  // What a ray draws from its point: the beam path's direction and first free path (Sobol'
  // dimensions 0, 1, 2), and the second path's direction (dimensions 0 and 1 again, under
  // shifts of their own).
  enum Use { beam_u1, beam_u2, beam_free_path, second_u1, second_u2, uses };

  SobolPoints(std::uint64_t seed, std::uint64_t shot);

  // Ray `ray`'s coordinate for `use`, in [0, 1), drawing its jitter from the ray's stream.
  double coordinate(std::uint64_t ray, Use use, RandomStream& random) const {
    const int dimension = use < dimensions ? use : use - dimensions;
    const double u = ((bits(ray, dimension) ^ shift_[use]) + random.uniform()) * 0x1.0p-32;
    return u < 1.0 ? u : 0x1.fffffffffffffp-1;  // the sum can round up to 2^32
  }

  // The unscrambled coordinate, as 32 bits: Sobol' point `index` (its lowest 32 bits).
  static std::uint32_t bits(std::uint64_t index, int dimension);

 private:
  std::array<std::uint32_t, uses> shift_{};
};

}  // namespace glaswave
