// The scene of one shot, in its local east-north-up frame: the ground, tree trunks and facet
// trees (instances of shared models) as surfaces, crowns and a homogeneous layer as turbid
// volumes. Embree holds the geometry in
// single precision; ray origins are placed just above the scene so that float coordinates stay
// small (PHYSICS.md section 0).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "canopy/crown.hpp"
#include "pipeline/scene/facet_model.hpp"
#include "pipeline/scene/voxel_field.hpp"
#include "terrain/ground_mesh.hpp"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace glaswave {

// One Embree device per run, shared by every thread.
class RayDevice {
 public:
  RayDevice();
  ~RayDevice();
  RayDevice(const RayDevice&) = delete;
  RayDevice& operator=(const RayDevice&) = delete;
  RTCDeviceTy* handle() const { return device_; }

 private:
  RTCDeviceTy* device_;
};

// A horizontally homogeneous turbid slab (the RAMI HOM case) between two heights above the
// plane z = ground_slope_x * x + ground_slope_y * y (the footprint's mean ground).
struct TurbidLayer {
  double ground_slope_x = 0.0, ground_slope_y = 0.0;
  double bottom_m = 0.0, top_m = 0.0;
  double area_density_m2_m3 = 0.0;
  int material = 0;
};

// A facet tree: a shared model standing with its origin at `foot_m`, its +y axis turned to the
// azimuth `rotation_rad` (clockwise from north) and scaled by `scale`.
struct FacetInstance {
  std::shared_ptr<const FacetModel> model;
  Vec3 foot_m{};
  double rotation_rad = 0.0;
  double scale = 1.0;
};

// What grows on the ground of one shot.
struct Vegetation {
  std::vector<Crown> crowns;
  GroundMesh trunks;  // bark: triangles and grids (ForestSource's cylinders, a grid each)
  std::vector<int> trunk_materials;  // each trunk triangle's material, then each trunk grid's
  std::optional<TurbidLayer> layer;
  std::shared_ptr<const VoxelField> voxels;  // a voxel grid of plant area density, when given
  std::vector<FacetInstance> facets;
  // Per material number: whether a facet of it is a two-sided bi-Lambertian leaf (a hit of kind
  // `leaf`); the others are opaque and Lambertian, as bark (kind `trunk`).
  std::vector<char> leaf_materials;
};

// What a ray meets on a surface: the ground; bark (a trunk, or a wood facet), Lambertian; a leaf
// facet, two-sided bi-Lambertian.
enum class SurfaceKind { none, ground, trunk, leaf };

struct SurfaceHit {
  SurfaceKind kind = SurfaceKind::none;
  double distance_m = 0.0;  // along the ray from its origin
  Vec3 normal{};            // unit, on the side the ray came from
  int material = 0;         // of a trunk or a facet
};

// A stretch [start_m, end_m] of a ray inside turbid foliage of the given plant area density.
struct VolumeSpan {
  double start_m = 0.0, end_m = 0.0;  // distances along the ray
  double area_density_m2_m3 = 0.0;
  int material = 0;
  int crown = -1;  // index of the crown in Vegetation::crowns; -1 for the layer and voxels
};

class Scene {
 public:
  Scene(const RayDevice& device, const GroundMesh& ground, const Vegetation& vegetation = {});
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  // The nearest surface along origin + t * direction for t in (min_distance_m, max_distance_m].
  SurfaceHit intersect(const Vec3& origin, const Vec3& direction, double max_distance_m,
                       double min_distance_m = 0.0) const;

  // The ground alone along the ray within (0, max_distance_m]: what lies above it is passed
  // without a look.
  SurfaceHit ground_hit(const Vec3& origin, const Vec3& direction, double max_distance_m) const;

  // Whether any surface lies along the ray within (min_distance_m, max_distance_m).
  bool occluded(const Vec3& origin, const Vec3& direction, double max_distance_m,
                double min_distance_m) const;

  // Every stretch of the ray inside foliage for t in [0, max_distance_m], in no particular
  // order; overlapping crowns give overlapping spans. Cleared first.
  void volume_spans(const Vec3& origin, const Vec3& direction, double max_distance_m,
                    std::vector<VolumeSpan>& spans) const;

  // The same, for a free path of optical depth `depth`, a span's extinction being its density
  // times `extinction_per_density[material]`: the search stops short of crowns that lie wholly
  // beyond where one crown's foliage alone reaches that depth, as the free path ends before them.
  // Every span that starts before the free path's end is there, whole.
  void volume_spans(const Vec3& origin, const Vec3& direction, double max_distance_m,
                    std::vector<VolumeSpan>& spans, double depth,
                    const std::vector<double>& extinction_per_density) const;

  double top_m() const { return top_m_; }  // highest point of anything, local frame
  bool has_volumes() const { return !crowns_.empty() || layer_.has_value() || voxels_; }
  const std::vector<FacetInstance>& facets() const { return facets_; }

 private:
  SurfaceHit nearest(const Vec3& origin, const Vec3& direction, double max_distance_m,
                     double min_distance_m, unsigned mask) const;
  void collect_spans(const Vec3& origin, const Vec3& direction, double max_distance_m,
                     std::vector<VolumeSpan>& spans, double depth,
                     const std::vector<double>* extinction_per_density) const;

  RTCSceneTy* surfaces_;
  RTCSceneTy* crown_scene_ = nullptr;
  std::vector<Crown> crowns_;
  std::vector<CrownCrossing> crossings_;  // one a crown, made once
  std::vector<int> trunk_materials_;
  std::size_t trunk_triangles_ = 0;  // trunk_materials_' first entries
  std::optional<TurbidLayer> layer_;
  std::shared_ptr<const VoxelField> voxels_;
  std::vector<FacetInstance> facets_;
  std::vector<std::array<double, 2>> facet_turns_;  // each instance's (cos, sin) of its rotation
  std::vector<char> leaf_materials_;
  double top_m_;
};

}  // namespace glaswave
