// Voxel grids of plant area density (PAD, one-sided m^2 of plant per m^3), the `voxels` format of
// PRODUCT.md section 8:
//   - a CF NetCDF file with a variable `pad(z, y, x)`, coordinate variables x and y (cell
//     centres, in the CRS its grid_mapping variable gives as `crs_wkt` or `spatial_ref`), and z
//     the height above the ground of each layer's centre (its `bounds` variable, when present,
//     gives the layers' bottoms and tops; else layers are contiguous about the centres);
//   - a multi-band GeoTIFF (any raster GDAL reads), band i the layer between the heights its band
//     metadata `z_bottom_m` and `z_top_m` give.
// Heights are above the local ground, within 10 km of it. Columns are regular in x and y (north
// up, no rotation); layers may differ in thickness but neither overlap nor leave gaps. Packed
// values (CF's scale_factor and add_offset, a GDAL band's scale and offset) are unpacked.
//
// A grid is opened once and read by windows of columns (a shot needs a few hundred metres of a
// grid that may cover many km^2), as the DEM is.
//
// A NetCDF-4 grid is an HDF5 file, and Debian 12's HDF5 1.10.8 crashes on some corrupt ones (a
// read 16 MB past a heap buffer inside nc_inq_varndims): it is opened and read, window by window,
// by the small program glaswave-read-voxels (core/spawned_reader.hpp), started when the grid is
// opened and ended when it is closed, found as the granule reader is (footprints/granule.hpp). A
// crash there refuses the file. A classic NetCDF grid (CDF-1, 2, 5) is read here, its header's
// sizes checked against the file's first (canopy/netcdf_classic_header.hpp).
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

namespace glaswave {

// A block of a grid: nx * ny columns of nz layers, PAD at [(k * ny + j) * nx + i], row j = 0 the
// northernmost when north_up (GeoTIFF order) or the southernmost otherwise (NetCDF order with
// increasing y); x0, y0 the outer corner of column (0, 0), dx > 0, dy signed (negative north up).
struct VoxelBlock {
  std::string crs_wkt;
  int nx = 0, ny = 0, nz = 0;
  double x0 = 0.0, y0 = 0.0, dx = 1.0, dy = 1.0;
  std::vector<double> z_edges_m;  // nz + 1 heights above the ground, increasing
  std::vector<float> pad;         // m^2/m^3, >= 0

  float at(int i, int j, int k) const {
    return pad[(static_cast<std::size_t>(k) * ny + j) * nx + i];
  }
  // The column holding (x, y) in the grid's CRS; false when it is outside the block.
  bool column_of(double x, double y, int& i, int& j) const;
  double plant_area_index(int i, int j) const;  // sum of PAD x thickness over the column
};

class VoxelGridFile {
 public:
  // Largest grid a window read may return, in voxels (the configuration's windows are far less).
  static constexpr std::size_t max_window_voxels = std::size_t{1} << 28;

  // Opens a NetCDF (.nc) or GDAL raster file and checks it: dimensions, coordinates (regular),
  // layer heights (increasing, no gap), a CRS. An input error naming the file otherwise.
  explicit VoxelGridFile(const std::filesystem::path& file);
  // A grid held in memory (a point cloud voxelised at start), served by the same windows.
  explicit VoxelGridFile(VoxelBlock grid);
  ~VoxelGridFile();
  VoxelGridFile(const VoxelGridFile&) = delete;
  VoxelGridFile& operator=(const VoxelGridFile&) = delete;

  // The whole grid's extent and layers (its pad is empty but for a grid held in memory).
  const VoxelBlock& shape() const;

  // A grid is read by blocks of read_block_columns x read_block_columns columns, at multiples of
  // it from the grid's corner (VoxelFieldSource's tiles, each read once and kept packed), one
  // row of blocks after another: `voxelize` writes chunks of that many columns, each inflated
  // once. The decompressed chunks of a NetCDF grid kept between reads are those 2 x 2 blocks
  // meet at most (whole chunks, every layer: a file chunked otherwise inflates a chunk shared
  // by neighbouring blocks again only when the next row of blocks comes), up to
  // max_read_cache_bytes; 0 for a grid not read through NetCDF's chunks.
  static constexpr int read_block_columns = 64;
  static constexpr std::size_t max_read_cache_bytes = std::size_t{128} << 20;
  std::size_t read_cache_bytes() const;
  bool netcdf() const;  // read through NetCDF (else GDAL, or held in memory)

  // The columns that meet the rectangle [x_min, x_max] x [y_min, y_max] (the grid's CRS), read
  // from the file. Empty (nx = 0) when the rectangle misses the grid. Negative, NaN or fill PAD
  // values are an input error naming the file and the voxel. Thread-safe.
  VoxelBlock window(double x_min, double x_max, double y_min, double y_max) const;
  // The same window in two steps: its columns, [i0, i0 + ni) x [j0, j0 + nj) of the grid (all 0
  // when it misses; an input error when it is over max_window_voxels), then any block of them
  // read (a window read by bands of rows need not be held whole). Thread-safe.
  void window_columns(double x_min, double x_max, double y_min, double y_max, int& i0, int& ni,
                      int& j0, int& nj) const;
  VoxelBlock columns(int i0, int ni, int j0, int nj) const;

 private:
  struct InProcess {};
  // The grid read in this process, NetCDF-4 too: glaswave-read-voxels's.
  VoxelGridFile(const std::filesystem::path& file, InProcess);
  void open(const std::filesystem::path& file, bool spawn);
  friend int voxel_reader_main(int argc, char** argv);

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// glaswave-read-voxels's whole work: `argv` is the program and the grid. Opens the grid and writes
// its shape, or the error, to standard output; then answers each window asked on standard input
// with its checked densities, or the error, until its input ends. 0 when all was written.
int voxel_reader_main(int argc, char** argv);

// Writes a block as the `voxels` NetCDF format (CF-1.10), to `file`.part then renamed.
// `ground_m`, when not empty (nx * ny, rows as in the block), is written as `ground_elevation`.
void write_voxel_netcdf(const std::filesystem::path& file, const VoxelBlock& block,
                        const std::vector<float>& ground_m = {}, const std::string& history = "");

}  // namespace glaswave
