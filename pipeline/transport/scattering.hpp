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
// Each foliage's G toward the zenith (0 for a material of no leaf angles: facets, bark), for the
// truth's gap probability (pipeline/scene/vegetation.hpp).
std::vector<double> nadir_projection(const SceneOptics& optics);

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

// Where the accumulated optical depth along the ray reaches `target` within the spans
// (overlapping spans add their extinctions), and the extinction there; empty if the depth is
// never reached. Spans that begin beyond that point change neither.
struct FreePath {
  double distance_m;
  double extinction_per_m;
};
std::optional<FreePath> free_path_depth(const std::vector<VolumeSpan>& spans,
                                        const std::vector<double>& projection, double target);

// Which foliage the ray met at a free path's end: one of the spans covering the point, chosen
// in proportion to its extinction there (one uniform number).
template <class Uniform>
Interaction foliage_met(const std::vector<VolumeSpan>& spans, const std::vector<double>& projection,
                        const FreePath& path, Uniform&& uniform) {
  double pick = uniform() * path.extinction_per_m;
  const VolumeSpan* met = &spans.front();
  for (const VolumeSpan& span : spans) {
    if (span.start_m > path.distance_m || span.end_m <= path.distance_m) continue;
    met = &span;
    pick -= span.area_density_m2_m3 * projection[span.material];
    if (pick < 0.0) break;
  }
  return Interaction{path.distance_m, met->material, met->crown};
}

// What a ray meets first within (min_distance_m, limit_m]: a leaf, by free-path sampling to
// the optical depth `target` through the foliage (none: the scene has none), or a surface,
// whichever is nearer (PHYSICS.md section 8). The free path is found first, through the foliage
// up to the limit (crowns beyond its end are not searched): up to that end these are the spans
// before any surface, so the surfaces are searched only that far, and a ray that meets a leaf
// rarely traverses the ground's mesh. What is met is what searching the surfaces first, and
// the foliage up to them, finds, to the bit. `spans` is the caller's scratch, `projection` its G
// for the ray's direction.
struct ElementMet {
  SurfaceHit surface;               // the nearest within reach (the leaf's, when one is met)
  std::optional<Interaction> leaf;  // set when no surface comes before it
  int ray_queries = 1;              // the surfaces', and the foliage's when there is any
};
template <class Uniform>
ElementMet element_met(const Scene& scene, const Vec3& origin, const Vec3& direction,
                       double limit_m, double min_distance_m, std::optional<double> target,
                       std::vector<VolumeSpan>& spans, const std::vector<double>& projection,
                       Uniform&& uniform) {
  ElementMet met;
  std::optional<FreePath> free;
  if (target) {
    scene.volume_spans(origin, direction, limit_m, spans, *target, projection);
    free = free_path_depth(spans, projection, *target);
    ++met.ray_queries;
  }
  // Embree's range is in float: a little beyond the free path's end, so that rounding loses no
  // surface before it.
  met.surface = scene.intersect(origin, direction,
                                free ? std::min(free->distance_m * (1.0 + 1e-6), limit_m) : limit_m,
                                min_distance_m);
  if (free && (met.surface.kind == SurfaceKind::none || met.surface.distance_m >= free->distance_m))
    met.leaf = foliage_met(spans, projection, *free, uniform);
  return met;
}

// Optical depth along a connection ray whose first `shared_m` metres run close to a path
// already sampled, at separation angle `separation_rad`: over a length l the two paths are
// l * separation apart, and where that is less than a leaf they see the same gaps, so only a
// fraction 1 - exp(-l separation / leaf_size) of the foliage there is new (Kuusk's hotspot).
double connection_depth(const std::vector<VolumeSpan>& spans, const std::vector<double>& projection,
                        const std::vector<Foliage>& foliage, double shared_m,
                        double separation_rad);

// The element a surface hit is: ground, bark (trunks and wood facets) or a leaf facet.
inline RayElement surface_element(SurfaceKind kind) {
  return kind == SurfaceKind::ground ? RayElement::ground
         : kind == SurfaceKind::leaf ? RayElement::facet
                                     : RayElement::trunk;
}

// A direction about `normal`, cosine-weighted.
Vec3 cosine_direction(const Vec3& normal, double u1, double u2);

// The next travel direction of a path arriving along `direction` at an element of normal
// `normal`, drawn by the element's scattering (a leaf reflects or transmits by the bands'
// throughput-weighted reflectance and transmittance, then cosine-weighted; soil and bark are
// Lambertian), and the per-band `throughput` updated to carry the rest; false (nothing
// changed) when the element scatters nothing. `material` is the leaf's or trunk's foliage. A
// leaf facet scatters as a leaf, about its own normal: reflected to the side the path came
// from, transmitted to the other.
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
