// Voxel grids of plant area density: the NetCDF written and read back by windows, a multi-band
// GeoTIFF with z_bottom_m / z_top_m band metadata written here with GDAL, and grids that must be
// refused (no CRS, layers with a gap, negative or missing density); grids written by hand with
// NetCDF-C in every way a grid can be wrong (issue 42): bounds or coordinates of other shapes,
// dimensions in another order, values never written, heights no layer reaches; CF packing and
// NC_STRING attributes read as CF means them.
#include "canopy/voxel_grid.hpp"

#include <cpl_conv.h>
#include <gdal.h>
#include <gtest/gtest.h>
#include <netcdf.h>
#include <ogr_srs_api.h>
#include <sys/resource.h>

#include <chrono>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <tuple>

#include "core/error.hpp"
#include "core/spawned_reader.hpp"
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

// A grid written by hand: dimensions z, y, x of 3, 4, 6 (or those given), coordinate variables
// of the sample block's centres, pad written as `put_pad` does; `extra` defines more before the
// definitions end. Returns the file.
struct HandGrid {
  std::vector<std::string> order = {"z", "y", "x"};  // pad's dimensions, by name
  std::size_t z_bounds_rows = 0;                     // 0: no z_bounds
  bool x_two_dimensional = false;
  bool crs_as_nc_string = false;
  nc_type pad_type = NC_FLOAT;
  bool write_pad = true;  // false: only layer 0 written
  std::function<void(int nc, int pad)> extra;
  std::function<void(int nc, int pad)> put_pad;  // replaces writing the sample's values
  std::vector<double> z_bounds = {0, 1, 1, 3, 3, 6, 6, 10, 10, 15};
  int format = NC_NETCDF4;  // or a classic one: 0 (CDF-1), NC_64BIT_OFFSET, NC_64BIT_DATA
};

std::filesystem::path write_hand_grid(const std::filesystem::path& file, const HandGrid& g) {
  const VoxelBlock b = sample_block();
  int nc = -1;
  EXPECT_EQ(nc_create(file.c_str(), g.format | NC_CLOBBER, &nc), NC_NOERR);
  int dz, dy, dx, dnv, dzb = -1;
  nc_def_dim(nc, "z", 3, &dz);
  nc_def_dim(nc, "y", 4, &dy);
  nc_def_dim(nc, "x", 6, &dx);
  nc_def_dim(nc, "nv", 2, &dnv);
  const auto dim = [&](const std::string& name) {
    return name == "z" ? dz : name == "y" ? dy : dx;
  };
  int vx, vy, vz, vzb = -1, vcrs, vpad;
  if (g.x_two_dimensional) {
    const int d[2] = {dy, dx};
    nc_def_var(nc, "x", NC_DOUBLE, 2, d, &vx);
  } else {
    nc_def_var(nc, "x", NC_DOUBLE, 1, &dx, &vx);
  }
  nc_def_var(nc, "y", NC_DOUBLE, 1, &dy, &vy);
  nc_def_var(nc, "z", NC_DOUBLE, 1, &dz, &vz);
  if (g.z_bounds_rows > 0) {
    nc_put_att_text(nc, vz, "bounds", 8, "z_bounds");
    if (g.z_bounds_rows != 3) nc_def_dim(nc, "zb", g.z_bounds_rows, &dzb);
    const int d[2] = {g.z_bounds_rows == 3 ? dz : dzb, dnv};
    nc_def_var(nc, "z_bounds", NC_DOUBLE, 2, d, &vzb);
  }
  nc_def_var(nc, "crs", NC_INT, 0, nullptr, &vcrs);
  if (g.crs_as_nc_string) {
    const char* wkt = b.crs_wkt.c_str();
    nc_put_att_string(nc, vcrs, "crs_wkt", 1, &wkt);
  } else {
    nc_put_att_text(nc, vcrs, "crs_wkt", b.crs_wkt.size(), b.crs_wkt.c_str());
  }
  const int pad_dims[3] = {dim(g.order[0]), dim(g.order[1]), dim(g.order[2])};
  nc_def_var(nc, "pad", g.pad_type, 3, pad_dims, &vpad);
  nc_put_att_text(nc, vpad, "grid_mapping", 3, "crs");
  if (g.extra) g.extra(nc, vpad);
  EXPECT_EQ(nc_enddef(nc), NC_NOERR);
  std::vector<double> c;
  for (int i = 0; i < 6; ++i) c.push_back(b.x0 + (i + 0.5) * b.dx);
  if (g.x_two_dimensional) {
    std::vector<double> xy;
    for (int j = 0; j < 4; ++j) xy.insert(xy.end(), c.begin(), c.end());
    nc_put_var_double(nc, vx, xy.data());
  } else {
    nc_put_var_double(nc, vx, c.data());
  }
  c.clear();
  for (int j = 0; j < 4; ++j) c.push_back(b.y0 + (j + 0.5) * b.dy);
  nc_put_var_double(nc, vy, c.data());
  // The bounds' middles; without bounds, 1 m layers from the ground (centres 0.5, 2 and 4.5
  // would make the first layer's bottom -0.25 m, under the ground).
  const double zc[3] = {0.5, vzb >= 0 ? 2.0 : 1.5, vzb >= 0 ? 4.5 : 2.5};
  nc_put_var_double(nc, vz, zc);
  if (vzb >= 0) {
    std::vector<double> zb(g.z_bounds.begin(), g.z_bounds.begin() + 2 * g.z_bounds_rows);
    nc_put_var_double(nc, vzb, zb.data());
  }
  if (g.put_pad) {
    g.put_pad(nc, vpad);
  } else if (g.write_pad) {
    nc_put_var_float(nc, vpad, b.pad.data());
  } else {
    const std::size_t start[3] = {0, 0, 0}, count[3] = {1, 4, 6};
    nc_put_vara_float(nc, vpad, start, count, b.pad.data());
  }
  EXPECT_EQ(nc_close(nc), NC_NOERR);
  return file;
}

TEST(VoxelGrid, HandWrittenGridsOfOtherShapesAreRefusedNotOverrun) {
  test_support::ScratchDir dir;
  HandGrid g;
  EXPECT_EQ(refusal(write_hand_grid(dir.path() / "plain.nc", g)), "");  // the writer is right
  g.z_bounds_rows = 3;
  EXPECT_EQ(refusal(write_hand_grid(dir.path() / "bounds.nc", g)), "");
  g.z_bounds_rows = 5;  // more rows than z: read whole, it overran
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "rows.nc", g)).find("z bounds are not (z, 2)"),
            std::string::npos);
  g = HandGrid();
  g.x_two_dimensional = true;  // x(y, x): 24 values into 6
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "x2d.nc", g)).find("not one-dimensional"),
            std::string::npos);
  g = HandGrid();
  g.order = {"x", "y", "z"};
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "xyz.nc", g)).find("ordered (z, y, x)"),
            std::string::npos);
  g = HandGrid();
  g.write_pad = false;  // layers 1 and 2 hold NetCDF's default fill
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "unwritten.nc", g)).find("z 1 of the grid"),
            std::string::npos);
  g.pad_type = NC_DOUBLE;  // a double's fill, read as a float
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "unwritten_double.nc", g)).find("missing"),
            std::string::npos);
}

TEST(VoxelGrid, HeightsNoVegetationReachesAreRefused) {
  test_support::ScratchDir dir;
  HandGrid g;
  g.z_bounds_rows = 3;
  g.z_bounds = {0, 1, 1, 3, 3, 1e300};
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "high.nc", g)).find("within 10000 m"),
            std::string::npos);
  g.z_bounds = {-1e5, 1, 1, 3, 3, 6};
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "low.nc", g)).find("layer 0's bottom"),
            std::string::npos);
  // Centres near 1e308: the top edge computed from them overflows.
  g = HandGrid();
  g.extra = [](int, int) {};
  const auto file = write_hand_grid(dir.path() / "centres.nc", g);
  int nc = -1, var = -1;
  ASSERT_EQ(nc_open(file.c_str(), NC_WRITE, &nc), NC_NOERR);
  nc_inq_varid(nc, "z", &var);
  const double z[3] = {1e307, 5e307, 1.7e308};
  nc_put_var_double(nc, var, z);
  nc_close(nc);
  EXPECT_NE(refusal(file).find("within 10000 m"), std::string::npos);
}

TEST(VoxelGrid, CfPackingIsAppliedAndAStringAttributeRead) {
  test_support::ScratchDir dir;
  const VoxelBlock b = sample_block();
  HandGrid g;
  g.pad_type = NC_SHORT;
  g.extra = [](int nc, int pad) {
    const double scale = 0.01, offset = 0.5;
    const short fill = -1;
    nc_put_att_double(nc, pad, "scale_factor", NC_DOUBLE, 1, &scale);
    nc_put_att_double(nc, pad, "add_offset", NC_DOUBLE, 1, &offset);
    nc_put_att_short(nc, pad, "_FillValue", NC_SHORT, 1, &fill);
  };
  std::vector<short> packed;  // pad = 0.01 n + 0.5
  for (float v : b.pad) packed.push_back(static_cast<short>(std::lround(v * 100)));
  g.put_pad = [&](int nc, int pad) { nc_put_var_short(nc, pad, packed.data()); };
  const VoxelGridFile grid(write_hand_grid(dir.path() / "packed.nc", g));
  const VoxelBlock all = grid.window(-1e9, 1e9, -1e9, 1e9);
  ASSERT_EQ(all.pad.size(), b.pad.size());
  for (std::size_t n = 0; n < b.pad.size(); ++n)
    EXPECT_NEAR(all.pad[n], 0.01 * packed[n] + 0.5, 1e-6) << n;
  packed[5] = -1;  // the packed fill: missing, not -0.01 + 0.5
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "packed_fill.nc", g)).find("z 0 of the grid"),
            std::string::npos);

  g = HandGrid();
  g.crs_as_nc_string = true;
  const VoxelGridFile named(write_hand_grid(dir.path() / "string.nc", g));
  EXPECT_EQ(named.shape().crs_wkt, b.crs_wkt);
}

// Issue 42: units were not read (pad in cm2 cm-3, z in cm, x in km all taken as metres). Known
// units are converted: cm2 cm-3 is 100 m2 m-3, a cm 0.01 m, a km 1000 m; others refused naming
// the variable; a layer under the ground and a centre outside its bounds refused.
TEST(VoxelGrid, UnitsAreReadAndLayersBelowTheGroundRefused) {
  test_support::ScratchDir dir;
  const VoxelBlock b = sample_block();
  const auto with_units = [](const char* variable, const char* units) {
    return [=](int nc, int pad) {
      int var = pad;
      if (std::string(variable) != "pad") nc_inq_varid(nc, variable, &var);
      nc_put_att_text(nc, var, "units", std::strlen(units), units);
    };
  };
  HandGrid g;
  g.z_bounds_rows = 3;
  g.extra = with_units("pad", "cm2 cm-3");
  const VoxelGridFile cm(write_hand_grid(dir.path() / "cm.nc", g));
  const VoxelBlock all = cm.window(-1e9, 1e9, -1e9, 1e9);
  ASSERT_EQ(all.pad.size(), b.pad.size());
  for (std::size_t n = 0; n < b.pad.size(); ++n) EXPECT_FLOAT_EQ(all.pad[n], 100 * b.pad[n]) << n;
  g.extra = with_units("z", "cm");  // bounds 0-1-3-6 cm, without units of their own
  EXPECT_EQ(VoxelGridFile(write_hand_grid(dir.path() / "z.nc", g)).shape().z_edges_m,
            (std::vector<double>{0.0, 0.01, 0.03, 0.06}));
  g.extra = with_units("x", "km");  // x centres of 500001 km... over a CRS in metres
  const VoxelBlock km = VoxelGridFile(write_hand_grid(dir.path() / "km.nc", g)).shape();
  EXPECT_DOUBLE_EQ(km.x0, 1000 * b.x0);
  EXPECT_DOUBLE_EQ(km.dx, 1000 * b.dx);
  EXPECT_DOUBLE_EQ(km.dy, b.dy);
  for (const auto& [variable, units, says] :
       {std::tuple<const char*, const char*, const char*>{"pad", "furlong-1", "`pad`'s units"},
        {"pad", "m2 m-2", "not a plant area density"},
        {"z", "hands", "the units of z are \"hands\""},
        {"y", "leagues", "the units of y"}}) {
    g.extra = with_units(variable, units);
    EXPECT_NE(refusal(write_hand_grid(dir.path() / "unknown.nc", g)).find(says), std::string::npos)
        << units;
  }
  g.extra = {};
  g.z_bounds = {-2, 1, 1, 3, 3, 6};  // the first layer's centre 0.5 lies in it
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "under.nc", g)).find("under the ground"),
            std::string::npos);
  g.z_bounds = {0, 1, 1, 3, 3, 6};
  g.put_pad = [&](int nc, int pad) {  // centres 0.5, 0.5, 0.5: the second outside [1, 3]
    int z = -1;
    nc_inq_varid(nc, "z", &z);
    const double repeated[3] = {0.5, 0.5, 0.5};
    nc_put_var_double(nc, z, repeated);
    nc_put_var_float(nc, pad, b.pad.data());
  };
  EXPECT_NE(refusal(write_hand_grid(dir.path() / "repeated.nc", g))
                .find("z centre 1 (0.500000 m) lies outside its bounds [1.000000, 3.000000] m"),
            std::string::npos);
}

// A GeoTIFF of one band 0-`top` m, with a scale of its own.
std::filesystem::path write_one_band(const std::filesystem::path& file, const char* top,
                                     double scale = 1.0) {
  GDALAllRegister();
  GDALDatasetH ds =
      GDALCreate(GDALGetDriverByName("GTiff"), file.c_str(), 2, 2, 1, GDT_Float32, nullptr);
  double t[6] = {500000.0, 2.0, 0.0, 4000008.0, 0.0, -2.0};
  GDALSetGeoTransform(ds, t);
  GDALSetProjection(ds, sample_block().crs_wkt.c_str());
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  GDALSetMetadataItem(band, "z_bottom_m", "0", nullptr);
  GDALSetMetadataItem(band, "z_top_m", top, nullptr);
  if (scale != 1.0) GDALSetRasterScale(band, scale);
  const float values[4] = {1.0f, 2.0f, 3.0f, 4.0f};
  EXPECT_EQ(
      GDALRasterIO(band, GF_Write, 0, 0, 2, 2, const_cast<float*>(values), 2, 2, GDT_Float32, 0, 0),
      CE_None);
  GDALClose(ds);
  return file;
}

TEST(VoxelGrid, GeotiffHeightsAreNumbersOfMetresAndItsScaleApplied) {
  test_support::ScratchDir dir;
  for (const char* top : {"ten", "10 ft", "1e400", "0x10", "nan"})
    EXPECT_NE(refusal(write_one_band(dir.path() / "top.tif", top)).find("not a number of metres"),
              std::string::npos)
        << top;
  const VoxelGridFile grid(write_one_band(dir.path() / "scaled.tif", " 10.5", 0.25));
  EXPECT_EQ(grid.shape().z_edges_m, (std::vector<double>{0.0, 10.5}));
  const VoxelBlock all = grid.window(-1e9, 1e9, -1e9, 1e9);
  EXPECT_EQ(all.pad, (std::vector<float>{0.25f, 0.5f, 0.75f, 1.0f}));
}

// The fuzz target's regressions (tests/fuzz/corpus/voxel/regression-*: the first byte picks the
// format, the rest is the file), each once a crash or an allocation beyond the limit, are refused
// as input errors naming the file: a corrupt NetCDF-4 grid on which HDF5 1.10.8 read 16 MB past a
// heap buffer (it crashed the process: now its reader program), a 23-byte classic NetCDF asking
// nc_open for 9 GB, a GeoTIFF whose pixel size is not finite.
TEST(VoxelGrid, TheFuzzRegressionsAreRefusedAsInputErrorsNamingTheFile) {
  test_support::ScratchDir dir;
  const std::filesystem::path corpus =
      std::filesystem::path(GLASWAVE_SOURCE_DIR) / "tests/fuzz/corpus/voxel";
  int refused = 0;
  for (const auto& entry : std::filesystem::directory_iterator(corpus)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("regression-", 0) != 0) continue;
    std::ifstream in(entry.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ASSERT_FALSE(bytes.empty()) << name;
    const auto file = dir.path() / (name + (bytes[0] % 2 ? ".tif" : ".nc"));
    std::ofstream(file, std::ios::binary) << bytes.substr(1);
    const std::string error = refusal(file);
    EXPECT_EQ(error.rfind(file.string() + ": ", 0), 0u) << name << ": " << error;
    EXPECT_EQ(error.find('\n'), std::string::npos) << name;
    ++refused;
  }
  EXPECT_GE(refused, 3);
}

// A corrupt NetCDF-4 grid on which HDF5 1.10.8 spins for ever (voxel_fuzzer, seed 1, in a
// fresh-clone CI run: 6 min of CPU before it was killed): its reader is ended at its CPU budget,
// 1 s for a file of 10,702 bytes (1 s + 10,702 B / 16 MiB per s, rounded up to whole seconds), and
// the grid refused saying so, with the CPU its reader used: after 1 s of the reader's CPU (this
// process's children's, which the kernel gives), less than 3 budgets of it, and within 60 s of wall
// time (10.5 s at a load of 9 on 2 cores; the hang was 6 min).
TEST(VoxelGrid, AGridOnWhichHdf5SpinsIsRefusedAtItsReadersCpuBudget) {
  test_support::ScratchDir dir;
  std::ifstream in(std::filesystem::path(GLASWAVE_SOURCE_DIR) /
                       "tests/fuzz/corpus/voxel/regression-netcdf4-hdf5-spins",
                   std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  ASSERT_EQ(bytes.size(), 10703u);  // the first byte picks NetCDF
  const auto file = dir.path() / "spins.nc";
  std::ofstream(file, std::ios::binary) << bytes.substr(1);
  const auto children_cpu_s = [] {
    rusage used{};
    ::getrusage(RUSAGE_CHILDREN, &used);
    return cpu_seconds(used);
  };
  const double cpu_before_s = children_cpu_s();
  const auto start = std::chrono::steady_clock::now();
  const std::string error = refusal(file);
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const double reader_cpu_s = children_cpu_s() - cpu_before_s;
  // The CPU said is the reader's, as this process's children's count gives it (to its 0.1 s).
  const std::string said =
      file.string() +
      ": reading the voxel grid took its reader program, glaswave-read-voxels, "
      "past its CPU budget on one request (1 s, and 1 s for each 16 MiB of "
      "the file and of its answer; ";
  const std::string cut = " s of CPU in all), so the file may be corrupt: it is refused";
  ASSERT_EQ(error.rfind(said, 0), 0u) << error;
  ASSERT_GT(error.size(), said.size() + cut.size()) << error;
  EXPECT_EQ(error.substr(error.size() - cut.size()), cut) << error;
  const double said_cpu_s = std::stod(error.substr(said.size()));
  EXPECT_NEAR(said_cpu_s, reader_cpu_s, 0.051) << error;
  EXPECT_GE(reader_cpu_s, 1.0);
  EXPECT_LT(reader_cpu_s, 3.0);
  EXPECT_LT(wall_s, 60.0);
}

// A classic NetCDF header's declared sizes are checked against the file before nc_open (which
// allocates them). The regression's bytes worked by hand: "CDF" 1, no records, NC_DIMENSION
// (0x0A), then a count of 0x4344460A = 1128547850 dimensions in a file of 23 bytes.
TEST(VoxelGrid, AClassicHeaderDeclaringMoreThanItsFileHoldsIsRefused) {
  test_support::ScratchDir dir;
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(dir.path() / name, std::ios::binary) << bytes;
    return dir.path() / name;
  };
  const std::string nine_gb(
      "CDF\x01\0\0\0\0\0\0\0\x0a"
      "CDF\x0a\x0bP_C\x0a\x0a\0",
      23);
  EXPECT_NE(refusal(write("nine_gb.nc", nine_gb)).find("declares 1128547850 dimensions"),
            std::string::npos);
  // Two dimensions declared: "x" of 4, then a name of no character, and the file ends.
  const std::string cut(
      "CDF\x01"
      "\0\0\0\0\0\0\0\x0a\0\0\0\x02\0\0\0\x01"
      "x\0\0\0\0\0\0\x04\0\0\0\0",
      32);
  EXPECT_NE(refusal(write("cut.nc", cut)).find("cut short"), std::string::npos);
  // An attribute of 2^30 doubles in a file of 40 bytes.
  const std::string values(
      "CDF\x01"
      "\0\0\0\0\0\0\0\0\0\0\0\0\0\0\0\x0c\0\0\0\x01\0\0\0\x01"
      "a\0\0\0\0\0\0\x06\x40\0\0\0",
      40);
  EXPECT_NE(refusal(write("values.nc", values)).find("declares 1073741824 attribute values"),
            std::string::npos);
}

// The walk of the header reads what libnetcdf writes: the hand grid (dimensions, a CRS attribute
// of some 600 bytes, variables with attributes) in each classic version is read as it is in
// NetCDF-4.
TEST(VoxelGrid, ClassicGridsOfEachVersionAreRead) {
  test_support::ScratchDir dir;
  for (const int format : {0, NC_64BIT_OFFSET, NC_64BIT_DATA}) {
    HandGrid g;
    g.format = format;
    g.z_bounds_rows = 3;
    const auto file = write_hand_grid(dir.path() / ("v" + std::to_string(format) + ".nc"), g);
    const VoxelGridFile grid(file);
    EXPECT_FALSE(grid.shape().crs_wkt.empty());
    const VoxelBlock block = grid.window(-1e9, 1e9, -1e9, 1e9);
    const VoxelBlock b = sample_block();
    ASSERT_EQ(block.pad.size(), b.pad.size()) << format;
    EXPECT_EQ(block.pad, b.pad) << format;
    EXPECT_EQ(block.z_edges_m, (std::vector<double>{0, 1, 3, 6})) << format;
  }
}

}  // namespace
}  // namespace glaswave
