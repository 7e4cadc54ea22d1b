// Rasters the tests write themselves with GDAL (never downloaded): a GeoTIFF of any CRS, size,
// band count and type, its values from a function of the pixel; planes in UTM and geographic
// coordinates; EGM96 geoid heights read by hand from PROJ's grid.
#pragma once

#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>

#include <GeographicLib/UTMUPS.hpp>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "terrain/terrain.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave::testing {

struct RasterSpec {
  std::string crs;  // "EPSG:32611", "EPSG:4326+5773"; empty: none
  std::array<double, 6> geotransform{};
  int width = 0, height = 0, bands = 1;
  GDALDataType type = GDT_Float32;
  std::optional<double> nodata;
};

// Writes a GeoTIFF; `value(col, row, band)` gives each pixel (band from 1).
inline void write_raster(const std::filesystem::path& file, const RasterSpec& spec,
                         const std::function<double(int, int, int)>& value) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  ASSERT_NE(driver, nullptr);
  GDALDataset* dataset =
      driver->Create(file.c_str(), spec.width, spec.height, spec.bands, spec.type, nullptr);
  ASSERT_NE(dataset, nullptr) << file;
  dataset->SetGeoTransform(const_cast<double*>(spec.geotransform.data()));
  if (!spec.crs.empty()) {
    OGRSpatialReference srs;
    ASSERT_EQ(srs.SetFromUserInput(spec.crs.c_str()), OGRERR_NONE) << spec.crs;
    dataset->SetSpatialRef(&srs);
  }
  std::vector<double> row(spec.width);
  for (int band = 1; band <= spec.bands; ++band) {
    GDALRasterBand* b = dataset->GetRasterBand(band);
    if (spec.nodata) b->SetNoDataValue(*spec.nodata);
    for (int r = 0; r < spec.height; ++r) {
      for (int c = 0; c < spec.width; ++c) row[c] = value(c, r, band);
      ASSERT_EQ(
          b->RasterIO(GF_Write, 0, r, spec.width, 1, row.data(), spec.width, 1, GDT_Float64, 0, 0),
          CE_None);
    }
  }
  GDALClose(dataset);
}

// The geodetic position of a pixel centre of a UTM raster (northern zone).
inline std::array<double, 2> utm_pixel_lat_lon(const RasterSpec& spec, int zone, int col, int row) {
  const auto& g = spec.geotransform;
  const double x = g[0] + (col + 0.5) * g[1] + (row + 0.5) * g[2];
  const double y = g[3] + (col + 0.5) * g[4] + (row + 0.5) * g[5];
  double lat = 0, lon = 0;
  GeographicLib::UTMUPS::Reverse(zone, true, x, y, lat, lon);
  return {lat, lon};
}

// A raster of `terrain` (heights above the ellipsoid) in UTM zone `zone` north, `cell_m` cells,
// covering +-half_m about a point.
inline RasterSpec utm_raster_of(const Terrain& terrain, const std::filesystem::path& file,
                                double lat_deg, double lon_deg, int zone, double half_m,
                                double cell_m) {
  int z = 0;
  bool north = true;
  double x = 0, y = 0;
  GeographicLib::UTMUPS::Forward(lat_deg, lon_deg, z, north, x, y, zone);
  RasterSpec spec;
  spec.crs = "EPSG:" + std::to_string(32600 + zone);
  const int cells = static_cast<int>(std::ceil(2.0 * half_m / cell_m));
  spec.width = spec.height = cells;
  spec.geotransform = {std::floor(x - half_m), cell_m, 0.0, std::floor(y + half_m), 0.0, -cell_m};
  write_raster(file, spec, [&](int c, int r, int) {
    const auto p = utm_pixel_lat_lon(spec, zone, c, r);
    return terrain.height_m(p[0], p[1]);
  });
  return spec;
}

// A raster of `terrain` in geographic coordinates (EPSG:4326), `cell_deg` cells.
inline RasterSpec geographic_raster_of(const Terrain& terrain, const std::filesystem::path& file,
                                       double lat_deg, double lon_deg, double half_deg,
                                       double cell_deg, const std::string& crs = "EPSG:4326") {
  RasterSpec spec;
  spec.crs = crs;
  const int cells = static_cast<int>(std::ceil(2.0 * half_deg / cell_deg));
  spec.width = spec.height = cells;
  spec.geotransform = {lon_deg - half_deg, cell_deg, 0.0, lat_deg + half_deg, 0.0, -cell_deg};
  write_raster(file, spec, [&](int c, int r, int) {
    const double lon = spec.geotransform[0] + (c + 0.5) * cell_deg,
                 lat = spec.geotransform[3] - (r + 0.5) * cell_deg;
    return terrain.height_m(lat, lon);
  });
  return spec;
}

// EGM96 geoid undulation N (m; ellipsoidal height = orthometric height + N), read by hand from
// PROJ's egm96_15.gtx (NOAA's GTX: a big-endian header of south latitude, west longitude and the
// two spacings in degrees, rows and columns, then float32 rows from the south) and interpolated
// bilinearly, independently of PROJ.
class Egm96Grid {
 public:
  static constexpr const char* file = "/usr/share/proj/egm96_15.gtx";

  bool load() {
    std::ifstream in(file, std::ios::binary);
    if (!in) return false;
    auto read_double = [&] {
      std::uint64_t bits = 0;
      unsigned char bytes[8];
      in.read(reinterpret_cast<char*>(bytes), 8);
      for (unsigned char byte : bytes) bits = (bits << 8) | byte;
      return std::bit_cast<double>(bits);
    };
    auto read_int = [&] {
      std::uint32_t bits = 0;
      unsigned char bytes[4];
      in.read(reinterpret_cast<char*>(bytes), 4);
      for (unsigned char byte : bytes) bits = (bits << 8) | byte;
      return static_cast<std::int32_t>(bits);
    };
    south_deg_ = read_double();
    west_deg_ = read_double();
    step_lat_deg_ = read_double();
    step_lon_deg_ = read_double();
    rows_ = read_int();
    cols_ = read_int();
    values_.resize(static_cast<std::size_t>(rows_) * cols_);
    for (float& v : values_) {
      std::uint32_t bits = 0;
      unsigned char bytes[4];
      in.read(reinterpret_cast<char*>(bytes), 4);
      for (unsigned char byte : bytes) bits = (bits << 8) | byte;
      v = std::bit_cast<float>(bits);
    }
    return static_cast<bool>(in);
  }

  double undulation_m(double lat_deg, double lon_deg) const {
    const double y = (lat_deg - south_deg_) / step_lat_deg_;
    double x = std::fmod(lon_deg - west_deg_, 360.0);
    if (x < 0) x += 360.0;
    x /= step_lon_deg_;
    // The columns go once round the Earth: the one east of the last is the first.
    const int i = static_cast<int>(x) % cols_, east = (i + 1) % cols_;
    const int j = std::min(static_cast<int>(y), rows_ - 2);
    const double fx = x - std::floor(x), fy = y - j;
    auto at = [&](int col, int row) {
      return static_cast<double>(values_[static_cast<std::size_t>(row) * cols_ + col]);
    };
    return (1 - fx) * (1 - fy) * at(i, j) + fx * (1 - fy) * at(east, j) +
           (1 - fx) * fy * at(i, j + 1) + fx * fy * at(east, j + 1);
  }

 private:
  double south_deg_ = 0, west_deg_ = 0, step_lat_deg_ = 1, step_lon_deg_ = 1;
  int rows_ = 0, cols_ = 0;
  std::vector<float> values_;
};

// A fresh folder under the system's temporary directory for one test, removed at its end.
using TempFolder = test_support::ScratchDir;

}  // namespace glaswave::testing
