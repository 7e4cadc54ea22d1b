// The scattering kernels that every transport through a scene shares (the lidar shots and the
// sun's photons of `brf`): the scene's optics, free paths through turbid foliage, the optical
// depth of a connection that keeps the hotspot, and the elements' scattering (bi-Lambertian
// leaves, Lambertian soil and bark), both sampled and evaluated.
#pragma once

#include <algorithm>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "canopy/leaf_angles.hpp"
#include "core/random.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/ray_event.hpp"

namespace glaswave {

// One kind of foliage (a stand's), values per band. Its elements are plant-area weighted:
// leaves are bi-Lambertian, bark inside crowns Lambertian and opaque, so reflectance =
// f_green rho_leaf + f_bark rho_bark and transmittance = f_green tau_leaf.
struct Foliage {
  std::vector<double> reflectance;
  std::vector<double> transmittance;
  std::vector<double> trunk_reflectance;  // Lambertian bark of the trunks
  const LeafAngles* leaf_angles = nullptr;
  // Leaf size: paths in and out that run within a leaf's width of each other see the same
  // gaps (the hotspot); 0 is the point-leaf turbid limit.
  double leaf_size_m = 0.0;
};

// Optical properties of the scene, one value per band.
struct SceneOptics {
  std::vector<double> soil_reflectance;  // Lambertian
  std::vector<Foliage> foliage;          // indexed by the crowns' and trunks' material
};

// Each foliage's projected leaf area G toward a direction of this cosine from the zenith, into
// projection (one value a foliage). Thousands of stands share a few leaf angle tables (one
// object each): one lookup a table.
void project_foliage(const SceneOptics& optics, double cos_zenith, std::vector<double>& projection);

// Embree's float geometry needs a path leaving a surface to start a little off it.
constexpr double surface_offset_m = 1e-4;
// Farther than anything in a shot's scene.
constexpr double far_m = 1.0e5;

// A leaf met by free-path sampling: how far along the ray, and in which foliage.
struct Interaction {
  double distance_m;
  int material;
  int crown;  // -1 for the layer
};

// Where the accumulated optical depth along the ray reaches `target`, within the spans
// (overlapping spans add their extinctions), and which foliage the ray met there, chosen in
// proportion to each one's extinction at that point; empty if the depth is never reached.
template <class Uniform>
std::optional<Interaction> free_path(const std::vector<VolumeSpan>& spans,
                                     const std::vector<double>& projection, double target,
                                     Uniform&& uniform) {
  if (spans.empty()) return std::nullopt;
  // One sweep over span ends: extinction added where a span starts, removed where it ends.
  thread_local std::vector<std::pair<double, double>> events;
  events.clear();
  for (const VolumeSpan& span : spans) {
    const double extinction = span.area_density_m2_m3 * projection[span.material];
    events.emplace_back(span.start_m, extinction);
    events.emplace_back(span.end_m, -extinction);
  }
  std::sort(events.begin(), events.end());
  double extinction = 0.0, depth = 0.0, t_previous = events.front().first;
  for (const auto& [t, change] : events) {
    if (extinction > 0.0 && t > t_previous) {
      const double step = extinction * (t - t_previous);
      if (depth + step >= target) {
        const double at = t_previous + (target - depth) / extinction;
        // The spans covering the point share the interaction by their extinction.
        double pick = uniform() * extinction;
        const VolumeSpan* met = &spans.front();
        for (const VolumeSpan& span : spans) {
          if (span.start_m > at || span.end_m <= at) continue;
          met = &span;
          pick -= span.area_density_m2_m3 * projection[span.material];
          if (pick < 0.0) break;
        }
        return Interaction{at, met->material, met->crown};
      }
      depth += step;
    }
    t_previous = t;
    extinction += change;
  }
  return std::nullopt;
}

// Optical depth along a connection ray whose first `shared_m` metres run close to a path
// already sampled, at separation angle `separation_rad`: over a length l the two paths are
// l * separation apart, and where that is less than a leaf they see the same gaps, so only a
// fraction 1 - exp(-l separation / leaf_size) of the foliage there is new (Kuusk's hotspot).
double connection_depth(const std::vector<VolumeSpan>& spans, const std::vector<double>& projection,
                        const std::vector<Foliage>& foliage, double shared_m,
                        double separation_rad);

// A direction about `normal`, cosine-weighted.
Vec3 cosine_direction(const Vec3& normal, double u1, double u2);

// The next travel direction of a path arriving along `direction` at an element of normal
// `normal`, drawn by the element's scattering (a leaf reflects or transmits by the bands'
// throughput-weighted reflectance and transmittance, then cosine-weighted; soil and bark are
// Lambertian), and the per-band `throughput` updated to carry the rest; false (nothing
// changed) when the element scatters nothing. `material` is the leaf's or trunk's foliage.
bool sample_scattering(RayElement element, const Foliage* material, const SceneOptics& optics,
                       const Vec3& normal, RayRandom& random, Vec3& direction,
                       std::span<double> throughput);

// What an element of normal `normal` sends along `outgoing` of light travelling along
// `incoming`, per unit throughput and per unit of the light's irradiance across its path:
// bi-Lambertian leaves (bilambertian_response), Lambertian soil and bark (reflectance times
// the cosine of incidence). Over pi it is the element's BRDF times that cosine.
double element_response(RayElement element, const Foliage* material, const SceneOptics& optics,
                        std::size_t band, const Vec3& normal, const Vec3& incoming,
                        const Vec3& outgoing);

}  // namespace glaswave
