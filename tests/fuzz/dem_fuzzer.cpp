// Fuzzes the DEM reader (terrain/dem_terrain): bytes -> a GeoTIFF in /vsimem/ -> DemTerrain,
// then heights, has_data and a mesh about points on the raster. An input that starts as a TIFF
// does ("II*\0", "MM\0*") is the file itself, byte for byte (corrupt and truncated files); any
// other input describes a raster that the target writes with GDAL (size, data type, bands,
// geotransform, CRS, nodata, scale, unit, pixels), which reaches the reader's checks far more
// often than mutated TIFF bytes do. An input that starts "<VRTDataset" is a VRT, written as a
// file beside a GeoTIFF (dem.tif), a FIFO nobody writes (fifo) and a VRT whose source is that
// FIFO (inner.vrt), which its sources may name: the regular-file rule (terrain/gdal_source) must
// refuse every source that is no regular file before GDAL opens it, or the target hangs (issue
// 28). GDAL keeps only its GTiff and VRT drivers. An Error is a refusal; anything else is a
// finding.
#include <cpl_vsi.h>
#include <fuzzer/FuzzedDataProvider.h>
#include <gdal.h>
#include <ogr_srs_api.h>
#include <sys/stat.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "terrain/dem_terrain.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/local_frame.hpp"
#include "tests/fuzz/fuzz_support.hpp"

namespace {

constexpr const char* dem_path = "/vsimem/fuzz_dem.tif";

bool is_tiff(const std::uint8_t* data, std::size_t size) {
  return size >= 4 && (std::memcmp(data, "II*\0", 4) == 0 || std::memcmp(data, "MM\0*", 4) == 0);
}

// Writes the raster the input describes; false when GDAL refuses to make it.
bool write_described_raster(FuzzedDataProvider& in) {
  const int width = in.ConsumeIntegralInRange(1, 40);
  const int height = in.ConsumeIntegralInRange(1, 40);
  const int bands = in.ConsumeIntegralInRange(1, 2);
  const GDALDataType type =
      in.PickValueInArray({GDT_Byte, GDT_Int16, GDT_UInt16, GDT_Int32, GDT_Float32, GDT_Float64});
  GDALDatasetH dataset =
      GDALCreate(GDALGetDriverByName("GTiff"), dem_path, width, height, bands, type, nullptr);
  if (!dataset) return false;
  if (in.ConsumeBool()) {
    std::array<double, 6> transform{};
    if (in.ConsumeBool()) {  // a plausible one: degrees or metres, north up or rotated
      transform = {in.ConsumeFloatingPointInRange(-200.0, 200.0),
                   in.ConsumeFloatingPointInRange(-1.0, 1.0),
                   in.ConsumeBool() ? 0.0 : in.ConsumeFloatingPointInRange(-0.1, 0.1),
                   in.ConsumeFloatingPointInRange(-100.0, 100.0),
                   in.ConsumeBool() ? 0.0 : in.ConsumeFloatingPointInRange(-0.1, 0.1),
                   in.ConsumeFloatingPointInRange(-1.0, 1.0)};
      if (in.ConsumeBool())
        for (double& t : transform) t *= 1e5;
    } else {
      for (double& t : transform) t = in.ConsumeFloatingPoint<double>();
    }
    GDALSetGeoTransform(dataset, transform.data());
  }
  const std::string crs = in.PickValueInArray<std::string>(
      {"", "EPSG:4326", "EPSG:32633", "EPSG:3857", "EPSG:4979", "EPSG:4326+5773", "EPSG:2193",
       "EPSG:32633+3855", "+proj=longlat +a=1 +b=1", "+proj=ortho +lat_0=90", "EPSG:4269",
       "EPSG:2056"});
  if (!crs.empty()) {
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    if (OSRSetFromUserInput(srs, crs.c_str()) == OGRERR_NONE) GDALSetSpatialRef(dataset, srs);
    OSRDestroySpatialReference(srs);
  }
  for (int b = 1; b <= bands; ++b) {
    GDALRasterBandH band = GDALGetRasterBand(dataset, b);
    if (in.ConsumeBool()) GDALSetRasterNoDataValue(band, in.ConsumeFloatingPoint<double>());
    if (in.ConsumeBool()) {
      GDALSetRasterScale(band, in.ConsumeFloatingPoint<double>());
      GDALSetRasterOffset(band, in.ConsumeFloatingPoint<double>());
    }
    GDALSetRasterUnitType(band, in.PickValueInArray({"", "m", "ft", "US survey foot", "km"}));
    std::vector<double> pixels(static_cast<std::size_t>(width) * height);
    for (double& p : pixels)
      p = in.ConsumeBool() ? in.ConsumeFloatingPointInRange(-500.0, 9000.0)
                           : in.ConsumeFloatingPoint<double>();
    if (GDALRasterIO(band, GF_Write, 0, 0, width, height, pixels.data(), width, height, GDT_Float64,
                     0, 0) != CE_None) {
      GDALClose(dataset);
      return false;
    }
  }
  GDALClose(dataset);
  return true;
}

// Latitude and longitude of the raster's pixel (u, v), through its own georeferencing; false
// when there is none or PROJ cannot say.
bool geodetic_of_pixel(double u, double v, double& lat_deg, double& lon_deg) {
  GDALDatasetH dataset = GDALOpen(dem_path, GA_ReadOnly);
  if (!dataset) return false;
  std::array<double, 6> t{};
  bool found = false;
  OGRSpatialReferenceH from = GDALGetSpatialRef(dataset);
  if (GDALGetGeoTransform(dataset, t.data()) == CE_None && from) {
    double x = t[0] + u * t[1] + v * t[2], y = t[3] + u * t[4] + v * t[5], z = 0.0;
    OGRSpatialReferenceH to = OSRNewSpatialReference(nullptr);
    OSRImportFromEPSG(to, 4326);
    OSRSetAxisMappingStrategy(to, OAMS_TRADITIONAL_GIS_ORDER);
    OGRCoordinateTransformationH transform = OCTNewCoordinateTransformation(from, to);
    if (transform && OCTTransform(transform, 1, &x, &y, &z)) {
      lon_deg = x;
      lat_deg = y;
      found = true;
    }
    if (transform) OCTDestroyCoordinateTransformation(transform);
    OSRDestroySpatialReference(to);
  }
  GDALClose(dataset);
  return found;
}

bool is_vrt(const std::uint8_t* data, std::size_t size) {
  constexpr std::string_view start = "<VRTDataset";
  return size >= start.size() && std::memcmp(data, start.data(), start.size()) == 0;
}

// What a fuzzed VRT's sources may name, beside it in the scratch folder: a GeoTIFF, a FIFO, and
// a VRT whose source is the FIFO.
void write_vrt_neighbours() {
  namespace fs = std::filesystem;
  const fs::path dir = glaswave::fuzz::scratch_dir();
  GDALDatasetH dataset = GDALCreate(GDALGetDriverByName("GTiff"), (dir / "dem.tif").c_str(), 4, 4,
                                    1, GDT_Float32, nullptr);
  std::array<double, 6> transform = {7.0, 0.001, 0.0, 45.0, 0.0, -0.001};
  GDALSetGeoTransform(dataset, transform.data());
  OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
  OSRSetFromUserInput(srs, "EPSG:4326");
  GDALSetSpatialRef(dataset, srs);
  OSRDestroySpatialReference(srs);
  GDALClose(dataset);
  ::mkfifo((dir / "fifo").c_str(), 0600);
  std::ofstream(dir / "inner.vrt")
      << "<VRTDataset rasterXSize=\"4\" rasterYSize=\"4\"><SRS>EPSG:4326</SRS>"
         "<GeoTransform>7, 0.001, 0, 45, 0, -0.001</GeoTransform>"
         "<VRTRasterBand dataType=\"Float32\" band=\"1\"><SimpleSource>"
         "<SourceFilename relativeToVRT=\"1\">fifo</SourceFilename><SourceBand>1</SourceBand>"
         "</SimpleSource></VRTRasterBand></VRTDataset>";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  glaswave::fuzz::keep_only_gdal_drivers({"GTiff", "VRT"});
  CPLPushErrorHandler(CPLQuietErrorHandler);  // the fuzzer's own GDAL calls stay quiet
  write_vrt_neighbours();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  FuzzedDataProvider in(data, size);
  TerrainSettings settings;
  settings.dem = dem_path;
  if (is_vrt(data, size)) {
    // A file of its own, so that the rule sees it and its relative sources as GDAL would.
    settings.dem = fuzz::write_input("input.vrt", data, size).string();
  } else if (is_tiff(data, size)) {
    VSILFILE* file = VSIFileFromMemBuffer(dem_path, const_cast<GByte*>(data), size, FALSE);
    if (!file) return 0;
    VSIFCloseL(file);
  } else {
    settings.dem_band = in.ConsumeIntegralInRange(0, 3);
    settings.vertical_datum = in.PickValueInArray<std::string>(
        {"ellipsoid", "egm96", "EPSG:3855", "EPSG:5773", "EPSG:4326", "bogus"});
    if (!write_described_raster(in)) {
      VSIUnlink(dem_path);
      return 0;
    }
  }
  try {
    const DemTerrain dem(settings, DemTerrain::Options{std::size_t{1} << 20, 16});
    dem.detail_m();
    for (const auto& [u, v] : {std::array<double, 2>{0.0, 0.0}, {0.5, 0.5}, {3.3, 7.7}}) {
      double lat_deg = 0.0, lon_deg = 0.0;
      if (!geodetic_of_pixel(u, v, lat_deg, lon_deg)) continue;
      const double h_m = dem.height_m(lat_deg, lon_deg);
      if (!(lat_deg >= -90.0 && lat_deg <= 90.0) || !std::isfinite(lon_deg)) continue;
      const LocalFrame frame(Geodetic{lat_deg, lon_deg, std::isfinite(h_m) ? h_m : 0.0});
      dem.has_data(frame, 30.0);
      dem.mesh(frame, 60.0, 1.0);
    }
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  if (!is_vrt(data, size)) VSIUnlink(dem_path);
  return 0;
}
