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
//
// A mesh has at most max_nodes_a_side lattice nodes a side. Where the region under the beam
// needs more, the relief is meshed on a coarser lattice of the same construction (its own
// noise), a node every correlation_m / 2, else every correlation_m: the RMS height stays the
// setting's, only detail finer than the correlation length goes. Where even that needs more, the
// configuration is refused (an error naming roughness/correlation_m and the limit): roughness is
// never smoothed away.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "core/error.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

// A square of a frame, about (x_m, y_m), where the relief is meshed.
struct RoughSquare {
  double x_m = 0.0, y_m = 0.0, half_size_m = 0.0;
};

class RoughnessField {
 public:
  RoughnessField(const RoughnessSettings& settings, std::uint64_t seed);

  bool enabled() const { return rms_m_ > 0.0; }
  double rms_m() const { return rms_m_; }
  double correlation_m() const { return correlation_m_; }
  // Of the finest lattice (and of the mesh it makes): correlation_m / 3.
  double spacing_m() const { return correlation_m_ / nodes_per_correlation[0]; }

  // The relief (m, up) at a geodetic position, on lattice `level` (0: the finest; see
  // nodes_per_correlation). A convolution per point: for tests and single points, not meshes.
  double height_m(double lat_deg, double lon_deg, int level = 0) const;

  // The base mesh with the relief added within `half_size_m` of the frame's origin: that part is
  // re-meshed on the finest lattice with at most max_nodes_a_side nodes a side over it, heights
  // from the base plus the relief, and the base triangles are clipped to the rest. The relief
  // tapers to nothing over the region's outer 2 correlation lengths, so that the two meet
  // without a step. Where the base's own spacing `base_spacing_m` is finer than the lattice, the
  // region is meshed that finely (up to 1024 nodes a side), so that the base's relief is kept.
  // Throws (naming roughness/correlation_m) where no lattice fits.
  GroundMesh roughen(const GroundMesh& base, const LocalFrame& frame, double half_size_m,
                     double base_spacing_m = std::numeric_limits<double>::infinity()) const;

  // The same within any of `squares` (the beams of the footprints sharing one scene): their
  // union is meshed on one lattice (each square within the node limit), the relief tapering over
  // the union's outer 2 correlation lengths; a point's relief is the same whichever squares hold
  // it, away from that taper. One square about the origin is the call above, bit for bit.
  GroundMesh roughen(const GroundMesh& base, const LocalFrame& frame,
                     const std::vector<RoughSquare>& squares,
                     double base_spacing_m = std::numeric_limits<double>::infinity()) const;

  // 1024 nodes a side: about 2 million triangles, some 200 MB of mesh and ray-tracing index.
  static constexpr std::int64_t max_nodes_a_side = 1024;
  // The lattices, finest first: nodes a correlation length.
  static constexpr std::array<int, 3> nodes_per_correlation = {3, 2, 1};

 private:
  // One lattice: its spacing, smoothing kernel and scale.
  struct Lattice {
    Lattice(double correlation_m, double rms_m, int nodes_per_correlation);
    double spacing_m;
    std::vector<double> kernel;  // taps -K..K along one axis
    double scale = 0.0;          // smoothed noise -> metres
  };
  Error too_fine(double half_size_m, std::int64_t nodes_a_side) const;

  double rms_m_;
  double correlation_m_;
  std::uint64_t seed_;
  std::vector<Lattice> lattices_;  // as nodes_per_correlation
};

}  // namespace glaswave
