// Fuzzes the voxel grid reader (canopy/voxel_grid: VoxelGridFile over a NetCDF file or a GDAL
// raster, its shape, coordinates, layer heights, fill, packing and CRS checked when opened, and
// its values when read). The input's first byte picks the format (.nc or .tif); the rest is the
// file, opened, then read whole by windows of the size a shot reads. A NetCDF-4 grid is read by
// the program glaswave-read-voxels (canopy/voxel_grid.hpp), as the library reads it: what
// crashes that program (HDF5 1.10 on some corrupt files) is a refusal by design, its sanitizer's
// report, if any, in the log, and libFuzzer's coverage does not reach into it. An input Error is a
// refusal; anything else (a crash, a read out of bounds, a hang, an allocation beyond the limit,
// a file left open) is a finding. library_leaks.supp suppresses leaks with a frame inside
// libnetcdf or HDF5, which would hide a file glaswave forgot to close: the check below finds that
// instead.
#include <gdal.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "canopy/voxel_grid.hpp"
#include "core/error.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  glaswave::fuzz::keep_only_gdal_drivers({"GTiff", "netCDF"});
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  if (size == 0) return 0;
  const auto file = fuzz::write_input(data[0] % 2 ? "grid.tif" : "grid.nc", data + 1, size - 1);
  try {
    const VoxelGridFile grid(file);
    const VoxelBlock& shape = grid.shape();
    // What a shot relies on once the grid is open: layers increasing, steps finite.
    for (std::size_t k = 0; k + 1 < shape.z_edges_m.size(); ++k)
      if (!(shape.z_edges_m[k + 1] > shape.z_edges_m[k])) __builtin_trap();
    if (!std::isfinite(shape.dx) || !std::isfinite(shape.dy)) __builtin_trap();
    // The grid read by blocks of 64 x 64 columns (a shot's tiles), at most 16 of them.
    constexpr int kBlock = VoxelGridFile::read_block_columns;
    int blocks = 0;
    for (int j0 = 0; j0 < shape.ny && blocks < 16; j0 += kBlock)
      for (int i0 = 0; i0 < shape.nx && blocks < 16; i0 += kBlock, ++blocks) {
        const VoxelBlock block =
            grid.columns(i0, std::min(kBlock, shape.nx - i0), j0, std::min(kBlock, shape.ny - j0));
        for (float v : block.pad)
          if (!(v >= 0.0f) || !std::isfinite(v)) __builtin_trap();  // refused, never handed on
      }
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  // No file left open, on refusal too: libnetcdf numbers its open files 1, 2, ... (shifted by
  // 16 bits into the id), GDAL lists its datasets.
  int format = 0;
  for (int slot = 1; slot <= 4; ++slot)
    if (nc_inq_format(slot << 16, &format) == NC_NOERR) __builtin_trap();
  int open_datasets = 0;
  GDALDatasetH* datasets = nullptr;
  GDALGetOpenDatasets(&datasets, &open_datasets);
  if (open_datasets != 0) __builtin_trap();
  std::filesystem::remove(file);
  return 0;
}
