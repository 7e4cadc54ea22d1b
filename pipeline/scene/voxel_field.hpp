// A voxel grid of plant area density in a shot's local frame, and the stretches of a ray inside
// its non-empty voxels as the transport's VolumeSpans.
//
// Each column of the grid stands on the ground under its centre: its layers are heights above
// that ground, so a column is a prism from ground + z_edges[0] to ground + z_edges[nz]. On level
// ground this is a regular 3-D lattice and the traversal below is exactly Amanatides and Woo's
// (1987) 3-D DDA; over terrain the layers of neighbouring columns do not line up, so the DDA
// steps through columns in x and y (Amanatides-Woo in 2-D) and, in each column, cuts the ray at
// the column's own layer heights. The spans are exact for the prisms, in double precision.
// Where the ground mesh and a column's flat foot differ (a slope under a wide column: up to
// half the column's width times the slope), the surface the ray meets first wins, as for crowns.
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "canopy/voxel_grid.hpp"
#include "core/vec3.hpp"

namespace glaswave {

class Terrain;
class LocalFrame;
struct VolumeSpan;

struct VoxelField {
  // Column (i, j) is the parallelogram origin + a * axis_i + b * axis_j, a in [i, i + 1),
  // b in [j, j + 1): horizontal vectors in the local frame (a cell's edges).
  std::array<double, 2> origin_m{}, axis_i_m{1.0, 0.0}, axis_j_m{0.0, 1.0};
  int nx = 0, ny = 0, nz = 0;
  std::vector<double> z_edges_m;  // nz + 1 heights above the ground, increasing
  std::vector<double> ground_m;   // local height of the ground under each column, [j * nx + i]
  std::vector<float> pad;         // m^2/m^3 at [(k * ny + j) * nx + i]; empty once packed
  int material = 0;               // the foliage of every voxel
  // The grid column by column, once packed: column c's layers from its lowest non-empty one to
  // its highest, [first, end) (first == end: an empty column), at (*blocks[block])[offset] on.
  // A ray down a column then reads consecutive floats where the layers of `pad` lie nx * ny
  // floats apart (a cache miss a voxel, most of a shot's time), and skips the empty layers. A
  // field packed from its own `pad` holds one block; the fields a grid file serves share its
  // tiles' blocks (VoxelFieldSource), so that a shot packs only the columns no shot has before.
  struct Column {
    std::uint32_t offset = 0;
    std::int32_t first = 0, end = 0;
    std::uint32_t block = 0;
  };
  std::vector<Column> columns;
  std::vector<std::shared_ptr<const std::vector<float>>> blocks;
  // The lowest bottom and highest top of any column (local frame), set with the ground by
  // fill_ground: a ray is traversed only between them (unbounded when not set).
  double bottom_m = -std::numeric_limits<double>::infinity();
  double ceiling_m = std::numeric_limits<double>::infinity();

  // Highest point of any non-empty voxel (local frame); -infinity for an empty field.
  double top_m() const;

  // Moves `pad` into `columns` and one block (and frees it): the traversal and top_m give the
  // same values, to the bit, packed or not.
  void pack();
  bool packed() const { return !columns.empty(); }
  // Packs `count` columns of `nz` layers, given layer by layer (layer k of the c-th at
  // layers[k * count + c]), onto `columns` (each of block `block`) and `block_pad`.
  static void pack_columns(const float* layers, std::size_t count, int nz, std::uint32_t block,
                           std::vector<Column>& columns, std::vector<float>& block_pad);
};

// Appends to `spans` every stretch of origin + t * direction, t in [0, max_distance_m], inside a
// voxel of non-zero density, in order along the ray; adjacent stretches of equal density are
// merged. With `extinction_per_density` (by material), the traversal stops after the span in
// which the voxels' own optical depth reaches `depth`: the free path has ended there.
void voxel_spans(const VoxelField& field, const Vec3& origin, const Vec3& direction,
                 double max_distance_m, std::vector<VolumeSpan>& spans, double depth = 0.0,
                 const std::vector<double>* extinction_per_density = nullptr);

// Sets the ground under each of the field's columns (its origin, axes and sizes set), in the
// frame: the terrain's height under the column's centre, exact at nodes every few columns (as
// many as fit in a quarter of the terrain's detail, the spacing of the ground mesh the rays meet;
// at most 16) and bilinear between them, or exact at every column of a fine DEM. Computing it at
// every column of a 1 m grid (a quarter of a million geodetic conversions) was most of a shot.
void fill_ground(VoxelField& field, const LocalFrame& frame, const Terrain& terrain, double cell_m);

// A voxel grid file placed under shots: for each shot, the window of the grid within
// `half_size_m` of the footprint, carried into the shot's frame, each column standing on the
// terrain under its centre. The grid is read and packed by tiles of tile_columns x tile_columns
// columns, kept (the least recently used dropped beyond max_tile_cache_bytes) and shared by the
// shots' fields: consecutive shots' windows overlap, and a 1 m grid's window is 10^7 voxels,
// which every shot read and packed anew (nearly all of a shot's fixed cost).
class VoxelFieldSource {
 public:
  // `grid` must outlive this. Its CRS is read with PROJ; an input error naming `place` when PROJ
  // cannot use it.
  // `tile_cache_bytes`: the packed tiles kept between shots, at most (tests make it small).
  static constexpr int tile_columns = VoxelGridFile::read_block_columns;
  static constexpr std::size_t max_tile_cache_bytes = std::size_t{256} << 20;
  VoxelFieldSource(const VoxelGridFile& grid, const std::string& place,
                   std::size_t tile_cache_bytes = max_tile_cache_bytes);
  ~VoxelFieldSource();

  // The field around the frame's origin (empty, nx = 0, when the grid does not reach it).
  // Columns over terrain without data are left empty.
  std::shared_ptr<const VoxelField> field(const LocalFrame& frame, const Terrain& terrain,
                                          double half_size_m, int material) const;
  // Reads the tiles field() would read, and refuses their values as it does (an input error
  // naming the voxel), without the ground or the field: for `check`.
  void check_values(const LocalFrame& frame, double half_size_m) const;

 private:
  // field(), or with no terrain check_values() (an empty field).
  std::shared_ptr<const VoxelField> window(const LocalFrame& frame, const Terrain* terrain,
                                           double half_size_m, int material) const;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace glaswave
