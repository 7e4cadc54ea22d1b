// Embree scenes of the ground, trunks and crowns in a shot's local frame.
#include "pipeline/scene/scene.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/error.hpp"

namespace glaswave {
namespace {

constexpr unsigned ground_geometry = 0;
// Trunks' triangles are geometry 1, the ground's grids 2, the trunks' grids 3; facet tree k is
// instance geometry first_facet + k.
constexpr unsigned trunk_geometry = 1, ground_grid_geometry = 2, trunk_grid_geometry = 3;
constexpr unsigned first_facet = 4;
// Ray masks: the ground's bit, and every other surface's; a ray for the ground alone skips the
// trees at the instances' level.
constexpr unsigned ground_mask = 1u, vegetation_mask = 2u;

void check_device(RTCDevice device, const char* what) {
  const RTCError code = rtcGetDeviceError(device);
  if (code != RTC_ERROR_NONE)
    throw run_error("Embree", std::string(what) + " failed (error " + std::to_string(code) + ")");
}

void attach_mesh(RTCDevice device, RTCScene scene, const GroundMesh& mesh, unsigned id) {
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               mesh.vertices_m.size() / 3));
  auto* triangles = static_cast<unsigned*>(
      rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                              3 * sizeof(unsigned), mesh.triangles.size() / 3));
  check_device(device, "allocating a mesh");
  std::memcpy(vertices, mesh.vertices_m.data(), mesh.vertices_m.size() * sizeof(float));
  std::memcpy(triangles, mesh.triangles.data(), mesh.triangles.size() * sizeof(unsigned));
  rtcSetGeometryMask(geometry, id == ground_geometry ? ground_mask : vegetation_mask);
  rtcCommitGeometry(geometry);
  rtcAttachGeometryByID(scene, geometry, id);
  rtcReleaseGeometry(geometry);
}

// The mesh's grids as one Embree grid geometry: built over the grids' rectangles without a
// triangle each, and intersected as the same triangles (Embree cuts a grid's cell (x, y) by the
// diagonal from node (x + 1, y) to (x, y + 1), so each row is handed over right to left to keep
// triangulate_grid's diagonal). A hit's primID is its grid's index.
void attach_grids(RTCDevice device, RTCScene scene, const GroundMesh& mesh, unsigned id) {
  std::size_t nodes = 0;
  for (const MeshGrid& grid : mesh.grids) nodes += grid.nodes.size();
  RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_GRID);
  auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), nodes));
  auto* grids = static_cast<RTCGrid*>(rtcSetNewGeometryBuffer(
      geometry, RTC_BUFFER_TYPE_GRID, 0, RTC_FORMAT_GRID, sizeof(RTCGrid), mesh.grids.size()));
  check_device(device, "allocating a mesh's grids");
  unsigned first = 0;
  for (std::size_t g = 0; g < mesh.grids.size(); ++g) {
    const MeshGrid& grid = mesh.grids[g];
    grids[g] = {first, static_cast<unsigned>(grid.width), static_cast<unsigned short>(grid.width),
                static_cast<unsigned short>(grid.height)};
    for (int b = 0; b < grid.height; ++b)
      for (int a = grid.width - 1; a >= 0; --a) {
        const std::uint32_t v = grid.nodes[static_cast<std::size_t>(b) * grid.width + a];
        std::memcpy(vertices, &mesh.vertices_m[3 * std::size_t{v}], 3 * sizeof(float));
        vertices += 3;
      }
    first += static_cast<unsigned>(grid.nodes.size());
  }
  rtcSetGeometryMask(geometry, id == ground_grid_geometry ? ground_mask : vegetation_mask);
  rtcCommitGeometry(geometry);
  rtcAttachGeometryByID(scene, geometry, id);
  rtcReleaseGeometry(geometry);
}

// A facet tree as an instance of its model's scene: x' = foot + scale R(rotation) x, the
// model's +y turned to the azimuth (clockwise from north).
void attach_facet(const RayDevice& device, RTCScene scene, const FacetInstance& tree,
                  const std::array<double, 2>& turn, unsigned id) {
  RTCGeometry geometry = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_INSTANCE);
  rtcSetGeometryInstancedScene(geometry, tree.model->scene_on(device));
  const double c = tree.scale * turn[0], s = tree.scale * turn[1];
  const float transform[12] = {static_cast<float>(c),
                               static_cast<float>(-s),
                               0.0f,
                               static_cast<float>(s),
                               static_cast<float>(c),
                               0.0f,
                               0.0f,
                               0.0f,
                               static_cast<float>(tree.scale),
                               static_cast<float>(tree.foot_m[0]),
                               static_cast<float>(tree.foot_m[1]),
                               static_cast<float>(tree.foot_m[2])};
  rtcSetGeometryTransform(geometry, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, transform);
  rtcSetGeometryMask(geometry, vegetation_mask);
  rtcCommitGeometry(geometry);
  rtcAttachGeometryByID(scene, geometry, id);
  rtcReleaseGeometry(geometry);
}

// Crowns are Embree user geometry: their callbacks record every crossing and accept none as a
// hit, so that traversal goes on to every crown along the ray.
struct SpanCollector {
  RTCIntersectContext context;  // first, so Embree's context pointer is ours
  const std::vector<Crown>* crowns;
  const std::vector<CrownCrossing>* crossings;
  std::vector<VolumeSpan>* spans;
  Vec3 origin, direction;  // in double: the float ray is only for traversal
  double max_distance_m;   // spans end here at the latest
  // For a free path: its optical depth, and each material's extinction per unit density.
  double depth = 0.0;
  const std::vector<double>* extinction_per_density = nullptr;
};

void crown_bounds(const RTCBoundsFunctionArguments* args) {
  const auto& crown =
      static_cast<const std::vector<Crown>*>(args->geometryUserPtr)->at(args->primID);
  const double r = crown.radius_m;
  args->bounds_o->lower_x = static_cast<float>(crown.base_m[0] - r);
  args->bounds_o->lower_y = static_cast<float>(crown.base_m[1] - r);
  args->bounds_o->lower_z = static_cast<float>(crown.base_m[2]);
  args->bounds_o->upper_x = static_cast<float>(crown.base_m[0] + r);
  args->bounds_o->upper_y = static_cast<float>(crown.base_m[1] + r);
  args->bounds_o->upper_z = static_cast<float>(crown.base_m[2] + 2.0 * crown.half_height_m);
}

void crown_intersect(const RTCIntersectFunctionNArguments* args) {
  auto* collector = reinterpret_cast<SpanCollector*>(args->context);
  const Crown& crown = (*collector->crowns)[args->primID];
  const auto* ray = reinterpret_cast<const RTCRay*>(args->rayhit);
  const auto interval =
      (*collector->crossings)[args->primID].interval(collector->origin, collector->direction);
  if (!interval) return;
  const double t0 = std::max(interval->first, static_cast<double>(ray->tnear));
  const double t1 = std::min(interval->second, collector->max_distance_m);
  if (!(t0 < t1)) return;
  collector->spans->push_back(
      {t0, t1, crown.area_density_m2_m3, crown.material, static_cast<int>(args->primID)});
  if (!collector->extinction_per_density) return;
  // Where this crown's foliage alone reaches the free path's depth, the free path has ended:
  // crowns wholly beyond need not be visited. Embree culls by tfar in float: a little beyond.
  const double extinction =
      crown.area_density_m2_m3 * (*collector->extinction_per_density)[crown.material];
  if (!(extinction > 0.0)) return;
  const double end_m = t0 + collector->depth / extinction;
  if (end_m > t1) return;
  float& tfar = reinterpret_cast<RTCRayHit*>(args->rayhit)->ray.tfar;
  tfar = std::min(tfar, static_cast<float>(end_m * (1.0 + 1e-5) + 1e-3));
}

// A slab between two heights above a plane: where the ray is inside it.
void layer_span(const TurbidLayer& layer, const Vec3& origin, const Vec3& direction,
                double max_distance_m, std::vector<VolumeSpan>& spans) {
  const double height =
      origin[2] - layer.ground_slope_x * origin[0] - layer.ground_slope_y * origin[1];
  const double rate =
      direction[2] - layer.ground_slope_x * direction[0] - layer.ground_slope_y * direction[1];
  double t0 = 0.0, t1 = max_distance_m;
  if (rate == 0.0) {
    if (height < layer.bottom_m || height > layer.top_m) return;
  } else {
    double a = (layer.bottom_m - height) / rate, b = (layer.top_m - height) / rate;
    if (a > b) std::swap(a, b);
    t0 = std::max(t0, a);
    t1 = std::min(t1, b);
  }
  if (t0 < t1) spans.push_back({t0, t1, layer.area_density_m2_m3, layer.material});
}

}  // namespace

RayDevice::RayDevice() : device_(rtcNewDevice(nullptr)) {
  if (!device_) throw run_error("Embree", "cannot create a ray tracing device");
}

RayDevice::~RayDevice() { rtcReleaseDevice(device_); }

Scene::Scene(const RayDevice& device, const GroundMesh& ground, const Vegetation& vegetation)
    : surfaces_(rtcNewScene(device.handle())),
      crowns_(vegetation.crowns),
      crossings_(crowns_.begin(), crowns_.end()),
      trunk_materials_(vegetation.trunk_materials),
      layer_(vegetation.layer),
      voxels_(vegetation.voxels && vegetation.voxels->nx > 0 ? vegetation.voxels : nullptr),
      facets_(vegetation.facets),
      leaf_materials_(vegetation.leaf_materials),
      top_m_(ground.max_height_m) {
  check_device(device.handle(), "creating a scene");
  if (!ground.triangles.empty()) attach_mesh(device.handle(), surfaces_, ground, ground_geometry);
  if (!ground.grids.empty()) attach_grids(device.handle(), surfaces_, ground, ground_grid_geometry);
  const GroundMesh& trunks = vegetation.trunks;
  trunk_triangles_ = trunks.triangles.size() / 3;
  if (!trunks.triangles.empty()) attach_mesh(device.handle(), surfaces_, trunks, trunk_geometry);
  if (!trunks.grids.empty()) attach_grids(device.handle(), surfaces_, trunks, trunk_grid_geometry);
  if (!trunks.triangles.empty() || !trunks.grids.empty())
    top_m_ = std::max(top_m_, trunks.max_height_m);
  for (std::size_t k = 0; k < facets_.size(); ++k) {
    const FacetInstance& tree = facets_[k];
    facet_turns_.push_back({std::cos(tree.rotation_rad), std::sin(tree.rotation_rad)});
    attach_facet(device, surfaces_, tree, facet_turns_.back(),
                 first_facet + static_cast<unsigned>(k));
    top_m_ = std::max(top_m_, tree.foot_m[2] + tree.scale * tree.model->top_m());
  }
  rtcSetSceneFlags(surfaces_, RTC_SCENE_FLAG_ROBUST);
  rtcCommitScene(surfaces_);
  check_device(device.handle(), "building the scene");

  if (!crowns_.empty()) {
    crown_scene_ = rtcNewScene(device.handle());
    RTCGeometry geometry = rtcNewGeometry(device.handle(), RTC_GEOMETRY_TYPE_USER);
    rtcSetGeometryUserPrimitiveCount(geometry, crowns_.size());
    rtcSetGeometryUserData(geometry, &crowns_);
    rtcSetGeometryBoundsFunction(geometry, crown_bounds, nullptr);
    rtcSetGeometryIntersectFunction(geometry, crown_intersect);
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(crown_scene_, geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(crown_scene_);
    check_device(device.handle(), "building the crowns");
    for (const Crown& crown : crowns_)
      top_m_ = std::max(top_m_, crown.base_m[2] + 2.0 * crown.half_height_m);
  }
  if (layer_) {
    // The layer's top plane at the far corners of the ground patch.
    double reach_m = 0.0;
    for (std::size_t i = 0; i + 2 < ground.vertices_m.size(); i += 3)
      reach_m = std::max({reach_m, std::abs(double{ground.vertices_m[i]}),
                          std::abs(double{ground.vertices_m[i + 1]})});
    top_m_ = std::max(top_m_, layer_->top_m + reach_m * (std::abs(layer_->ground_slope_x) +
                                                         std::abs(layer_->ground_slope_y)));
  }
  if (voxels_) top_m_ = std::max(top_m_, voxels_->top_m());
}

Scene::~Scene() {
  if (crown_scene_) rtcReleaseScene(crown_scene_);
  rtcReleaseScene(surfaces_);
}

namespace {

RTCRay make_ray(const Vec3& origin, const Vec3& direction, double min_distance_m,
                double max_distance_m, unsigned mask = std::numeric_limits<unsigned>::max()) {
  RTCRay ray{};
  ray.org_x = static_cast<float>(origin[0]);
  ray.org_y = static_cast<float>(origin[1]);
  ray.org_z = static_cast<float>(origin[2]);
  ray.dir_x = static_cast<float>(direction[0]);
  ray.dir_y = static_cast<float>(direction[1]);
  ray.dir_z = static_cast<float>(direction[2]);
  ray.tnear = static_cast<float>(min_distance_m);
  ray.tfar = static_cast<float>(max_distance_m);
  ray.mask = mask;
  return ray;
}

}  // namespace

SurfaceHit Scene::intersect(const Vec3& origin, const Vec3& direction, double max_distance_m,
                            double min_distance_m) const {
  return nearest(origin, direction, max_distance_m, min_distance_m,
                 std::numeric_limits<unsigned>::max());
}

SurfaceHit Scene::ground_hit(const Vec3& origin, const Vec3& direction,
                             double max_distance_m) const {
  return nearest(origin, direction, max_distance_m, 0.0, ground_mask);
}

SurfaceHit Scene::nearest(const Vec3& origin, const Vec3& direction, double max_distance_m,
                          double min_distance_m, unsigned mask) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRayHit query{};
  query.ray = make_ray(origin, direction, min_distance_m, max_distance_m, mask);
  query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(surfaces_, &context, &query);

  SurfaceHit hit;
  if (query.hit.geomID == RTC_INVALID_GEOMETRY_ID) return hit;
  Vec3 normal{query.hit.Ng_x, query.hit.Ng_y, query.hit.Ng_z};
  if (query.hit.instID[0] != RTC_INVALID_GEOMETRY_ID) {
    // A facet: its material's kind, and its normal turned from the model's frame (Embree gives
    // it there) into the scene's; a uniform scale leaves its direction.
    const std::size_t tree = query.hit.instID[0] - first_facet;
    hit.material = facets_[tree].model->material(query.hit.primID);
    hit.kind = leaf_materials_[hit.material] ? SurfaceKind::leaf : SurfaceKind::trunk;
    const auto& [c, s] = facet_turns_[tree];
    normal = {c * normal[0] + s * normal[1], -s * normal[0] + c * normal[1], normal[2]};
  } else {
    hit.kind = query.hit.geomID == ground_geometry || query.hit.geomID == ground_grid_geometry
                   ? SurfaceKind::ground
                   : SurfaceKind::trunk;
    if (hit.kind == SurfaceKind::trunk) {
      const std::size_t trunk = query.hit.geomID == trunk_grid_geometry
                                    ? trunk_triangles_ + query.hit.primID
                                    : query.hit.primID;
      if (trunk < trunk_materials_.size()) hit.material = trunk_materials_[trunk];
    }
  }
  hit.distance_m = query.ray.tfar;
  normal = normalized(normal);
  if (dot(normal, direction) > 0.0) normal = -1.0 * normal;
  hit.normal = normal;
  return hit;
}

bool Scene::occluded(const Vec3& origin, const Vec3& direction, double max_distance_m,
                     double min_distance_m) const {
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  RTCRay ray = make_ray(origin, direction, min_distance_m, max_distance_m);
  rtcOccluded1(surfaces_, &context, &ray);
  return ray.tfar < 0.0f;  // Embree marks an occluded ray with tfar = -inf
}

void Scene::volume_spans(const Vec3& origin, const Vec3& direction, double max_distance_m,
                         std::vector<VolumeSpan>& spans) const {
  collect_spans(origin, direction, max_distance_m, spans, 0.0, nullptr);
}

void Scene::volume_spans(const Vec3& origin, const Vec3& direction, double max_distance_m,
                         std::vector<VolumeSpan>& spans, double depth,
                         const std::vector<double>& extinction_per_density) const {
  collect_spans(origin, direction, max_distance_m, spans, depth, &extinction_per_density);
}

void Scene::collect_spans(const Vec3& origin, const Vec3& direction, double max_distance_m,
                          std::vector<VolumeSpan>& spans, double depth,
                          const std::vector<double>* extinction_per_density) const {
  spans.clear();
  if (crown_scene_) {
    SpanCollector collector{};
    rtcInitIntersectContext(&collector.context);
    collector.crowns = &crowns_;
    collector.crossings = &crossings_;
    collector.spans = &spans;
    collector.origin = origin;
    collector.direction = direction;
    collector.max_distance_m = static_cast<float>(max_distance_m);  // as Embree's tfar holds it
    collector.depth = depth;
    collector.extinction_per_density = extinction_per_density;
    RTCRayHit query{};
    query.ray = make_ray(origin, direction, 0.0, max_distance_m);
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    query.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(crown_scene_, &collector.context, &query);
  }
  if (layer_) layer_span(*layer_, origin, direction, max_distance_m, spans);
  if (voxels_)
    voxel_spans(*voxels_, origin, direction, max_distance_m, spans, depth, extinction_per_density);
}

}  // namespace glaswave
