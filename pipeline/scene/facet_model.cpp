// A facet model's triangles, area cells and Embree scenes.
#include "pipeline/scene/facet_model.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <unordered_map>

#include "core/error.hpp"
#include "pipeline/scene/scene.hpp"

namespace glaswave {

FacetModel::FacetModel(FacetMesh mesh, std::vector<int> triangle_materials)
    : vertices_m_(std::move(mesh.vertices_m)), triangles_(std::move(mesh.triangles)) {
  if (triangle_materials.size() != triangles())
    throw run_error("facet model", "a material for each of its " + std::to_string(triangles()) +
                                       " triangles is needed, " +
                                       std::to_string(triangle_materials.size()) + " were given");
  for (std::size_t t = 0; t < triangle_materials.size(); ++t)
    if (material_runs_.empty() || material_runs_.back().material != triangle_materials[t])
      material_runs_.push_back({static_cast<unsigned>(t), triangle_materials[t]});
  top_m_ = -std::numeric_limits<double>::infinity();
  bottom_m_ = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 2 < vertices_m_.size(); i += 3) {
    reach_m_ = std::max(reach_m_, std::hypot(double{vertices_m_[i]}, double{vertices_m_[i + 1]}));
    bottom_m_ = std::min(bottom_m_, double{vertices_m_[i + 2]});
    top_m_ = std::max(top_m_, double{vertices_m_[i + 2]});
  }
  // Cells no smaller than 1/512 of the model's width, so that a large model keeps few.
  double low[2] = {std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity()};
  double high[2] = {-low[0], -low[1]};
  for (std::size_t i = 0; i + 2 < vertices_m_.size(); i += 3)
    for (int axis = 0; axis < 2; ++axis) {
      low[axis] = std::min(low[axis], double{vertices_m_[i + axis]});
      high[axis] = std::max(high[axis], double{vertices_m_[i + axis]});
    }
  AreaGrid& grid = area_grid_;
  grid.cell_m = std::max({min_area_cell_m, (high[0] - low[0]) / 512.0, (high[1] - low[1]) / 512.0});
  std::int64_t first[2] = {0, 0};
  for (int axis = 0; axis < 2 && !triangles_.empty(); ++axis) {
    first[axis] = static_cast<std::int64_t>(std::floor(low[axis] / grid.cell_m));
    grid.first_centre_m[axis] = (static_cast<double>(first[axis]) + 0.5) * grid.cell_m;
  }
  // Cells keyed by their indices, in the order first met: the same cells for the same mesh.
  // Every centroid lies within the vertices' bounds, so that at most 514 columns and rows hold
  // them; the clamp only guards a rounding at the last one.
  std::unordered_map<std::int64_t, std::size_t> cells;
  auto add = [&](const Vec3& point, double area) {
    std::int64_t index[2];
    for (int axis = 0; axis < 2; ++axis)
      index[axis] = std::clamp<std::int64_t>(
          static_cast<std::int64_t>(std::floor(point[axis] / grid.cell_m)) - first[axis], 0, 513);
    const auto [entry, added] = cells.emplace(index[0] * 1024 + index[1], grid.cells.size());
    if (added) {
      grid.cells.push_back(
          {static_cast<std::uint16_t>(index[0]), static_cast<std::uint16_t>(index[1]), 0.0f});
      grid.columns = std::max(grid.columns, static_cast<int>(index[0]) + 1);
      grid.rows = std::max(grid.rows, static_cast<int>(index[1]) + 1);
    }
    grid.cells[entry->second].area_m2 += static_cast<float>(area);
  };
  for (std::size_t t = 0; t + 2 < triangles_.size(); t += 3) {
    Vec3 p[3];
    for (int k = 0; k < 3; ++k) {
      const std::size_t v = 3 * std::size_t{triangles_[t + k]};
      p[k] = {vertices_m_[v], vertices_m_[v + 1], vertices_m_[v + 2]};
    }
    const Vec3 e1 = p[1] - p[0], e2 = p[2] - p[0];
    const double area = 0.5 * norm(cross(e1, e2));
    area_m2_ += area;
    // A triangle wider than a cell is cut into n^2 equal ones (n along each edge), each
    // gathered at its centroid.
    const double longest = std::max({norm(e1), norm(e2), norm(p[2] - p[1])});
    const int n = std::max(1, static_cast<int>(std::ceil(longest / grid.cell_m)));
    const double part = area / (double(n) * n);
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        add(p[0] + ((i + 1.0 / 3.0) / n) * e1 + ((j + 1.0 / 3.0) / n) * e2, part);
        if (i + j + 1 < n)
          add(p[0] + ((i + 2.0 / 3.0) / n) * e1 + ((j + 2.0 / 3.0) / n) * e2, part);
      }
  }
  vertices_m_.push_back(0.0f);  // Embree reads a vertex's three floats with one 16-byte load
}

FacetModel::~FacetModel() {
  for (const auto& [device, scene] : scenes_) {
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
  }
}

RTCSceneTy* FacetModel::scene_on(const RayDevice& device) const {
  const std::lock_guard lock(mutex_);
  RTCDevice handle = device.handle();
  if (const auto found = scenes_.find(handle); found != scenes_.end()) return found->second;
  RTCScene scene = rtcNewScene(handle);
  RTCGeometry geometry = rtcNewGeometry(handle, RTC_GEOMETRY_TYPE_TRIANGLE);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                             vertices_m_.data(), 0, 3 * sizeof(float), vertices_m_.size() / 3);
  rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                             triangles_.data(), 0, 3 * sizeof(std::uint32_t),
                             triangles_.size() / 3);
  rtcCommitGeometry(geometry);
  rtcAttachGeometryByID(scene, geometry, 0);
  rtcReleaseGeometry(geometry);
  // Built once and traced by every shot: the slower build of the better tree pays.
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  rtcCommitScene(scene);
  if (const RTCError code = rtcGetDeviceError(handle); code != RTC_ERROR_NONE) {
    rtcReleaseScene(scene);
    throw run_error("Embree", "building a facet model failed (error " + std::to_string(code) + ")");
  }
  rtcRetainDevice(handle);  // the key stays this device while the scene lives
  scenes_.emplace(handle, scene);
  return scene;
}

double FacetModel::bytes() const {
  // Embree's BVH of triangles takes about 100 bytes a triangle at medium quality.
  return vertices_m_.size() * sizeof(float) + triangles_.size() * sizeof(std::uint32_t) +
         material_runs_.size() * sizeof(MaterialRun) + triangles() * 100.0 +
         area_grid_.cells.size() * sizeof(AreaCell);
}

}  // namespace glaswave
