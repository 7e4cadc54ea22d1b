// The table of sines and cosines over one turn.
#include "core/turn_trig.hpp"

#include <cmath>
#include <numbers>

namespace glaswave {

const std::array<SinCos, turn_nodes + 1> turn_table = [] {
  std::array<SinCos, turn_nodes + 1> table;
  for (int k = 0; k <= turn_nodes; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / turn_nodes;
    table[k] = {std::sin(angle), std::cos(angle)};
  }
  return table;
}();

}  // namespace glaswave
