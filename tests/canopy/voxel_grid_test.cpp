// Voxel grids of plant area density: the NetCDF written and read back by windows, a multi-band
// GeoTIFF with z_bottom_m / z_top_m band metadata written here with GDAL, and grids that must be
// refused (no CRS, layers with a gap, negative or missing density).
#include "canopy/voxel_grid.hpp"

#include <cpl_conv.h>
#include <gdal.h>
#include <gtest/gtest.h>
#include <netcdf.h>
#include <ogr_srs_api.h>

#include <cmath>
#include <fstream>
#include <string>

#include "core/error.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

// 6 x 4 columns of 2 m from (500000, 4000000), three layers 0-1-3-6 m, PAD = i + 10 j + 100 k.
VoxelBlock sample_block() {
  VoxelBlock b;
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRImportFromEPSG(srs, 32633);
  char* wkt = nullptr;
  OSRExportToWkt(srs, &wkt);
  b.crs_wkt = wkt;
  CPLFree(wkt);
  OSRDestroySpatialReference(srs);
  b.nx = 6;
  b.ny = 4;
  b.nz = 3;
  b.x0 = 500000.0;
  b.y0 = 4000000.0;
  b.dx = 2.0;
  b.dy = 2.0;
  b.z_edges_m = {0.0, 1.0, 3.0, 6.0};
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 6; ++i) b.pad.push_back(static_cast<float>(i + 10 * j + 100 * k) / 100);
  return b;
}

std::string refusal(const std::filesystem::path& file) {
  try {
    VoxelGridFile grid(file);
    grid.window(-1e9, 1e9, -1e9, 1e9);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    return e.what();
  }
  return "";
}

TEST(VoxelGrid, NetcdfWrittenAndReadBackByWindows) {
  test_support::ScratchDir dir;
  const VoxelBlock b = sample_block();
  write_voxel_netcdf(dir.path() / "pad.nc", b, std::vector<float>(24, 100.0f), "test");
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "pad.nc.part"));
  const VoxelGridFile grid(dir.path() / "pad.nc");
  EXPECT_EQ(grid.shape().nx, 6);
  EXPECT_EQ(grid.shape().nz, 3);
  EXPECT_DOUBLE_EQ(grid.shape().x0, 500000.0);
  EXPECT_DOUBLE_EQ(grid.shape().dy, 2.0);
  EXPECT_EQ(grid.shape().z_edges_m, b.z_edges_m);
  EXPECT_NE(grid.shape().crs_wkt.find("UTM zone 33N"), std::string::npos);
  // Columns 2-3 and rows 1-2: x in [500004.5, 500007.5], y in [4000003, 4000005].
  const VoxelBlock w = grid.window(500004.5, 500007.5, 4000003.0, 4000005.0);
  ASSERT_EQ(w.nx, 2);
  ASSERT_EQ(w.ny, 2);
  EXPECT_DOUBLE_EQ(w.x0, 500004.0);
  EXPECT_DOUBLE_EQ(w.y0, 4000002.0);
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 2; ++j)
      for (int i = 0; i < 2; ++i) EXPECT_FLOAT_EQ(w.at(i, j, k), b.at(i + 2, j + 1, k));
  EXPECT_NEAR(w.plant_area_index(0, 0), 0.12 * 1 + 1.12 * 2 + 2.12 * 3, 1e-5);
  EXPECT_EQ(grid.window(0.0, 1.0, 0.0, 1.0).nx, 0);  // off the grid
  // The same windows from a grid held in memory.
  const VoxelGridFile memory(sample_block());
  const VoxelBlock m = memory.window(500004.5, 500007.5, 4000003.0, 4000005.0);
  EXPECT_EQ(m.pad, w.pad);
  EXPECT_DOUBLE_EQ(m.x0, w.x0);
  EXPECT_DOUBLE_EQ(m.y0, w.y0);
}

TEST(VoxelGrid, MultiBandGeotiffWithLayerHeights) {
  test_support::ScratchDir dir;
  const VoxelBlock b = sample_block();
  const auto file = dir.path() / "pad.tif";
  GDALAllRegister();
  // North up: row 0 is the northernmost, so the block's rows go in reverse.
  GDALDatasetH ds =
      GDALCreate(GDALGetDriverByName("GTiff"), file.c_str(), 6, 4, 3, GDT_Float32, nullptr);
  double t[6] = {500000.0, 2.0, 0.0, 4000008.0, 0.0, -2.0};
  GDALSetGeoTransform(ds, t);
  GDALSetProjection(ds, b.crs_wkt.c_str());
  const int band_of_layer[3] = {2, 3, 1};  // bands in any order: the metadata says the heights
  for (int k = 0; k < 3; ++k) {
    GDALRasterBandH band = GDALGetRasterBand(ds, band_of_layer[k]);
    GDALSetMetadataItem(band, "z_bottom_m", std::to_string(b.z_edges_m[k]).c_str(), nullptr);
    GDALSetMetadataItem(band, "z_top_m", std::to_string(b.z_edges_m[k + 1]).c_str(), nullptr);
    std::vector<float> rows;
    for (int j = 3; j >= 0; --j)
      for (int i = 0; i < 6; ++i) rows.push_back(b.at(i, j, k));
    ASSERT_EQ(GDALRasterIO(band, GF_Write, 0, 0, 6, 4, rows.data(), 6, 4, GDT_Float32, 0, 0),
              CE_None);
  }
  GDALClose(ds);
  const VoxelGridFile grid(file);
  EXPECT_EQ(grid.shape().z_edges_m, b.z_edges_m);
  EXPECT_DOUBLE_EQ(grid.shape().dy, -2.0);
  const VoxelBlock w = grid.window(500004.5, 500005.5, 4000002.5, 4000003.5);  // column (2, 1)
  ASSERT_EQ(w.nx, 1);
  ASSERT_EQ(w.ny, 1);
  for (int k = 0; k < 3; ++k) EXPECT_FLOAT_EQ(w.at(0, 0, k), b.at(2, 1, k));
  int i = -1, j = -1;
  ASSERT_TRUE(grid.shape().column_of(500005.0, 4000003.0, i, j));
  EXPECT_EQ(i, 2);
  EXPECT_EQ(j, 2);  // counted from the north
}

TEST(VoxelGrid, RefusesGridsItCannotUse) {
  test_support::ScratchDir dir;
  VoxelBlock b = sample_block();
  b.pad[7] = -0.5f;
  write_voxel_netcdf(dir.path() / "negative.nc", b);
  EXPECT_NE(refusal(dir.path() / "negative.nc").find("negative"), std::string::npos);
  b = sample_block();
  b.pad[3] = std::nanf("");
  write_voxel_netcdf(dir.path() / "nan.nc", b);
  EXPECT_NE(refusal(dir.path() / "nan.nc"), "");
  b = sample_block();
  b.crs_wkt = "";
  write_voxel_netcdf(dir.path() / "nocrs.nc", b);
  EXPECT_NE(refusal(dir.path() / "nocrs.nc").find("CRS"), std::string::npos);
  // Bounds with a gap between layers 0 and 1.
  write_voxel_netcdf(dir.path() / "gap.nc", sample_block());
  int nc = -1, var = -1;
  ASSERT_EQ(nc_open((dir.path() / "gap.nc").c_str(), NC_WRITE, &nc), NC_NOERR);
  ASSERT_EQ(nc_inq_varid(nc, "z_bounds", &var), NC_NOERR);
  const std::size_t at[2] = {1, 0};
  const double bottom = 1.5;
  ASSERT_EQ(nc_put_var1_double(nc, var, at, &bottom), NC_NOERR);
  nc_close(nc);
  EXPECT_NE(refusal(dir.path() / "gap.nc").find("gap"), std::string::npos);
  EXPECT_NE(refusal(dir.path() / "missing.nc").find("no such"), std::string::npos);
  std::ofstream(dir.path() / "junk.nc") << "not a grid";
  EXPECT_NE(refusal(dir.path() / "junk.nc"), "");
}

}  // namespace
}  // namespace glaswave
