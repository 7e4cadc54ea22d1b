// A facet model's triangles, area cells and Embree scenes.
#include "pipeline/scene/facet_model.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
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
  double low[2] = {std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity()};
  double high[2] = {-low[0], -low[1]};
  for (std::size_t i = 0; i + 2 < vertices_m_.size(); i += 3)
    for (int axis = 0; axis < 2; ++axis) {
      low[axis] = std::min(low[axis], double{vertices_m_[i + axis]});
      high[axis] = std::max(high[axis], double{vertices_m_[i + axis]});
    }
  if (!triangles_.empty()) start_area_grid(low, high);
  const AreaGrid& grid = area_grid_;
  auto add = [this](const Vec3& point, double area) { add_area(point, area); };
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
  cell_numbers_ = {};           // only needed while the grid is made
  vertices_m_.push_back(0.0f);  // Embree reads a vertex's three floats with one 16-byte load
}

FacetModel::FacetModel(DiscLeaves discs, int material)
    : discs_m_(std::move(discs.discs_m)), normals_(std::move(discs.normals)) {
  if (discs_m_.empty() || normals_.size() != 3 * this->discs())
    throw run_error("facet model", "discs need a centre, radius and normal each");
  material_runs_.push_back({0, material});
  top_m_ = -std::numeric_limits<double>::infinity();
  bottom_m_ = std::numeric_limits<double>::infinity();
  double low[2] = {std::numeric_limits<double>::infinity(),
                   std::numeric_limits<double>::infinity()};
  double high[2] = {-low[0], -low[1]};
  for (std::size_t d = 0; d < this->discs(); ++d) {
    const float* c = &discs_m_[4 * d];
    const double r = c[3];
    const Vec3 n{normals_[3 * d], normals_[3 * d + 1], normals_[3 * d + 2]};
    // A disc reaches r sin(its tilt) up and down, r sqrt(1 - n_axis^2) along a horizontal axis.
    const double vertical = r * std::sqrt(std::max(0.0, 1.0 - n[2] * n[2]));
    reach_m_ = std::max(reach_m_, std::hypot(double{c[0]}, double{c[1]}) + r);
    bottom_m_ = std::min(bottom_m_, c[2] - vertical);
    top_m_ = std::max(top_m_, c[2] + vertical);
    for (int axis = 0; axis < 2; ++axis) {
      const double half = r * std::sqrt(std::max(0.0, 1.0 - n[axis] * n[axis]));
      low[axis] = std::min(low[axis], c[axis] - half);
      high[axis] = std::max(high[axis], c[axis] + half);
    }
  }
  start_area_grid(low, high);
  for (std::size_t d = 0; d < this->discs(); ++d) {
    const float* c = &discs_m_[4 * d];
    const double r = c[3];
    const Vec3 centre{c[0], c[1], c[2]};
    const double area = std::numbers::pi * r * r;
    area_m2_ += area;
    // A disc wider than a cell is cut into n^2 pieces of equal area (n rings of n sectors), each
    // gathered at its middle.
    const int n = std::max(1, static_cast<int>(std::ceil(2.0 * r / area_grid_.cell_m)));
    if (n == 1) {
      add_area(centre, area);
      continue;
    }
    const Vec3 normal{normals_[3 * d], normals_[3 * d + 1], normals_[3 * d + 2]};
    const Vec3 helper = std::abs(normal[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{1.0, 0.0, 0.0};
    const Vec3 u = normalized(cross(normal, helper)), v = cross(normal, u);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double rho = r * std::sqrt((i + 0.5) / n);
        const double phi = 2.0 * std::numbers::pi * (j + 0.5) / n;
        add_area(centre + rho * std::cos(phi) * u + rho * std::sin(phi) * v,
                 area / (double(n) * n));
      }
  }
  cell_numbers_ = {};        // only needed while the grid is made
  normals_.push_back(0.0f);  // Embree may read a normal's three floats with one 16-byte load
}

void FacetModel::start_area_grid(const double low[2], const double high[2]) {
  // Cells no smaller than 1/512 of the model's width, so that a large model keeps few.
  AreaGrid& grid = area_grid_;
  grid.cell_m = std::max({min_area_cell_m, (high[0] - low[0]) / 512.0, (high[1] - low[1]) / 512.0});
  for (int axis = 0; axis < 2; ++axis) {
    first_cell_[axis] = static_cast<std::int64_t>(std::floor(low[axis] / grid.cell_m));
    grid.first_centre_m[axis] = (static_cast<double>(first_cell_[axis]) + 0.5) * grid.cell_m;
  }
}

// Cells keyed by their indices, in the order first met: the same cells for the same model.
// Every point lies within the model's bounds, so that at most 514 columns and rows hold them; the
// clamp only guards a rounding at the last one.
void FacetModel::add_area(const Vec3& point, double area) {
  AreaGrid& grid = area_grid_;
  std::int64_t index[2];
  for (int axis = 0; axis < 2; ++axis)
    index[axis] = std::clamp<std::int64_t>(
        static_cast<std::int64_t>(std::floor(point[axis] / grid.cell_m)) - first_cell_[axis], 0,
        513);
  const auto [entry, added] = cell_numbers_.emplace(index[0] * 1024 + index[1], grid.cells.size());
  if (added) {
    grid.cells.push_back(
        {static_cast<std::uint16_t>(index[0]), static_cast<std::uint16_t>(index[1]), 0.0f});
    grid.columns = std::max(grid.columns, static_cast<int>(index[0]) + 1);
    grid.rows = std::max(grid.rows, static_cast<int>(index[1]) + 1);
  }
  grid.cells[entry->second].area_m2 += static_cast<float>(area);
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
  RTCGeometry geometry = nullptr;
  if (!discs_m_.empty()) {
    // Oriented discs: a centre and radius, and a normal; Embree hits either side and gives the
    // normal as the hit's geometric normal, in the model's frame.
    geometry = rtcNewGeometry(handle, RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                               discs_m_.data(), 0, 4 * sizeof(float), discs());
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3,
                               normals_.data(), 0, 3 * sizeof(float), discs());
  } else {
    geometry = rtcNewGeometry(handle, RTC_GEOMETRY_TYPE_TRIANGLE);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                               vertices_m_.data(), 0, 3 * sizeof(float), vertices_m_.size() / 3);
    rtcSetSharedGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                               triangles_.data(), 0, 3 * sizeof(std::uint32_t),
                               triangles_.size() / 3);
  }
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
  // Embree's BVH of triangles takes about 100 bytes a triangle at medium quality; of discs, as
  // many (a bound for them as for a triangle).
  return vertices_m_.size() * sizeof(float) + triangles_.size() * sizeof(std::uint32_t) +
         (discs_m_.size() + normals_.size()) * sizeof(float) +
         material_runs_.size() * sizeof(MaterialRun) + (triangles() + discs()) * 100.0 +
         area_grid_.cells.size() * sizeof(AreaCell);
}

}  // namespace glaswave
