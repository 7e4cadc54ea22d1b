// The footprint's truth, measured along vertical lines through the scene.
#include "pipeline/scene/vegetation.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>

namespace glaswave {

namespace {

constexpr int half_nodes = 20;  // a footprint's grid: 41 x 41 lines out to 3 sigma

// One vertical line down through the scene from above everything at (x_m, y_m).
struct VerticalLine {
  bool ground = false;      // it met the ground (else it is left out)
  double plant_area = 0.0;  // m^2 m^-2 crossed
  double gap = 1.0;         // exp(-G toward the zenith times the plant area, summed over foliage)
  bool covered = false;     // it crossed foliage
  double canopy_m = 0.0;    // its first foliage above the ground
};

VerticalLine measure_line(const Scene& scene, const std::vector<double>& nadir_projection,
                          double x_m, double y_m, std::vector<VolumeSpan>& spans) {
  VerticalLine line;
  const Vec3 origin{x_m, y_m, scene.top_m() + 1.0};
  const Vec3 down{0.0, 0.0, -1.0};
  const SurfaceHit ground = scene.intersect(origin, down, 1.0e5);
  if (ground.kind == SurfaceKind::none) return line;
  line.ground = true;
  scene.volume_spans(origin, down, ground.distance_m, spans);
  double first_m = ground.distance_m, optical_depth = 0.0;
  for (const VolumeSpan& span : spans) {
    const double area = span.area_density_m2_m3 * (span.end_m - span.start_m);
    line.plant_area += area;
    optical_depth += nadir_projection.at(static_cast<std::size_t>(span.material)) * area;
    first_m = std::min(first_m, span.start_m);
  }
  // Once a line: TruthGrid's lines serve every footprint that weighs them.
  if (!spans.empty()) line.gap = std::exp(-optical_depth);
  line.covered = !spans.empty();
  line.canopy_m = ground.distance_m - first_m;
  return line;
}

// The beam-weighted sums of the lines a footprint weighs, `r_sq` from its centre.
struct TruthSums {
  VegetationTruth truth{.gap_probability = 0.0};
  double weights = 0.0;

  void add(const VerticalLine& line, double r_sq, double sigma_m) {
    if (line.ground) add(line, std::exp(-r_sq / (2.0 * sigma_m * sigma_m)), r_sq, sigma_m);
  }
  // With the line's weight given.
  void add(const VerticalLine& line, double weight, double r_sq, double sigma_m) {
    if (!line.ground) return;
    weights += weight;
    truth.pai += weight * line.plant_area;
    truth.cover += line.covered ? weight : 0.0;
    truth.gap_probability += weight * line.gap;
    if (r_sq <= 4.0 * sigma_m * sigma_m)
      truth.canopy_height_m = std::max(truth.canopy_height_m, line.canopy_m);
  }
  VegetationTruth mean() const {
    VegetationTruth mean = truth;
    if (weights > 0.0) {
      mean.pai /= weights;
      mean.cover /= weights;
      mean.gap_probability /= weights;
    } else {
      mean.gap_probability = 1.0;  // no line met the ground: nothing measured, as cover 0 says
    }
    return mean;
  }
};

}  // namespace

VegetationTruth measure_vegetation(const Scene& scene, const BeamSpot& spot,
                                   const std::vector<double>& nadir_projection) {
  if (!scene.has_volumes()) return {};
  const double step_m = 3.0 * spot.sigma_m / half_nodes;
  std::vector<VolumeSpan> spans;
  TruthSums sums;
  for (int j = -half_nodes; j <= half_nodes; ++j) {
    for (int i = -half_nodes; i <= half_nodes; ++i) {
      const double x = i * step_m, y = j * step_m;
      sums.add(measure_line(scene, nadir_projection, spot.x_m + x, spot.y_m + y, spans),
               x * x + y * y, spot.sigma_m);
    }
  }
  return sums.mean();
}

// The lines of a tile of kTile x kTile nodes, measured by the first footprint that weighs one.
struct TruthGrid::Tile {
  static constexpr int kTile = 4;
  // Measured once, by the first footprint that weighs it (a flag and a lock rather than
  // std::call_once, whose every first call ends in a futex wake: a system call a tile).
  std::atomic<bool> measured{false};
  std::mutex measuring;
  std::array<VerticalLine, kTile * kTile> lines;
};

TruthGrid::TruthGrid(const Scene& scene, double step_m, std::vector<double> nadir_projection)
    : scene_(scene), step_m_(step_m), nadir_projection_(std::move(nadir_projection)) {}

TruthGrid::~TruthGrid() = default;

void TruthGrid::tiles(std::int64_t ti0, std::int64_t ti1, std::int64_t tj0, std::int64_t tj1,
                      std::vector<Tile*>& found) const {
  found.clear();
  {
    const std::lock_guard lock(mutex_);  // one lock a footprint, not a tile
    for (std::int64_t tj = tj0; tj <= tj1; ++tj)
      for (std::int64_t ti = ti0; ti <= ti1; ++ti) {
        std::unique_ptr<Tile>& held = tiles_[{ti, tj}];
        if (!held) held = std::make_unique<Tile>();
        found.push_back(held.get());
      }
  }
  std::size_t k = 0;
  for (std::int64_t tj = tj0; tj <= tj1; ++tj)
    for (std::int64_t ti = ti0; ti <= ti1; ++ti) {
      Tile* tile = found[k++];
      if (tile->measured.load(std::memory_order_acquire)) continue;
      const std::lock_guard measuring(tile->measuring);
      if (tile->measured.load(std::memory_order_relaxed)) continue;
      std::vector<VolumeSpan> spans;
      for (int b = 0; b < Tile::kTile; ++b)
        for (int a = 0; a < Tile::kTile; ++a)
          tile->lines[b * Tile::kTile + a] = measure_line(
              scene_, nadir_projection_, static_cast<double>(ti * Tile::kTile + a) * step_m_,
              static_cast<double>(tj * Tile::kTile + b) * step_m_, spans);
      tile->measured.store(true, std::memory_order_release);
    }
}

VegetationTruth TruthGrid::measure(const BeamSpot& spot) const {
  if (!scene_.has_volumes()) return {};
  const double reach_m = 3.0 * spot.sigma_m;
  const auto first = [&](double centre_m) {
    return static_cast<std::int64_t>(std::ceil((centre_m - reach_m) / step_m_));
  };
  const auto last = [&](double centre_m) {
    return static_cast<std::int64_t>(std::floor((centre_m + reach_m) / step_m_));
  };
  const auto tile_of = [](std::int64_t node) {
    return node >= 0 ? node / Tile::kTile : -((-node - 1) / Tile::kTile) - 1;
  };
  const std::int64_t i0 = first(spot.x_m), i1 = last(spot.x_m);
  const std::int64_t j0 = first(spot.y_m), j1 = last(spot.y_m);
  if (i1 < i0 || j1 < j0) return TruthSums{}.mean();
  const std::int64_t ti0 = tile_of(i0), tj0 = tile_of(j0);
  const std::int64_t tiles_across = tile_of(i1) - ti0 + 1;
  std::vector<Tile*> held;
  tiles(ti0, tile_of(i1), tj0, tile_of(j1), held);
  // The beam's weight is separable, exp(-x^2 / 2 sigma^2) exp(-y^2 / 2 sigma^2): one
  // exponential a column and a row, not one a line.
  const double two_sigma_sq = 2.0 * spot.sigma_m * spot.sigma_m;
  std::vector<double> column_weight;
  for (std::int64_t i = i0; i <= i1; ++i) {
    const double x = static_cast<double>(i) * step_m_ - spot.x_m;
    column_weight.push_back(std::exp(-x * x / two_sigma_sq));
  }
  TruthSums sums;
  for (std::int64_t j = j0; j <= j1; ++j) {
    const double y = static_cast<double>(j) * step_m_ - spot.y_m;
    const double row_weight = std::exp(-y * y / two_sigma_sq);
    const std::int64_t tj = tile_of(j);
    for (std::int64_t i = i0; i <= i1; ++i) {
      const std::int64_t ti = tile_of(i);
      const Tile& tile = *held[static_cast<std::size_t>((tj - tj0) * tiles_across + (ti - ti0))];
      const VerticalLine& line =
          tile.lines[(j - tj * Tile::kTile) * Tile::kTile + (i - ti * Tile::kTile)];
      const double x = static_cast<double>(i) * step_m_ - spot.x_m;
      sums.add(line, row_weight * column_weight[static_cast<std::size_t>(i - i0)], x * x + y * y,
               spot.sigma_m);
    }
  }
  return sums.mean();
}

VegetationTruth measure_facets(const Scene& scene, const BeamSpot& spot) {
  const double sigma_m = spot.sigma_m;
  VegetationTruth truth;
  if (scene.facets().empty()) return truth;
  const double two_sigma_sq = 2.0 * sigma_m * sigma_m;
  // The beam's weight at a cell is a Gaussian of the cell's distance from the spot, which a
  // rotation leaves: taken in the model's frame, about the spot turned into it, it is separable
  // along the model's grid, one exponential a column and a row where it was one a cell.
  std::vector<double> column_weight, row_weight;
  for (const FacetInstance& tree : scene.facets()) {
    const double c = std::cos(tree.rotation_rad), s = std::sin(tree.rotation_rad);
    const double scale_sq = tree.scale * tree.scale;
    // The model places its point q at foot + scale (c qx + s qy, -s qx + c qy).
    const double dx = spot.x_m - tree.foot_m[0], dy = spot.y_m - tree.foot_m[1];
    const double spot_model[2] = {(c * dx - s * dy) / tree.scale, (s * dx + c * dy) / tree.scale};
    const FacetModel::AreaGrid& grid = tree.model->area_grid();
    const auto weights = [&](int axis, int count, std::vector<double>& weight) {
      weight.resize(static_cast<std::size_t>(count));
      for (int k = 0; k < count; ++k) {
        const double u = grid.first_centre_m[axis] + k * grid.cell_m - spot_model[axis];
        weight[static_cast<std::size_t>(k)] = std::exp(-scale_sq * u * u / two_sigma_sq);
      }
    };
    weights(0, grid.columns, column_weight);
    weights(1, grid.rows, row_weight);
    double area_m2 = 0.0;
    for (const FacetModel::AreaCell& cell : grid.cells)
      area_m2 += cell.area_m2 * column_weight[cell.column] * row_weight[cell.row];
    truth.pai += scale_sq * area_m2;
  }
  truth.pai /= std::numbers::pi * two_sigma_sq;
  const double step_m = 3.0 * sigma_m / half_nodes;
  const double start_m = scene.top_m() + 1.0;
  const Vec3 down{0.0, 0.0, -1.0};
  double weights = 0.0;
  for (int j = -half_nodes; j <= half_nodes; ++j) {
    for (int i = -half_nodes; i <= half_nodes; ++i) {
      const double x = i * step_m, y = j * step_m, r_sq = x * x + y * y;
      const Vec3 origin{spot.x_m + x, spot.y_m + y, start_m};
      const SurfaceHit first = scene.intersect(origin, down, 1.0e5);
      if (first.kind == SurfaceKind::none) continue;
      const double weight = std::exp(-r_sq / (2.0 * sigma_m * sigma_m));
      weights += weight;
      if (first.kind == SurfaceKind::ground) continue;
      truth.cover += weight;
      if (r_sq > 4.0 * sigma_m * sigma_m) continue;
      // The ground under the first facet, for the facet's height above it.
      const SurfaceHit below = scene.ground_hit(origin, down, 1.0e5);
      if (below.kind == SurfaceKind::ground)
        truth.canopy_height_m =
            std::max(truth.canopy_height_m, below.distance_m - first.distance_m);
    }
  }
  if (weights > 0.0) truth.cover /= weights;
  truth.gap_probability = 1.0 - truth.cover;
  return truth;
}

}  // namespace glaswave
