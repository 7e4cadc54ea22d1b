// Sines and cosines of the angles that sampling draws (azimuths 2 pi u, leaf inclinations on a
// grid), from a table of nodes and a short series about the nearest node: the same values as
// std::sin and std::cos to a few units in the last place, at a fraction of their cost in the
// transport's inner loops.
#pragma once

#include <array>

namespace glaswave {

struct SinCos {
  double sin = 0.0, cos = 1.0;
};

// sin and cos of node + delta, from those of the node, for |delta| <= 0.013 rad: Taylor series
// whose first omitted terms are below 1e-20 relative.
inline SinCos rotate_small(const SinCos& node, double delta) {
  const double d2 = delta * delta;
  const double sin_delta = delta * (1.0 - d2 / 6.0 * (1.0 - d2 / 20.0 * (1.0 - d2 / 42.0)));
  const double cos_delta_m1 = -0.5 * d2 * (1.0 - d2 / 12.0 * (1.0 - d2 / 30.0 * (1.0 - d2 / 56.0)));
  return {node.sin + (node.sin * cos_delta_m1 + node.cos * sin_delta),
          node.cos + (node.cos * cos_delta_m1 - node.sin * sin_delta)};
}

constexpr int turn_nodes = 256;  // a power of two: u * turn_nodes is exact
// sin and cos of 2 pi k / turn_nodes for k = 0 .. turn_nodes.
extern const std::array<SinCos, turn_nodes + 1> turn_table;

// sin and cos of 2 pi u, for u in [0, 1].
inline SinCos sincos_turn(double u) {
  constexpr double two_pi = 6.283185307179586476925286766559;
  const double position = u * turn_nodes;
  const int k = static_cast<int>(position + 0.5);  // the nearest node: |delta| <= pi / 256
  return rotate_small(turn_table[k], two_pi / turn_nodes * (position - k));
}

}  // namespace glaswave
