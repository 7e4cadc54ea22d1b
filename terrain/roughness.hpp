// Random sub-grid relief of the ground (terrain.roughness): a Gaussian random field of RMS height
// `rms_m` and correlation length `correlation_m`, fixed by geodetic position and the run's seed,
// so that overlapping footprints see the same relief, and added to a shot's ground mesh by
// subdividing it under the beam.
//
// The field lives on a lattice of the UTM (or UPS) grid of the standard zone, nodes every
// correlation_m / 3 in easting and northing. Node values are white Gaussian noise, hashed from
// (seed, zone, node), smoothed by a Gaussian kernel so that their covariance falls as
// exp(-r^2 / correlation_m^2); between nodes the relief is linear on the triangles of the
// lattice (diagonal from node (i, j) to (i + 1, j + 1)), which is exactly what the mesh holds.
// The values are scaled so that the RMS of that piecewise-linear surface over any large area
// is rms_m: Gardner's roughness term (PHYSICS.md section 2) sees the mesh, not the nodes.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "terrain/ground_mesh.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

class RoughnessField {
 public:
  RoughnessField(const RoughnessSettings& settings, std::uint64_t seed);

  bool enabled() const { return rms_m_ > 0.0; }
  double rms_m() const { return rms_m_; }
  double correlation_m() const { return correlation_m_; }
  double spacing_m() const { return spacing_m_; }  // of the lattice (and of the mesh it makes)

  // The relief (m, up) at a geodetic position. A convolution per point: for tests and single
  // points, not for meshes.
  double height_m(double lat_deg, double lon_deg) const;

  // The base mesh with the relief added within `half_size_m` of the frame's origin: that part is
  // re-meshed on the lattice, heights from the base plus the relief, and the base triangles are
  // clipped to the rest. The relief tapers to nothing over the region's outer 2 correlation
  // lengths, so that the two meet without a step. At most `max_nodes` lattice nodes: a larger
  // region is shrunk about the origin (the lattice spacing, which defines the field, never
  // changes). Where the base's own spacing `base_spacing_m` is finer than the lattice, the
  // region is meshed that finely, so that the base's relief is kept.
  GroundMesh roughen(const GroundMesh& base, const LocalFrame& frame, double half_size_m,
                     double base_spacing_m = std::numeric_limits<double>::infinity()) const;

  static constexpr std::int64_t max_nodes = 512 * 512;

 private:
  double rms_m_;
  double correlation_m_;
  double spacing_m_;
  std::uint64_t seed_;
  std::vector<double> kernel_;  // taps -K..K along one axis
  double scale_ = 0.0;          // smoothed noise -> metres
};

}  // namespace glaswave
