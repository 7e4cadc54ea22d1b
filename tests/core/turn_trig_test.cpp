// The table of sines and cosines over a turn (core/turn_trig) against libm's.
#include "core/turn_trig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

namespace glaswave {
namespace {

constexpr double pi = std::numbers::pi;

// The tabled sines and cosines against libm's: about a node within 3e-16 (two units in the last
// place of 1); over a turn within 1e-15, the reference's own argument 2 pi u being rounded by up
// to 4.4e-16. Sampled directions are libm's to rounding.
TEST(TurnTrig, MatchesLibmToRounding) {
  std::mt19937_64 engine(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  for (int k = 0; k < 200000; ++k) {
    const double u = k < 1000 ? k / 1000.0 : uniform(engine);
    const SinCos turn = sincos_turn(u);
    EXPECT_NEAR(turn.sin, std::sin(2.0 * pi * u), 1e-15) << u;
    EXPECT_NEAR(turn.cos, std::cos(2.0 * pi * u), 1e-15) << u;
    const double node = 0.5 * pi * (k % 2048) / 2048.0,
                 delta = 0.013 * (2.0 * uniform(engine) - 1.0);
    const SinCos near = rotate_small({std::sin(node), std::cos(node)}, delta);
    EXPECT_NEAR(near.sin, std::sin(node + delta), 3e-16);
    EXPECT_NEAR(near.cos, std::cos(node + delta), 3e-16);
  }
}

}  // namespace
}  // namespace glaswave
