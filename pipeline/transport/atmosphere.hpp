// The atmosphere's layers in one shot's local frame, as the lidar's rays cross them (issue 40):
// free paths between scatterings, the layers' phase functions, the direct transmission of a
// straight line, and the single scattering that brings the light of a lit point into the field
// of view on its way back. Layers are horizontally uniform slabs in the frame's z; only what lies
// above the scene's top is crossed (the scene is traced as without an atmosphere).
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "core/vec3.hpp"
#include "footprints/atmosphere_settings.hpp"

namespace glaswave {

// Phase functions, normalised over the sphere (per sr), of the cosine of the scattering angle.
double phase_function(const AtmospherePhase& phase, double cos_angle);
// A cosine of the scattering angle drawn from the phase function with two uniform numbers.
double sample_phase_cosine(const AtmospherePhase& phase, double u1, double u2);

// The layers a space lidar's layer finder would report (ATL09's cloud and aerosol layers, GLAS's
// GLA09), as the simulation decides it: those whose backscatter at `band`, scattering coefficient
// times their phase function at 180 degrees, at least equals the molecules' at the layer's middle
// (a scattering ratio of 2 or more), the molecules being the Rayleigh layers and above-ground
// heights taken over sea level. Molecular layers are never reported. Indices into
// settings.layers, in their order.
std::vector<std::size_t> detected_layers(const AtmosphereSettings& settings, std::size_t band);

class AtmosphereModel {
 public:
  // `ground_z_m` is the frame's z of the ground under the footprint centre, `ground_height_m` its
  // height above the ellipsoid, `floor_z_m` the scene's top: layers are cut there.
  AtmosphereModel(const AtmosphereSettings& settings, std::size_t bands, double ground_z_m,
                  double ground_height_m, double floor_z_m);

  bool scatters() const { return scattering_column_ > 0.0; }
  double floor_z_m() const { return floor_z_m_; }
  // Vertical extinction optical depth of a band between two heights (clamped to the layers).
  double optical_depth(std::size_t band, double z_low, double z_high) const;
  // The whole column's, above the floor.
  double column_optical_depth(std::size_t band) const { return column_[band]; }
  // The top of the highest layer (the floor when there is none): a ray that `cross` gives up on
  // ends there when it left through the top, below it when it was lost.
  double top_z_m() const { return intervals_.empty() ? floor_z_m_ : intervals_.back().z1; }

  // Told of each scattering `cross` draws: where, the direction the ray arrived in, the phase
  // function of the layer that scattered it, and each band's weight after the scattering (its
  // albedo applied, before its new direction): `brf`'s local estimates toward the views.
  using ScatterSeen = std::function<void(const Vec3& point, const Vec3& arriving,
                                         const AtmospherePhase& phase, std::span<const double>)>;

  // Carries a ray from `position` (above the floor) along `direction` down to the floor: its
  // scatterings drawn (free paths by a band-independent scattering coefficient, each band's
  // weight carrying its own extinction and albedo), `path_m` lengthened by the way it went.
  // False when it is lost: it leaves the top going up, or scatters too often. `scatterings`, when
  // given, receives how often it scattered; `seen`, when given, is told of each scattering (it
  // draws no number: the ray's path is the same with or without it).
  bool cross(Vec3& position, Vec3& direction, double& path_m, std::span<double> weight,
             const std::function<double()>& uniform, int* scatterings = nullptr,
             const ScatterSeen* seen = nullptr) const;

  // Single scattering on the way back, sampled for a lit point. A height drawn by the column's
  // scattering (all bands summed) on the detector ray `down` (from `sensor`, pointing down) gives
  // the scattering point; `factor` receives per band the scattering coefficient there times the
  // layers' phase function for the angle between `up` (the light's direction from the lit point
  // to the scattering point) and -down, over the probability density of the point along the ray
  // (per m). False where nothing scatters.
  struct ScatterPoint {
    Vec3 point{};
    double z_m = 0.0;
  };
  bool scatter_point(const Vec3& sensor, const Vec3& down, double u, ScatterPoint& out) const;
  void scattering_factor(const ScatterPoint& at, const Vec3& down, double cos_angle,
                         std::span<double> factor) const;

 private:
  struct Slab {
    double z0 = 0.0, z1 = 0.0;
    std::vector<double> extinction, scattering;  // [band], per m
    double sampling = 0.0;                       // the largest of scattering, per m
    AtmospherePhase phase;
  };
  // Heights between consecutive boundaries of the slabs, and the slabs over each.
  struct Interval {
    double z0 = 0.0, z1 = 0.0;
    std::vector<double> extinction;  // [band], summed over its slabs
    double sampling = 0.0;           // summed
    double scattering_all = 0.0;     // all bands' scattering, summed
    std::vector<int> slabs;
  };
  int interval_at(double z, double dz) const;

  std::size_t bands_;
  double floor_z_m_;
  std::vector<Slab> slabs_;
  std::vector<Interval> intervals_;  // from the floor up, contiguous
  std::vector<double> column_;       // [band]
  double scattering_column_ = 0.0;   // all bands' scattering optical depth, summed
};

}  // namespace glaswave
