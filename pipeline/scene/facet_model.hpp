// One facet tree model, shared by every tree that stands as it (Embree instancing): its
// triangles in the model's frame, or its leaves as oriented discs (Embree's oriented disc
// points), each element's material number, and its Embree scene, built once per ray device on
// first use and instanced by every shot's scene, so that a plot of many trees of one model holds
// the model's elements and their BVH once. A hit's primitive is a triangle or a disc by number.
#pragma once

#include <algorithm>
#include <iterator>
#include <map>
#include <mutex>
#include <unordered_map>
#include <vector>

#include "canopy/facet_trees.hpp"
#include "core/vec3.hpp"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace glaswave {

class RayDevice;

class FacetModel {
 public:
  // `triangle_materials`: the vegetation's material number of each of the mesh's triangles.
  FacetModel(FacetMesh mesh, std::vector<int> triangle_materials);
  // Leaves as discs, all of the vegetation's material number `material`.
  FacetModel(DiscLeaves discs, int material);
  ~FacetModel();
  FacetModel(const FacetModel&) = delete;
  FacetModel& operator=(const FacetModel&) = delete;

  // The model's Embree scene on `device`: built on the first call for that device (any thread),
  // the same scene after.
  RTCSceneTy* scene_on(const RayDevice& device) const;

  std::size_t triangles() const { return triangles_.size() / 3; }
  std::size_t discs() const { return discs_m_.size() / 4; }
  // A mesh's triangles come grouped by material (a mesh of the file each): the runs are few and
  // in cache, where a table of 10^5 materials missed it on nearly every hit.
  int material(unsigned triangle) const {
    const auto run =
        std::upper_bound(material_runs_.begin(), material_runs_.end(), triangle,
                         [](unsigned t, const MaterialRun& r) { return t < r.first_triangle; });
    return std::prev(run)->material;
  }
  double reach_m() const { return reach_m_; }  // farthest vertex from the vertical axis
  double top_m() const { return top_m_; }
  double bottom_m() const { return bottom_m_; }

  // The one-sided area of the model's triangles gathered on a horizontal grid of cells (0.25 m,
  // or 1/512 of the model's width when larger) by their centroids, a triangle wider than a cell
  // cut into smaller ones: the truth's plant area under a beam without a look at every triangle.
  // A cell is its column and row of the grid, whose cell (0, 0) has its centre at
  // (first_centre_m, first_centre_m), so that a weight separable in x and y costs one value a
  // column and a row.
  struct AreaCell {
    std::uint16_t column, row;
    float area_m2;
  };
  struct AreaGrid {
    double cell_m = min_area_cell_m;
    double first_centre_m[2] = {0.0, 0.0};
    int columns = 0, rows = 0;
    std::vector<AreaCell> cells;
  };
  static constexpr double min_area_cell_m = 0.25;
  const AreaGrid& area_grid() const { return area_grid_; }
  double area_m2() const { return area_m2_; }

  // Bytes the model holds (its mesh or discs, and an estimate of one BVH).
  double bytes() const;

 private:
  std::vector<float> vertices_m_;  // Embree reads them in place: one float of padding at the end
  std::vector<std::uint32_t> triangles_;
  std::vector<float> discs_m_;  // x, y, z, radius per disc (Embree's RTC_FORMAT_FLOAT4 points)
  std::vector<float> normals_;  // nx, ny, nz per disc, one float of padding at the end
  struct MaterialRun {
    unsigned first_triangle;
    int material;
  };
  std::vector<MaterialRun> material_runs_;  // by first triangle; the first run starts at 0
  AreaGrid area_grid_;
  double area_m2_ = 0.0;
  double reach_m_ = 0.0, top_m_ = 0.0, bottom_m_ = 0.0;

  // The area grid's cells for a model spanning low..high (x, y), and a piece of area at a point.
  void start_area_grid(const double low[2], const double high[2]);
  void add_area(const Vec3& point, double area_m2);
  std::int64_t first_cell_[2] = {0, 0};
  std::unordered_map<std::int64_t, std::size_t> cell_numbers_;  // emptied once the grid is made
  mutable std::mutex mutex_;
  mutable std::map<RTCDeviceTy*, RTCSceneTy*> scenes_;  // each device retained while held
};

}  // namespace glaswave
