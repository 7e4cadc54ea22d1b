// One facet tree model, shared by every tree that stands as it (Embree instancing): its
// triangles in the model's frame, each triangle's material number, and its Embree scene, built
// once per ray device on first use and instanced by every shot's scene, so that a plot of many
// trees of one model holds the model's triangles and their BVH once.
#pragma once

#include <map>
#include <mutex>
#include <vector>

#include "canopy/facet_trees.hpp"

struct RTCDeviceTy;
struct RTCSceneTy;

namespace glaswave {

class RayDevice;

class FacetModel {
 public:
  // `triangle_materials`: the vegetation's material number of each of the mesh's triangles.
  FacetModel(FacetMesh mesh, std::vector<int> triangle_materials);
  ~FacetModel();
  FacetModel(const FacetModel&) = delete;
  FacetModel& operator=(const FacetModel&) = delete;

  // The model's Embree scene on `device`: built on the first call for that device (any thread),
  // the same scene after.
  RTCSceneTy* scene_on(const RayDevice& device) const;

  std::size_t triangles() const { return materials_.size(); }
  int material(unsigned triangle) const { return materials_[triangle]; }
  double reach_m() const { return reach_m_; }  // farthest vertex from the vertical axis
  double top_m() const { return top_m_; }
  double bottom_m() const { return bottom_m_; }

  // The one-sided area of the model's triangles gathered on a horizontal grid of cells (0.25 m,
  // or 1/512 of the model's width when larger) by their centroids, a triangle wider than a cell
  // cut into smaller ones: the truth's plant area under a beam without a look at every triangle.
  struct AreaCell {
    float x_m, y_m, area_m2;
  };
  static constexpr double min_area_cell_m = 0.25;
  const std::vector<AreaCell>& area_cells() const { return area_cells_; }
  double area_m2() const { return area_m2_; }

  // Bytes the model holds (its mesh, and an estimate of one BVH).
  double bytes() const;

 private:
  std::vector<float> vertices_m_;  // Embree reads them in place: one float of padding at the end
  std::vector<std::uint32_t> triangles_;
  std::vector<int> materials_;
  std::vector<AreaCell> area_cells_;
  double area_m2_ = 0.0;
  double cell_m_ = min_area_cell_m;
  double reach_m_ = 0.0, top_m_ = 0.0, bottom_m_ = 0.0;
  mutable std::mutex mutex_;
  mutable std::map<RTCDeviceTy*, RTCSceneTy*> scenes_;  // each device retained while held
};

}  // namespace glaswave
