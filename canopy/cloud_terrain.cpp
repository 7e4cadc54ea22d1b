// A point cloud's ground as a DEM in GDAL's memory.
#include "canopy/cloud_terrain.hpp"

#include <cpl_vsi.h>
#include <gdal_priv.h>

#include <atomic>
#include <cmath>
#include <limits>

#include "canopy/gap_fraction.hpp"
#include "canopy/las_reader.hpp"
#include "core/error.hpp"
#include "core/gdal_layer.hpp"
#include "terrain/dem_terrain.hpp"
#include "terrain/ground_mesh.hpp"

namespace glaswave {

namespace {

// Writes the grid as a one-band GeoTIFF at `path` (GDAL's memory): north-up, pixel (i, row) the
// cell centred at (x0 + (i + 1/2) s, y0 + (ny - row - 1/2) s), NaN where there is no ground.
void write_ground_raster(const CloudGround& cloud, const std::string& path,
                         const std::string& place) {
  prepare_gdal();
  const GroundGrid& g = cloud.ground;
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) throw input_error(place, "GDAL has no GTiff driver to hold the cloud's ground");
  GDALDataset* raster = driver->Create(path.c_str(), g.nx, g.ny, 1, GDT_Float32, nullptr);
  if (!raster) throw input_error(place, "cannot hold the cloud's ground in GDAL's memory");
  double transform[6] = {g.x0, g.cell_m, 0.0, g.y0 + g.ny * g.cell_m, 0.0, -g.cell_m};
  raster->SetGeoTransform(transform);
  raster->SetProjection(cloud.crs_wkt.c_str());
  GDALRasterBand* band = raster->GetRasterBand(1);
  band->SetNoDataValue(std::numeric_limits<double>::quiet_NaN());
  CPLErr status = CE_None;
  for (int row = 0; row < g.ny && status == CE_None; ++row) {
    const float* south_first = g.height_m.data() + std::size_t(g.ny - 1 - row) * g.nx;
    status = band->RasterIO(GF_Write, 0, row, g.nx, 1, const_cast<float*>(south_first), g.nx, 1,
                            GDT_Float32, 0, 0);
  }
  GDALClose(raster);
  if (status != CE_None) throw input_error(place, "cannot hold the cloud's ground in memory");
}

// `text` with GDAL's in-memory file named as what it holds: the cloud's ground.
std::string with_cloud_named(std::string text, const std::string& memory_path,
                             const std::string& cloud) {
  const std::string named = cloud + " (its ground, gridded from the class-2 points)";
  for (std::size_t at = text.find(memory_path); at != std::string::npos;
       at = text.find(memory_path, at + named.size()))
    text.replace(at, memory_path.size(), named);
  return text;
}

// `f`, its errors naming the LAS file where they named the ground's file in GDAL's memory, which
// the user never gave.
template <typename F>
auto naming_the_cloud(const std::string& memory_path, const std::string& cloud, F&& f)
    -> decltype(f()) {
  try {
    return f();
  } catch (const Error& e) {
    throw Error(e.kind(), with_cloud_named(e.place(), memory_path, cloud),
                with_cloud_named(e.message(), memory_path, cloud));
  }
}

// A DEM terrain over a file in GDAL's memory, removed with it, and the grid it was written from.
class CloudTerrain final : public Terrain {
 public:
  CloudTerrain(const TerrainSettings& settings, std::string path, std::string cloud,
               std::shared_ptr<const CloudGround> ground)
      : path_(std::move(path)),
        cloud_(std::move(cloud)),
        ground_(std::move(ground)),
        dem_(naming_the_cloud(path_, cloud_, [&] { return DemTerrain(settings); })) {}
  ~CloudTerrain() override { VSIUnlink(path_.c_str()); }
  double height_m(double lat_deg, double lon_deg) const override {
    return naming_the_cloud(path_, cloud_, [&] { return dem_.height_m(lat_deg, lon_deg); });
  }
  double detail_m() const override { return dem_.detail_m(); }
  GroundMesh mesh(const LocalFrame& frame, double half_size_m, double spacing_m) const override {
    return naming_the_cloud(path_, cloud_,
                            [&] { return dem_.mesh(frame, half_size_m, spacing_m); });
  }
  bool has_data(const LocalFrame& frame, double radius_m) const override {
    return dem_.has_data(frame, radius_m);
  }
  VerticalDatum vertical_datum() const override { return dem_.vertical_datum(); }
  const std::shared_ptr<const CloudGround>& ground() const { return ground_; }

 private:
  std::string path_;
  std::string cloud_;
  std::shared_ptr<const CloudGround> ground_;
  DemTerrain dem_;
};

}  // namespace

std::unique_ptr<Terrain> point_cloud_terrain(const TerrainSettings& terrain,
                                             const CanopySettings& canopy) {
  const LasFile cloud(canopy.point_cloud_file);
  GapFractionSettings grid;
  grid.voxel_size_m = canopy.voxel_size_m;
  auto ground = std::make_shared<const CloudGround>(
      grid_cloud_ground(cloud, canopy.point_cloud_crs, "/canopy/point_cloud/crs", grid));
  static std::atomic<unsigned> runs{0};
  const std::string path = "/vsimem/glaswave_cloud_ground_" + std::to_string(++runs) + ".tif";
  TerrainSettings dem = terrain;
  dem.dem = path;
  try {
    write_ground_raster(*ground, path, canopy.point_cloud_file);
    return std::make_unique<CloudTerrain>(dem, path, canopy.point_cloud_file, std::move(ground));
  } catch (...) {
    VSIUnlink(path.c_str());
    throw;
  }
}

std::shared_ptr<const CloudGround> cloud_ground_of(const Terrain& terrain) {
  const auto* cloud = dynamic_cast<const CloudTerrain*>(&terrain);
  return cloud ? cloud->ground() : nullptr;
}

}  // namespace glaswave
