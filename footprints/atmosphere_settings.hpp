// The atmosphere on the lidar's path (`"atmosphere"`, PRODUCT.md section 12), as the configuration
// declares it and the transport uses it: horizontally uniform layers, each with its heights, an
// optical depth and a single-scattering albedo per band, and one phase function. The configuration
// expands a named preset into these layers; the transport never sees JSON.
#pragma once

#include <string>
#include <vector>

namespace glaswave {

// The angular distribution of a layer's scattering (normalised over the sphere): Rayleigh for
// molecules, Henyey-Greenstein of asymmetry g, or the two-term w HG(g1) + (1 - w) HG(g2).
struct AtmospherePhase {
  enum class Kind { rayleigh, henyey_greenstein, two_term_henyey_greenstein };
  Kind kind = Kind::rayleigh;
  double g1 = 0.0;      // hg_g, or hg2's first term
  double g2 = 0.0;      // hg2's second term
  double weight = 1.0;  // hg2's weight of the first term
};

// One layer. Heights are of its base and top above the ground under the footprint centre, or
// above the WGS84 ellipsoid when `above_ellipsoid`.
struct AtmosphereLayer {
  double base_m = 0.0;
  double top_m = 0.0;
  bool above_ellipsoid = false;
  std::vector<double> optical_depth;             // [band], vertical, extinction
  std::vector<double> single_scattering_albedo;  // [band]
  AtmospherePhase phase;
};

struct AtmosphereSettings {
  std::string preset;  // the preset the layers came from, or empty
  std::vector<AtmosphereLayer> layers;
};

}  // namespace glaswave
