// Gap-fraction inversion of airborne lidar returns, and the ground DEM through GDAL's gridding.
#include "canopy/gap_fraction.hpp"

#include <cpl_error.h>
#include <gdal_alg.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <unordered_set>
#include <vector>

#include "core/error.hpp"
#include "core/gdal_layer.hpp"

namespace glaswave {

namespace {
constexpr std::uint64_t kPointWindow = 1 << 20;  // points read at a time: memory is the grid's

// The blocks of 10 m that hold a point of the cloud, to find a patch of points far from the rest
// before the ground is gridded (and the voxels made) over the empty space between: one ground
// point 800 m from an 80 m plot made voxelize grid 800 m (45 s). Patches closer than 20 m of
// empty blocks are one (flight lines, gaps in the ground returns).
class Patches {
 public:
  static constexpr double block_m = 10.0;
  static constexpr std::size_t max_blocks = std::size_t{1} << 22;  // beyond: not looked at

  void add(double x, double y) {
    const std::int64_t bx = static_cast<std::int64_t>(std::floor(x / block_m)),
                       by = static_cast<std::int64_t>(std::floor(y / block_m));
    if (bx == last_x_ && by == last_y_) return;  // neighbouring points share their block
    last_x_ = bx;
    last_y_ = by;
    if (blocks_.size() < max_blocks) blocks_.insert(key(bx, by));
  }

  // An input error when the largest patch spans less than a quarter of the extent the grid would
  // cover (lo, hi), naming the block of points farthest from it.
  void check(const double lo[2], const double hi[2], const std::string& place) const {
    if (blocks_.empty() || blocks_.size() >= max_blocks) return;
    // The patches: blocks within 3 blocks of one another, breadth first.
    std::unordered_set<std::uint64_t> seen;
    std::vector<std::uint64_t> largest, patch;
    for (const std::uint64_t start : blocks_) {
      if (!seen.insert(start).second) continue;
      patch.assign(1, start);
      for (std::size_t n = 0; n < patch.size(); ++n) {
        const auto [bx, by] = unkey(patch[n]);
        for (std::int64_t dy = -3; dy <= 3; ++dy)
          for (std::int64_t dx = -3; dx <= 3; ++dx) {
            const std::uint64_t k = key(bx + dx, by + dy);
            if (blocks_.count(k) && seen.insert(k).second) patch.push_back(k);
          }
      }
      if (patch.size() > largest.size()) largest.swap(patch);
    }
    if (largest.size() == blocks_.size()) return;
    std::int64_t x0 = INT64_MAX, y0 = INT64_MAX, x1 = INT64_MIN, y1 = INT64_MIN;
    for (const std::uint64_t k : largest) {
      const auto [bx, by] = unkey(k);
      x0 = std::min(x0, bx), x1 = std::max(x1, bx), y0 = std::min(y0, by), y1 = std::max(y1, by);
    }
    const double patch_w = (x1 - x0 + 1) * block_m, patch_h = (y1 - y0 + 1) * block_m;
    const double all_w = std::max(block_m, hi[0] - lo[0]), all_h = std::max(block_m, hi[1] - lo[1]);
    if (patch_w * patch_h >= 0.25 * all_w * all_h) return;
    // The block farthest from the largest patch's box.
    double far = -1.0, far_x = 0.0, far_y = 0.0;
    for (const std::uint64_t k : blocks_) {
      const auto [bx, by] = unkey(k);
      const double gx = double(std::max<std::int64_t>({0, x0 - bx, bx - x1})) * block_m,
                   gy = double(std::max<std::int64_t>({0, y0 - by, by - y1})) * block_m;
      if (std::hypot(gx, gy) > far) {
        far = std::hypot(gx, gy);
        far_x = (bx + 0.5) * block_m;
        far_y = (by + 0.5) * block_m;
      }
    }
    const auto metres = [](double m) { return std::to_string(std::llround(m)); };
    throw input_error(place, "the cloud's points lie in separate patches: the largest spans " +
                                 metres(patch_w) + " x " + metres(patch_h) + " m of the " +
                                 metres(all_w) + " x " + metres(all_h) +
                                 " m the cloud spans, points near x " + metres(far_x) + ", y " +
                                 metres(far_y) + " lie " + metres(far) +
                                 " m from it, and the grid would cover the empty space between "
                                 "(crop the cloud to one patch)");
  }

 private:
  static std::uint64_t key(std::int64_t bx, std::int64_t by) {
    return (static_cast<std::uint64_t>(bx) << 32) ^ static_cast<std::uint32_t>(by);
  }
  static std::pair<std::int64_t, std::int64_t> unkey(std::uint64_t k) {
    return {static_cast<std::int32_t>(k >> 32), static_cast<std::int32_t>(k & 0xffffffffu)};
  }

  std::unordered_set<std::uint64_t> blocks_;
  std::int64_t last_x_ = INT64_MIN, last_y_ = INT64_MIN;
};

}  // namespace

double GroundGrid::height_at(double x, double y) const {
  const double u = (x - x0) / cell_m - 0.5, v = (y - y0) / cell_m - 0.5;
  if (!(u >= -0.5 && u <= nx - 0.5 && v >= -0.5 && v <= ny - 0.5))
    return std::numeric_limits<double>::quiet_NaN();
  const double uc = std::clamp(u, 0.0, nx - 1.0), vc = std::clamp(v, 0.0, ny - 1.0);
  const int i = std::min(static_cast<int>(uc), std::max(nx - 2, 0));
  const int j = std::min(static_cast<int>(vc), std::max(ny - 2, 0));
  const double fu = nx > 1 ? uc - i : 0.0, fv = ny > 1 ? vc - j : 0.0;
  const auto h = [&](int di, int dj) {
    return double{height_m[std::size_t(std::min(j + dj, ny - 1)) * nx + std::min(i + di, nx - 1)]};
  };
  return (1 - fv) * ((1 - fu) * h(0, 0) + fu * h(1, 0)) + fv * ((1 - fu) * h(0, 1) + fu * h(1, 1));
}

GroundGrid grid_ground(const std::vector<std::array<double, 3>>& points, double x0, double y0,
                       int nx, int ny, double cell_m, const std::string& place) {
  GroundGrid grid;
  grid.nx = nx;
  grid.ny = ny;
  grid.x0 = x0;
  grid.y0 = y0;
  grid.cell_m = cell_m;
  // One point a quarter cell, the mean of its ground points: the triangulation stays a few
  // times the size of the grid, however dense the cloud, and its hull still holds the centre of
  // every cell whose quarters have ground (one point a cell would leave the edge cells' centres
  // outside it, to be filled by the nearest point: 14 cm off on a 10 % slope).
  const std::size_t cells = std::size_t(nx) * ny;
  const std::size_t thin = 4 * cells;
  std::vector<double> sx(thin, 0.0), sy(thin, 0.0), sz(thin, 0.0), n(thin, 0.0);
  for (const auto& p : points) {
    const int i = static_cast<int>(std::floor(2.0 * (p[0] - x0) / cell_m));
    const int j = static_cast<int>(std::floor(2.0 * (p[1] - y0) / cell_m));
    if (i < 0 || j < 0 || i >= 2 * nx || j >= 2 * ny) continue;
    const std::size_t c = std::size_t(j) * 2 * nx + i;
    sx[c] += p[0];
    sy[c] += p[1];
    sz[c] += p[2];
    n[c] += 1.0;
  }
  std::vector<double> gx, gy, gz;
  for (std::size_t c = 0; c < thin; ++c) {
    if (n[c] == 0.0) continue;
    gx.push_back(sx[c] / n[c]);
    gy.push_back(sy[c] / n[c]);
    gz.push_back(sz[c] / n[c]);
  }
  if (gx.empty()) throw input_error(place, "no ground point (class 2): the terrain is unknown");
  grid.height_m.assign(cells, std::numeric_limits<float>::quiet_NaN());
  GDALGridLinearOptions options{};
  options.nSizeOfStructure = sizeof options;
  options.dfRadius = -1.0;  // beyond the triangulation: the nearest ground point
  options.dfNoDataValue = std::numeric_limits<double>::quiet_NaN();
  const GDALGridAlgorithm algorithm = gx.size() >= 3 ? GGA_Linear : GGA_NearestNeighbor;
  GDALGridNearestNeighborOptions nearest{};
  nearest.nSizeOfStructure = sizeof nearest;
  nearest.dfNoDataValue = std::numeric_limits<double>::quiet_NaN();
  const GdalErrorTrap trap;
  // GDALGridCreate's node (i, j) lies at (xmin + (i + 0.5) dx, ymin + (j + 0.5) dy), row 0 at
  // ymin: the grid's own layout.
  const CPLErr status = GDALGridCreate(
      algorithm, algorithm == GGA_Linear ? static_cast<const void*>(&options) : &nearest,
      static_cast<GUInt32>(gx.size()), gx.data(), gy.data(), gz.data(), x0, x0 + nx * cell_m, y0,
      y0 + ny * cell_m, nx, ny, GDT_Float32, grid.height_m.data(), nullptr, nullptr);
  if (status != CE_None)
    throw input_error(place, "gridding the ground points failed: " + trap.cause(""));
  return grid;
}

GapFractionInversion::GapFractionInversion(const VoxelBlock& shape, const GroundGrid& ground,
                                           const GapFractionSettings& settings)
    : shape_(shape), ground_(&ground), settings_(settings) {
  const std::size_t columns = std::size_t(shape.nx) * shape.ny;
  weight_.assign(columns * (shape.nz + 1), 0.0);
  cos_sum_.assign(columns, 0.0);
  column_weight_.assign(columns, 0.0);
}

void GapFractionInversion::add(const LasPoint& p, VoxelizeReport& report) {
  if (p.withheld || p.classification == 7 || p.classification == 18) {
    ++report.noise_dropped;
    return;
  }
  int i = 0, j = 0;
  if (!shape_.column_of(p.x, p.y, i, j)) return;
  const double ground = ground_->height_at(p.x, p.y);
  if (!std::isfinite(ground)) return;
  const double h = p.z - ground;
  if (h > settings_.max_height_m) {
    ++report.noise_dropped;
    return;
  }
  const double w = 1.0 / std::max<int>(1, p.number_of_returns);
  const std::size_t column = std::size_t(j) * shape_.nx + i;
  // Ground returns, and anything below the lowest layer, passed every layer.
  int slot = 0;
  if (p.classification != 2 && h >= shape_.z_edges_m[0])
    slot = 1 + std::min(shape_.nz - 1,
                        static_cast<int>((h - shape_.z_edges_m[0]) / settings_.voxel_size_m));
  weight_[column * (shape_.nz + 1) + slot] += w;
  column_weight_[column] += w;
  cos_sum_[column] += w * std::cos(p.scan_angle_deg * std::numbers::pi / 180.0);
  ++report.returns_used;
}

VoxelBlock GapFractionInversion::result(VoxelizeReport& report) const {
  VoxelBlock block = shape_;
  const int nz = shape_.nz;
  const std::size_t columns = std::size_t(shape_.nx) * shape_.ny;
  block.pad.assign(columns * nz, 0.0f);
  report.columns = columns;
  for (std::size_t c = 0; c < columns; ++c) {
    const double total = column_weight_[c];
    if (!(total > 0.0)) continue;
    ++report.columns_with_pulses;
    const double mu = cos_sum_[c] / total;  // mean cosine of the path from nadir
    const double floor = 0.5 / total;       // occlusion: half a pulse passed
    // P at each layer's bottom and top: the weight returned below it, over the total.
    const double* w = weight_.data() + c * (nz + 1);
    double below = w[0];
    for (int k = 0; k < nz; ++k) {
      const double p_bottom = below / total;
      below += w[k + 1];
      const double p_top = below / total;
      if (!(p_top > 0.0)) continue;  // nothing reached this layer: it is not seen
      double bottom = p_bottom;
      if (bottom <= 0.0) {
        ++report.occluded_layers;
        bottom = std::min(floor, p_top);
      }
      const double dz = shape_.z_edges_m[k + 1] - shape_.z_edges_m[k];
      block.pad[std::size_t(k) * columns + c] = static_cast<float>(
          std::max(0.0, mu * std::log(p_top / bottom) / (settings_.leaf_projection * dz)));
    }
  }
  return block;
}

CloudGround grid_cloud_ground(const LasFile& cloud, const std::string& crs,
                              const std::string& crs_place, const GapFractionSettings& settings) {
  CloudGround out;
  const std::string place = cloud.path().string();
  const double s = settings.voxel_size_m;
  if (!(s > 0.0)) throw config_error("voxel_size_m", "must be > 0");
  out.crs_wkt = las_crs(cloud, crs, crs_place);
  const std::uint64_t count = cloud.header().point_count;
  // The extent, and the ground points.
  double lo[2] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  double hi[2] = {-lo[0], -lo[1]};
  std::vector<std::array<double, 3>> ground;
  std::vector<LasPoint> points;
  Patches patches;
  for (std::uint64_t first = 0; first < count; first += kPointWindow) {
    points.clear();
    cloud.read_points(first, kPointWindow, points);
    for (const LasPoint& p : points) {
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;
      patches.add(p.x, p.y);
      lo[0] = std::min(lo[0], p.x);
      lo[1] = std::min(lo[1], p.y);
      hi[0] = std::max(hi[0], p.x);
      hi[1] = std::max(hi[1], p.y);
      if (p.classification == 2 && !p.withheld) ground.push_back({p.x, p.y, p.z});
    }
  }
  out.points = count;
  out.ground_points = ground.size();
  if (!(hi[0] >= lo[0])) throw input_error(place, "the point cloud holds no point");
  patches.check(lo, hi, place);
  const double x0 = std::floor(lo[0] / s) * s, y0 = std::floor(lo[1] / s) * s;
  const double nx_real = std::floor((hi[0] - x0) / s) + 1,
               ny_real = std::floor((hi[1] - y0) / s) + 1;
  const double nz_real = std::ceil(settings.max_height_m / s);
  if (nx_real * ny_real * nz_real > double(VoxelGridFile::max_window_voxels))
    throw input_error(place, "the cloud spans " + std::to_string(nx_real) + " x " +
                                 std::to_string(ny_real) + " columns of " + std::to_string(s) +
                                 " m: more voxels than the limit of " +
                                 std::to_string(VoxelGridFile::max_window_voxels) +
                                 " (a larger voxel size, or tiles)");
  out.ground =
      grid_ground(ground, x0, y0, static_cast<int>(nx_real), static_cast<int>(ny_real), s, place);
  return out;
}

VoxelizeResult voxelize_point_cloud(const LasFile& cloud, const std::string& crs,
                                    const std::string& crs_place,
                                    const GapFractionSettings& settings,
                                    const CloudGround* gridded) {
  VoxelizeResult out;
  // Pass 1: the extent and the ground, unless the caller has them.
  if (gridded && gridded->ground.cell_m != settings.voxel_size_m)
    throw run_error(cloud.path().string(), "the cloud's ground was gridded at another voxel size");
  CloudGround first_pass;
  if (!gridded) first_pass = grid_cloud_ground(cloud, crs, crs_place, settings);
  const CloudGround& ground = gridded ? *gridded : first_pass;
  out.voxels.crs_wkt = ground.crs_wkt;
  out.ground = gridded ? gridded->ground : std::move(first_pass.ground);
  out.report.points = ground.points;
  out.report.ground_points = ground.ground_points;
  const int nx = out.ground.nx, ny = out.ground.ny;
  const double s = settings.voxel_size_m;

  VoxelBlock shape;
  shape.crs_wkt = out.voxels.crs_wkt;
  shape.nx = nx;
  shape.ny = ny;
  shape.nz = static_cast<int>(std::ceil(settings.max_height_m / s));
  shape.x0 = out.ground.x0;
  shape.y0 = out.ground.y0;
  shape.dx = shape.dy = s;
  for (int k = 0; k <= shape.nz; ++k) shape.z_edges_m.push_back(k * s);
  GapFractionInversion inversion(shape, out.ground, settings);
  // Pass 2: every return into its column and layer.
  std::vector<LasPoint> points;
  for (std::uint64_t first = 0; first < ground.points; first += kPointWindow) {
    points.clear();
    cloud.read_points(first, kPointWindow, points);
    for (const LasPoint& p : points) inversion.add(p, out.report);
  }
  out.voxels = inversion.result(out.report);
  // Layers above the highest non-empty one are dropped.
  const std::size_t columns = std::size_t(nx) * ny;
  int top = 0;
  for (int k = 0; k < out.voxels.nz; ++k)
    for (std::size_t c = 0; c < columns && top <= k; ++c)
      if (out.voxels.pad[k * columns + c] > 0.0f) top = k + 1;
  top = std::max(top, 1);
  out.voxels.nz = top;
  out.voxels.z_edges_m.resize(top + 1);
  out.voxels.pad.resize(columns * top);
  out.voxels.pad.shrink_to_fit();  // a run holds the grid: not the max_height_m layers' zeros
  return out;
}

}  // namespace glaswave
