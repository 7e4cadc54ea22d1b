// Voxel fields: the column DDA, and windows of a grid file carried into a shot's frame.
#include "pipeline/scene/voxel_field.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <mutex>

#include "canopy/voxel_grid.hpp"
#include "core/error.hpp"
#include "pipeline/scene/scene.hpp"
#include "terrain/crs_transform.hpp"
#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

double VoxelField::top_m() const {
  double top = -std::numeric_limits<double>::infinity(), highest_ground = top;
  const std::size_t columns_n = static_cast<std::size_t>(nx) * ny;
  if (packed()) {
    // A column's highest non-empty layer ends at its `end` edge.
    for (std::size_t c = 0; c < columns_n; ++c)
      if (columns[c].first < columns[c].end && std::isfinite(ground_m[c]))
        top = std::max(top, ground_m[c] + z_edges_m[columns[c].end]);
    return top;
  }
  // Layer by layer from the top, in memory order (a column's layers lie `columns` apart): the
  // highest top of a non-empty voxel, down to the layer whose top cannot beat it.
  for (std::size_t c = 0; c < columns_n; ++c)
    if (std::isfinite(ground_m[c])) highest_ground = std::max(highest_ground, ground_m[c]);
  for (int k = nz - 1; k >= 0 && highest_ground + z_edges_m[k + 1] > top; --k) {
    const float* layer = pad.data() + k * columns_n;
    for (std::size_t c = 0; c < columns_n; ++c)
      if (layer[c] > 0.0f && std::isfinite(ground_m[c]))
        top = std::max(top, ground_m[c] + z_edges_m[k + 1]);
  }
  return top;
}

void VoxelField::pack() {
  const std::size_t columns_n = static_cast<std::size_t>(nx) * ny;
  if (columns_n == 0 || nz <= 0 || packed()) return;
  if (pad.size() > std::numeric_limits<std::uint32_t>::max()) return;  // the traversal reads `pad`
  columns.clear();
  auto block = std::make_shared<std::vector<float>>();
  block->reserve(pad.size());  // at most all of it: only the pages written become resident
  pack_columns(pad.data(), columns_n, nz, 0, columns, *block);
  blocks = {std::move(block)};
  std::vector<float>().swap(pad);
}

void VoxelField::pack_columns(const float* layers, std::size_t count, int nz, std::uint32_t block,
                              std::vector<Column>& columns, std::vector<float>& block_pad) {
  // By tiles of columns: a tile's row of a layer is a page of floats (read whole, in memory
  // order), turned column by column in a buffer that stays in cache; then each column's
  // stretch is found in it and copied out.
  constexpr std::size_t tile = 1024;
  std::vector<float> turned(tile * static_cast<std::size_t>(nz));
  for (std::size_t c0 = 0; c0 < count; c0 += tile) {
    const std::size_t n = std::min(count - c0, tile);
    for (int k = 0; k < nz; ++k) {
      const float* layer = layers + k * count + c0;
      float* to = turned.data() + k;
      for (std::size_t c = 0; c < n; ++c) to[c * nz] = layer[c];
    }
    for (std::size_t c = 0; c < n; ++c) {
      const float* from = turned.data() + c * nz;
      int first = 0, end = nz;
      while (first < nz && !(from[first] > 0.0f)) ++first;
      if (first == nz)
        first = end = 0;  // an empty column
      else
        while (!(from[end - 1] > 0.0f)) --end;
      columns.push_back({static_cast<std::uint32_t>(block_pad.size()), first, end, block});
      block_pad.insert(block_pad.end(), from + first, from + end);
    }
  }
}

namespace {

struct Emitter {
  std::vector<VolumeSpan>& spans;
  std::size_t first;  // spans before this index are not ours to merge with
  int material;
  const std::vector<double>* extinction_per_density;
  double depth_left;

  // Adds [t0, t1] at `density`; false when the free path has ended (stop).
  bool add(double t0, double t1, float density) {
    if (!(t1 > t0) || !(density > 0.0f)) return true;
    const double d = density;
    if (spans.size() > first && spans.back().end_m == t0 && spans.back().area_density_m2_m3 == d)
      spans.back().end_m = t1;
    else
      spans.push_back({t0, t1, d, material, -1});
    if (!extinction_per_density) return true;
    depth_left -= d * (*extinction_per_density)[material] * (t1 - t0);
    return depth_left > 0.0;
  }
};

// A column's layers as the traversal reads them: the non-empty ones lie in [first, end), the
// density of layer k at pad[(k - base) * stride] (packed: the column's stretch, from its first
// layer; else `pad` itself, from the ground).
struct ColumnView {
  const float* pad;
  std::size_t stride;
  int base, first, end;
  float at(int k) const { return pad[static_cast<std::size_t>(k - base) * stride]; }
};

struct PackedColumns {
  const VoxelField& f;
  ColumnView operator()(std::size_t column) const {
    const VoxelField::Column& c = f.columns[column];
    return {f.blocks[c.block]->data() + c.offset, 1, c.first, c.first, c.end};
  }
};

struct LayeredColumns {
  const VoxelField& f;
  std::size_t columns;
  ColumnView operator()(std::size_t column) const {
    return {f.pad.data() + column, columns, 0, 0, f.nz};
  }
};

// The traversal, reading each column through `column_of`.
template <class Columns>
void column_spans(const VoxelField& f, const Columns& column_of, const Vec3& origin,
                  const Vec3& direction, double max_distance_m, std::vector<VolumeSpan>& spans,
                  double depth, const std::vector<double>* extinction_per_density) {
  // The ray in column coordinates (u, v): p = origin + u * axis_i + v * axis_j.
  const double a = f.axis_i_m[0], b = f.axis_j_m[0], c = f.axis_i_m[1], d = f.axis_j_m[1];
  const double det = a * d - b * c;
  if (det == 0.0) return;
  const double px = origin[0] - f.origin_m[0], py = origin[1] - f.origin_m[1];
  const double u0 = (d * px - b * py) / det, v0 = (a * py - c * px) / det;
  const double du = (d * direction[0] - b * direction[1]) / det;
  const double dv = (a * direction[1] - c * direction[0]) / det;
  double t_enter = 0.0, t_exit = max_distance_m;
  const auto clip = [&](double start, double rate, int n) {
    if (rate == 0.0) return start >= 0.0 && start < n;
    double t0 = (0.0 - start) / rate, t1 = (n - start) / rate;
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
    return true;
  };
  if (!clip(u0, du, f.nx) || !clip(v0, dv, f.ny) || !(t_enter < t_exit)) return;
  // Above the highest column and below the lowest there is nothing to meet.
  if (direction[2] != 0.0) {
    double t0 = (f.bottom_m - origin[2]) / direction[2],
           t1 = (f.ceiling_m - origin[2]) / direction[2];
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
    if (!(t_enter < t_exit)) return;
  } else if (!(origin[2] >= f.bottom_m && origin[2] <= f.ceiling_m)) {
    return;
  }

  const auto cell = [](double x, int n) {
    return std::clamp(static_cast<int>(std::floor(x)), 0, n - 1);
  };
  int i = cell(u0 + t_enter * du, f.nx), j = cell(v0 + t_enter * dv, f.ny);
  const double inf = std::numeric_limits<double>::infinity();
  const int step_i = du > 0.0 ? 1 : -1, step_j = dv > 0.0 ? 1 : -1;
  const double delta_i = du != 0.0 ? 1.0 / std::abs(du) : inf;
  const double delta_j = dv != 0.0 ? 1.0 / std::abs(dv) : inf;
  double next_i = du > 0.0 ? (i + 1 - u0) / du : du < 0.0 ? (i - u0) / du : inf;
  double next_j = dv > 0.0 ? (j + 1 - v0) / dv : dv < 0.0 ? (j - v0) / dv : inf;

  Emitter emit{spans, spans.size(), f.material, extinction_per_density, depth};
  const double* edges = f.z_edges_m.data();
  const double oz = origin[2], dz = direction[2];
  for (double t_a = t_enter;;) {
    const double t_b = std::min({next_i, next_j, t_exit});
    const std::size_t column = static_cast<std::size_t>(j) * f.nx + i;
    const ColumnView layers = column_of(column);
    const double ground = f.ground_m[column];
    // Empty voxels give no span: only the column's non-empty stretch is cut.
    if (t_b > t_a && layers.first < layers.end && std::isfinite(ground)) {
      if (dz == 0.0) {
        const double h = oz - ground;
        const double* above = std::upper_bound(edges, edges + f.nz + 1, h);
        if (above != edges && above != edges + f.nz + 1) {
          const int k = static_cast<int>(above - edges) - 1;
          if (k >= layers.first && k < layers.end && !emit.add(t_a, t_b, layers.at(k))) return;
        }
      } else {
        // Heights above this column's ground at the stretch's ends; the layers between them in
        // the order the ray crosses them.
        const double h_a = oz + t_a * dz - ground, h_b = oz + t_b * dz - ground;
        const double low = std::min(h_a, h_b), high = std::max(h_a, h_b);
        if (high > edges[layers.first] && low < edges[layers.end]) {
          const double* from = edges + layers.first;
          const double* to = edges + layers.end + 1;
          const int k_low =
              std::max(static_cast<int>(std::upper_bound(from, to, low) - edges) - 1, layers.first);
          const int k_high = std::min(
              static_cast<int>(std::lower_bound(from, to, high) - edges) - 1, layers.end - 1);
          const int k_step = dz > 0.0 ? 1 : -1;
          const int k_first = dz > 0.0 ? k_low : k_high, k_last = dz > 0.0 ? k_high : k_low;
          // An edge's distance serves the two layers it parts: kept for the next layer.
          int edge_known = -1;
          double t_known = 0.0;
          const auto t_at = [&](int edge) {
            if (edge != edge_known) {
              edge_known = edge;
              t_known = (ground + edges[edge] - oz) / dz;
            }
            return t_known;
          };
          for (int k = k_first; k_step > 0 ? k <= k_last : k >= k_last; k += k_step) {
            const float density = layers.at(k);
            if (!(density > 0.0f)) continue;
            // Up, a layer is entered at its bottom edge; down, at its top.
            const double t_in = t_at(dz > 0.0 ? k : k + 1), t_out = t_at(dz > 0.0 ? k + 1 : k);
            const double t0 = std::min(t_in, t_out), t1 = std::max(t_in, t_out);
            if (!emit.add(std::max(t0, t_a), std::min(t1, t_b), density)) return;
          }
        }
      }
    }
    if (t_b >= t_exit) return;
    if (next_i <= next_j) {
      i += step_i;
      next_i += delta_i;
      if (i < 0 || i >= f.nx) return;
    } else {
      j += step_j;
      next_j += delta_j;
      if (j < 0 || j >= f.ny) return;
    }
    t_a = t_b;
  }
}

}  // namespace

void voxel_spans(const VoxelField& f, const Vec3& origin, const Vec3& direction,
                 double max_distance_m, std::vector<VolumeSpan>& spans, double depth,
                 const std::vector<double>* extinction_per_density) {
  if (f.nx <= 0 || f.ny <= 0 || f.nz <= 0) return;
  if (f.packed())
    column_spans(f, PackedColumns{f}, origin, direction, max_distance_m, spans, depth,
                 extinction_per_density);
  else
    column_spans(f, LayeredColumns{f, static_cast<std::size_t>(f.nx) * f.ny}, origin, direction,
                 max_distance_m, spans, depth, extinction_per_density);
}

namespace {

// Nodes along an axis of n columns: every `stride`-th and the last.
std::vector<int> ground_nodes(int n, int stride) {
  std::vector<int> nodes;
  for (int i = 0; i < n; i += stride) nodes.push_back(i);
  if (nodes.back() != n - 1) nodes.push_back(n - 1);
  return nodes;
}

// Column i between nodes k and k + 1 at weight t of the second.
void between_nodes(const std::vector<int>& nodes, int i, int stride, std::size_t& k, double& t) {
  k = std::min(static_cast<std::size_t>(i / stride), nodes.size() - 1);
  if (k + 1 >= nodes.size() || nodes[k] == i) {
    t = 0.0;
    return;
  }
  t = static_cast<double>(i - nodes[k]) / (nodes[k + 1] - nodes[k]);
}

}  // namespace

void fill_ground(VoxelField& f, const LocalFrame& frame, const Terrain& terrain, double cell_m) {
  const auto exact = [&](int i, int j) {
    const double lx = f.origin_m[0] + (i + 0.5) * f.axis_i_m[0] + (j + 0.5) * f.axis_j_m[0];
    const double ly = f.origin_m[1] + (i + 0.5) * f.axis_i_m[1] + (j + 0.5) * f.axis_j_m[1];
    const Geodetic g = frame.to_geodetic({lx, ly, 0.0});
    const double h = terrain.height_m(g.lat_deg, g.lon_deg);
    return std::isfinite(h) ? frame.to_local(Geodetic{g.lat_deg, g.lon_deg, h})[2]
                            : std::numeric_limits<double>::quiet_NaN();
  };
  const int stride = std::clamp(static_cast<int>(0.25 * terrain.detail_m() / cell_m), 1, 16);
  const std::vector<int> nodes_i = ground_nodes(f.nx, stride), nodes_j = ground_nodes(f.ny, stride);
  std::vector<double> node_m(nodes_i.size() * nodes_j.size());
  for (std::size_t b = 0; b < nodes_j.size(); ++b)
    for (std::size_t a = 0; a < nodes_i.size(); ++a)
      node_m[b * nodes_i.size() + a] = exact(nodes_i[a], nodes_j[b]);
  f.ground_m.resize(static_cast<std::size_t>(f.nx) * f.ny);
  for (int j = 0; j < f.ny; ++j) {
    std::size_t b = 0;
    double v = 0.0;
    between_nodes(nodes_j, j, stride, b, v);
    const std::size_t b1 = std::min(b + 1, nodes_j.size() - 1);
    for (int i = 0; i < f.nx; ++i) {
      std::size_t a = 0;
      double u = 0.0;
      between_nodes(nodes_i, i, stride, a, u);
      const std::size_t a1 = std::min(a + 1, nodes_i.size() - 1);
      const std::size_t w = nodes_i.size();
      const double g00 = node_m[b * w + a], g10 = node_m[b * w + a1];
      const double g01 = node_m[b1 * w + a], g11 = node_m[b1 * w + a1];
      double g = (1 - v) * ((1 - u) * g00 + u * g10) + v * ((1 - u) * g01 + u * g11);
      if (u == 0.0 && v == 0.0) g = g00;
      // Where the terrain has no data about the column, its own ground (or none).
      if (!std::isfinite(g)) g = exact(i, j);
      f.ground_m[static_cast<std::size_t>(j) * f.nx + i] = g;
    }
  }
  f.bottom_m = std::numeric_limits<double>::infinity();
  f.ceiling_m = -f.bottom_m;
  for (const double g : f.ground_m) {
    if (!std::isfinite(g)) continue;
    f.bottom_m = std::min(f.bottom_m, g + f.z_edges_m.front());
    f.ceiling_m = std::max(f.ceiling_m, g + f.z_edges_m.back());
  }
}

// A tile of the grid, packed: its columns (ni a row, row by row, tile-local offsets into `pad`).
struct PackedTile {
  int ni = 0;
  std::vector<VoxelField::Column> columns;
  std::shared_ptr<const std::vector<float>> pad;
  std::size_t bytes() const {
    return columns.size() * sizeof(VoxelField::Column) + pad->size() * sizeof(float);
  }
};

struct VoxelFieldSource::Impl {
  const VoxelGridFile* grid;
  std::string place;
  std::unique_ptr<CrsTransform> crs;

  // A tile's place in the cache: loaded once, by the first field that needs it (the others that
  // need it meanwhile wait on `loading`); dropped from the cache when least recently used.
  struct Slot {
    std::mutex loading;
    std::shared_ptr<const PackedTile> tile;  // set once loaded
    std::uint64_t last_used = 0;             // under the cache's mutex, as the two below
    bool cached = true;
    std::size_t bytes = 0;
  };
  std::mutex mutex;
  std::map<std::pair<int, int>, std::shared_ptr<Slot>> slots;
  std::uint64_t uses = 0;
  std::size_t cached_bytes = 0, max_cached_bytes = max_tile_cache_bytes;

  std::shared_ptr<const PackedTile> load(int ti, int tj) const {
    const VoxelBlock& shape = grid->shape();
    const int i0 = ti * tile_columns, j0 = tj * tile_columns;
    const int ni = std::min(tile_columns, shape.nx - i0),
              nj = std::min(tile_columns, shape.ny - j0);
    const VoxelBlock block = grid->columns(i0, ni, j0, nj);
    auto tile = std::make_shared<PackedTile>();
    tile->ni = ni;
    auto pad = std::make_shared<std::vector<float>>();
    VoxelField::pack_columns(block.pad.data(), static_cast<std::size_t>(ni) * nj, shape.nz, 0,
                             tile->columns, *pad);
    pad->shrink_to_fit();
    tile->pad = std::move(pad);
    return tile;
  }

  // The tiles (ti0..ti1) x (tj0..tj1), row by row, each loaded once and kept while the cache
  // holds it. Thread-safe.
  std::vector<std::shared_ptr<const PackedTile>> tiles(int ti0, int ti1, int tj0, int tj1) {
    std::vector<std::shared_ptr<Slot>> held;
    {
      const std::lock_guard lock(mutex);
      for (int tj = tj0; tj <= tj1; ++tj)
        for (int ti = ti0; ti <= ti1; ++ti) {
          std::shared_ptr<Slot>& slot = slots[{ti, tj}];
          if (!slot) slot = std::make_shared<Slot>();
          slot->last_used = ++uses;
          held.push_back(slot);
        }
    }
    std::vector<std::shared_ptr<const PackedTile>> found;
    for (std::size_t k = 0; k < held.size(); ++k) {
      Slot& slot = *held[k];
      const std::lock_guard loading(slot.loading);
      if (!slot.tile) {
        const int ti = ti0 + static_cast<int>(k) % (ti1 - ti0 + 1);
        const int tj = tj0 + static_cast<int>(k) / (ti1 - ti0 + 1);
        slot.tile = load(ti, tj);
        const std::lock_guard lock(mutex);
        if (slot.cached) {
          slot.bytes = slot.tile->bytes();
          cached_bytes += slot.bytes;
        }
      }
      found.push_back(slot.tile);
    }
    evict();
    return found;
  }

  // The least recently used tiles out of the cache while it holds more than its bytes (the
  // fields that hold them keep them until they end).
  void evict() {
    const std::lock_guard lock(mutex);
    while (cached_bytes > max_cached_bytes && !slots.empty()) {
      auto oldest = slots.begin();
      for (auto slot = slots.begin(); slot != slots.end(); ++slot)
        if (slot->second->last_used < oldest->second->last_used) oldest = slot;
      oldest->second->cached = false;
      cached_bytes -= oldest->second->bytes;
      slots.erase(oldest);
    }
  }
};

VoxelFieldSource::VoxelFieldSource(const VoxelGridFile& grid, const std::string& place,
                                   std::size_t tile_cache_bytes)
    : impl_(std::make_unique<Impl>()) {
  impl_->max_cached_bytes = tile_cache_bytes;
  impl_->grid = &grid;
  impl_->place = place;
  impl_->crs = std::make_unique<CrsTransform>(grid.shape().crs_wkt, "ellipsoid", place);
}

VoxelFieldSource::~VoxelFieldSource() = default;

void VoxelFieldSource::check_values(const LocalFrame& frame, double half_size_m) const {
  window(frame, nullptr, half_size_m, 0);
}

std::shared_ptr<const VoxelField> VoxelFieldSource::field(const LocalFrame& frame,
                                                          const Terrain& terrain,
                                                          double half_size_m, int material) const {
  return window(frame, &terrain, half_size_m, material);
}

std::shared_ptr<const VoxelField> VoxelFieldSource::window(const LocalFrame& frame,
                                                           const Terrain* terrain,
                                                           double half_size_m, int material) const {
  auto field = std::make_shared<VoxelField>();
  field->material = material;
  const VoxelBlock& shape = impl_->grid->shape();
  const Geodetic& centre = frame.origin();
  const auto [cx, cy] = impl_->crs->from_wgs84(centre.lon_deg, centre.lat_deg);
  if (!std::isfinite(cx) || !std::isfinite(cy)) return field;
  // The grid's axes carried into the frame (scale and meridian convergence included): one
  // cell's step in x and in y about the footprint, through PROJ and the frame.
  double x[3] = {cx, cx + shape.dx, cx}, y[3] = {cy, cy, cy + shape.dy}, z[3] = {0.0, 0.0, 0.0};
  impl_->crs->to_wgs84(3, x, y, z);
  Vec3 local[3];
  for (int p = 0; p < 3; ++p) {
    if (!std::isfinite(x[p]) || !std::isfinite(y[p])) return field;
    local[p] = frame.to_local(Geodetic{y[p], x[p], centre.h_m});
  }
  field->axis_i_m = {local[1][0] - local[0][0], local[1][1] - local[0][1]};
  field->axis_j_m = {local[2][0] - local[0][0], local[2][1] - local[0][1]};
  const double cell_i_m = std::hypot(field->axis_i_m[0], field->axis_i_m[1]);
  const double cell_j_m = std::hypot(field->axis_j_m[0], field->axis_j_m[1]);
  if (!(cell_i_m > 0.0 && cell_j_m > 0.0)) return field;
  const double hx = half_size_m / cell_i_m * std::abs(shape.dx);
  const double hy = half_size_m / cell_j_m * std::abs(shape.dy);
  int i0 = 0, ni = 0, j0 = 0, nj = 0;
  impl_->grid->window_columns(cx - hx, cx + hx, cy - hy, cy + hy, i0, ni, j0, nj);
  if (ni == 0) return field;
  // The window's corner as VoxelGridFile::window gives it.
  const double x0 = shape.x0 + i0 * shape.dx, y0 = shape.y0 + j0 * shape.dy;
  const double ci = (x0 - cx) / shape.dx, cj = (y0 - cy) / shape.dy;
  field->origin_m = {local[0][0] + ci * field->axis_i_m[0] + cj * field->axis_j_m[0],
                     local[0][1] + ci * field->axis_i_m[1] + cj * field->axis_j_m[1]};
  field->nx = ni;
  field->ny = nj;
  field->nz = shape.nz;
  field->z_edges_m = shape.z_edges_m;
  // The window's columns from the grid's packed tiles, which the field shares.
  const int t = tile_columns;
  const int ti0 = i0 / t, ti1 = (i0 + ni - 1) / t, tj0 = j0 / t, tj1 = (j0 + nj - 1) / t;
  if (!terrain) {  // checked: the tiles read (their values refused as a shot refuses them)
    impl_->tiles(ti0, ti1, tj0, tj1);
    return field;
  }
  fill_ground(*field, frame, *terrain, std::min(cell_i_m, cell_j_m));
  const std::vector<std::shared_ptr<const PackedTile>> tiles = impl_->tiles(ti0, ti1, tj0, tj1);
  const int tiles_across = ti1 - ti0 + 1;
  for (const auto& tile : tiles) field->blocks.push_back(tile->pad);
  field->columns.resize(static_cast<std::size_t>(ni) * nj);
  for (int j = 0; j < nj; ++j) {
    const int tj = (j0 + j) / t, b = (j0 + j) % t;
    for (int i = 0; i < ni; ++i) {
      const int ti = (i0 + i) / t, a = (i0 + i) % t;
      const auto block = static_cast<std::size_t>((tj - tj0) * tiles_across + (ti - ti0));
      const PackedTile& tile = *tiles[block];
      VoxelField::Column column = tile.columns[static_cast<std::size_t>(b) * tile.ni + a];
      column.block = static_cast<std::uint32_t>(block);
      field->columns[static_cast<std::size_t>(j) * ni + i] = column;
    }
  }
  return field;
}

}  // namespace glaswave
