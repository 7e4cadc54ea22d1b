// What grows on the terrain, behind one interface: a VegetationSource hands a shot the
// vegetation of a square region around its footprint, as geometry the scene holds (turbid
// volumes: crowns, a layer; surfaces: triangles with one material each), the optical materials
// that geometry's material numbers index, the truth under the beam and a memory estimate.
//
// A new source is one class and one registration in its own .cpp (VegetationRegistration below,
// keyed by the configuration's canopy kind): the engine and the transport do not change. The
// built-in sources (crowns and layers, facet trees, voxel grids, point clouds) add what they need
// to `Vegetation` and the scene; the transport's VolumeSpan and SurfaceHit stay as they are.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "canopy/vegetation_traits.hpp"
#include "core/part_kind.hpp"
#include "core/registry.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/scene/vegetation.hpp"
#include "pipeline/transport/scattering.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/terrain.hpp"
#include "terrain/terrain_settings.hpp"

namespace glaswave {

// A rectangle of a frame turned along a track (a strip of footprints sharing one scene): the
// points whose coordinates along `axis` (unit, horizontal) lie in [along0_m, along1_m] and across
// it (axis turned 90 degrees counter-clockwise) in [across0_m, across1_m].
struct RegionStrip {
  double axis_x = 0.0, axis_y = 1.0;
  double along0_m = 0.0, along1_m = 0.0, across0_m = 0.0, across1_m = 0.0;
  // Whether (x, y) lies within `margin_m` of the rectangle, in each direction.
  bool holds(double x_m, double y_m, double margin_m = 0.0) const {
    const double along = x_m * axis_x + y_m * axis_y, across = y_m * axis_x - x_m * axis_y;
    return along >= along0_m - margin_m && along <= along1_m + margin_m &&
           across >= across0_m - margin_m && across <= across1_m + margin_m;
  }
};

// A square region of the terrain around a footprint, in the footprint's local frame.
struct VegetationRegion {
  const Terrain& terrain;
  const LocalFrame& frame;
  double half_size_m = 0.0;   // the region is [-half_size_m, half_size_m]^2 east and north
  SurfaceOrientation ground;  // the footprint's mean ground (a layer follows it)
  std::size_t bands = 0;      // the materials' values are per band
  // Where given, only the square's part within this strip is needed: a source may leave out
  // what lies wholly outside it (crowns do), or grow the square.
  const RegionStrip* strip = nullptr;
};

// The vegetation of one region: what the scene holds, and the materials it is made of.
struct RegionVegetation {
  Vegetation geometry;
  // Indexed by the geometry's material numbers (crowns', layer's, surfaces'): only those the
  // region holds, so that a shot's cost depends on the materials it meets, not on how many the
  // run knows.
  std::vector<Foliage> materials;
};

struct VegetationKind;

class VegetationSource {
 public:
  // What a registration holds (core/registry.hpp): how to make a source of its kind, and what
  // one takes in memory.
  using Factory = VegetationKind;

  virtual ~VegetationSource() = default;

  // What grows in the region. Thread-safe: every thread of a run asks at once.
  virtual RegionVegetation grow(const VegetationRegion& region) const = 0;

  // The truth over a footprint (cover, PAI, canopy height, gap probability along vertical lines
  // under the beam, a Gaussian about the spot's centre; nadir_projection as measure_vegetation's).
  // By default measured on the scene's turbid volumes; a source of surfaces (leaf facets) says
  // what its facets make.
  virtual VegetationTruth truth(const Scene& scene, const BeamSpot& spot,
                                const std::vector<double>& nadir_projection) const;
  // Whether truth() is measure_vegetation's, which shots sharing a scene measure on one grid
  // (TruthGrid); false for a source that says its own.
  virtual bool measured_on_volumes() const { return true; }

  // Whether what grows in a region is the same in any frame that covers it (plants placed on the
  // Earth, as crowns are), so that shots may share a scene built around several footprints
  // (stretch_scenes.hpp); false for vegetation shaped by the footprint (a layer that follows its
  // mean ground) or resampled in its frame.
  virtual bool fixed_on_the_ground() const { return false; }
  // Whether a region's strip (VegetationRegion::strip) bounds what grows, as crowns do; false for
  // a source that grows the square holding it. For the memory estimate of a strip's scene.
  virtual bool grows_within_strips() const { return false; }

  // Plants a file placed (a crowns file's crowns): where each stands and how far it reaches,
  // for the warning that they lie far from every footprint. Empty for vegetation that grows
  // wherever a shot looks (random crowns, a layer).
  struct Placed {
    double lat_deg = 0.0, lon_deg = 0.0, radius_m = 0.0;
  };
  virtual std::vector<Placed> placed() const { return {}; }

  // Reads what grow() would read for the region and refuses what it refuses (a voxel grid's
  // missing or negative values under the beam), without making the geometry: `check` refuses
  // what `run` does. Nothing for sources whose values were checked when made.
  virtual void check_region(const VegetationRegion& /*region*/) const {}
  // Whether check_region reads anything: `check` sizes a region per footprint only for those.
  virtual bool checks_regions() const { return false; }
};

struct CloudGround;

// What a source is made from: the configuration's canopy, its seed and its plane terrain.
struct VegetationSettings {
  CanopySettings canopy;
  std::uint64_t seed = 1;
  std::optional<PlaneSettings> plane;  // crowns files may be in metres on the plane
  // canopy.point_cloud's ground as terrain.point_cloud gridded it (canopy/cloud_terrain.hpp), so
  // that the voxelisation does not grid it again; null: the source grids it.
  std::shared_ptr<const CloudGround> cloud_ground;
};

// One kind of source: how to make it, and what it takes in memory before it is made (the memory
// estimate, which reads at most the headers of its files): bytes of a region `side_m` across,
// which every thread's shot holds; bytes the source itself holds once for the run, at its peak
// (a point cloud's voxelisation, facet models; none when empty); and the key that makes it
// large, where a run too large for the machine is refused. A source whose region is counted in
// plants (a forest's trees) gives the bytes of one, so that a message may say how many.
//
// Each kind registers itself from its own .cpp, by its CanopySettings::kind, with a
// VegetationRegistration (below; a source the configuration need not name, a test's, may register
// its VegetationKind alone).
struct VegetationKind {
  std::function<std::unique_ptr<VegetationSource>(const VegetationSettings&)> make;
  std::function<double(const VegetationSettings&, double side_m)> region_bytes;
  std::function<double(const VegetationSettings&)> source_bytes;
  std::string memory_key = "/canopy";
  double plant_bytes = 0.0;  // of one plant, where the region is counted in plants; else 0
};

// One kind's registration, from its own .cpp: its declaration (Registry<PartKind<
// VegetationTraits>>, core/part_kind.hpp: the canopy's kinds the configuration reads, by the
// keys it declares) and how to make it (Registry<VegetationSource>), under one name
// (forest_source.cpp, voxel_source.cpp, facet_source.cpp; the shot library is linked whole):
//   const VegetationRegistration forest("forest", 0, {"crowns, stands and a layer",
//                                       {.keys = VegetationTraits::Keys::crowns}}, {...});
struct VegetationRegistration {
  VegetationRegistration(const std::string& name, int order,
                         PartKind<VegetationTraits>::Declaration declaration, VegetationKind kind)
      : declared(name, order, std::move(declaration)), made(name, order, std::move(kind)) {}
  Registration<PartKind<VegetationTraits>> declared;
  Registration<VegetationSource> made;
};

// The source of `settings.canopy.kind`. Throws a setting error at `kind` for an unknown name.
std::unique_ptr<VegetationSource> make_vegetation_source(const VegetationSettings& settings);

// Bytes a region `side_m` across of that source takes in a shot's scene.
double vegetation_region_bytes(const VegetationSettings& settings, double side_m);

// Bytes the source of `settings` holds once for the run, and the key that makes it large.
double vegetation_source_bytes(const VegetationSettings& settings);
std::string vegetation_memory_key(const VegetationSettings& settings);

// Bytes of one plant of the source of `settings`, where it counts its region in plants; else 0.
double vegetation_plant_bytes(const VegetationSettings& settings);

}  // namespace glaswave
