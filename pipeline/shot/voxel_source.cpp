// Voxel grids and point clouds behind the VegetationSource interface.
#include "pipeline/shot/voxel_source.hpp"

#include <ogr_spatialref.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "canopy/gap_fraction.hpp"
#include "canopy/las_reader.hpp"
#include "core/error.hpp"
#include "core/gdal_layer.hpp"

namespace glaswave {
namespace {

// Of the two kinds, the one given a cloud's file (canopy.point_cloud.file, which configuration
// requires of it) voxelises it; the other reads a voxels file.
bool from_cloud(const CanopySettings& canopy) { return !canopy.point_cloud_file.empty(); }

}  // namespace

VoxelSource::VoxelSource(const VegetationSettings& settings)
    : canopy_(settings.canopy), leaf_angles_(canopy_.lad, canopy_.lad_mean_deg) {
  std::string place;
  if (from_cloud(canopy_)) {
    place = canopy_.point_cloud_file;
    const LasFile cloud(canopy_.point_cloud_file);
    GapFractionSettings inversion;
    inversion.voxel_size_m = canopy_.voxel_size_m;
    inversion.leaf_projection = 0.5;  // what the inversion assumes; see docs/vegetation.md
    VoxelizeResult result =
        voxelize_point_cloud(cloud, canopy_.point_cloud_crs, "/canopy/point_cloud/crs", inversion,
                             settings.cloud_ground.get());
    grid_ = std::make_unique<VoxelGridFile>(std::move(result.voxels));
  } else {
    place = canopy_.voxels_file;
    grid_ = std::make_unique<VoxelGridFile>(canopy_.voxels_file);
  }
  fields_ = std::make_unique<VoxelFieldSource>(*grid_, place);
}

VoxelSource::~VoxelSource() = default;

RegionVegetation VoxelSource::grow(const VegetationRegion& region) const {
  RegionVegetation grown;
  grown.geometry.trunks.max_height_m = -std::numeric_limits<double>::infinity();
  grown.geometry.voxels = fields_->field(region.frame, region.terrain, region.half_size_m, 0);
  // Plant-area weighted elements, as the forest's: leaves bi-Lambertian, bark opaque.
  Foliage foliage;
  const double bark = canopy_.bark_fraction, green = 1.0 - bark;
  for (std::size_t band = 0; band < region.bands; ++band) {
    foliage.reflectance.push_back(green * canopy_.leaf_reflectance[band] +
                                  bark * canopy_.bark_reflectance[band]);
    foliage.transmittance.push_back(green * canopy_.leaf_transmittance[band]);
  }
  foliage.trunk_reflectance = canopy_.bark_reflectance;
  foliage.leaf_angles = &leaf_angles_;
  foliage.leaf_size_m = canopy_.leaf_size_m;
  grown.materials.push_back(foliage);
  return grown;
}

void VoxelSource::check_region(const VegetationRegion& region) const {
  fields_->check_values(region.frame, region.half_size_m);
}

std::vector<VegetationSource::Placed> VoxelSource::placed() const {
  const VoxelBlock& g = grid_->shape();
  OGRSpatialReference crs;
  crs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::vector<Placed> points;
  {
    const GdalErrorTrap trap;
    if (crs.SetFromUserInput(g.crs_wkt.c_str(),
                             OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) !=
        OGRERR_NONE)
      return points;
    const auto to_wgs84 = transformation_to_wgs84(crs);
    if (!to_wgs84) return points;
    for (int a = 0; a <= 2; ++a)
      for (int b = 0; b <= 2; ++b) {
        double x = g.x0 + g.dx * g.nx * a / 2.0, y = g.y0 + g.dy * g.ny * b / 2.0;
        if (to_wgs84->Transform(1, &x, &y) && std::isfinite(x) && std::isfinite(y))
          points.push_back({y, x, 0.0});
      }
  }
  return points;
}

namespace {

// What a grid will be, from its file's header before the source is made: a voxels file's shape
// (its coordinates), or a cloud's extent (its z range bounds the heights above the ground) at
// the voxel size. 1 m columns of 60 layers when the file cannot be read: making the source names
// its fault.
struct GridShape {
  double cell_x_m = 1.0, cell_y_m = 1.0, layers = 60.0;
  double columns = 0.0, points = 0.0;  // the whole grid's, a cloud's
  double inversion_layers = 0.0;       // a cloud's layers while it is voxelised
  double cache_bytes = 0.0;            // a NetCDF file's decompressed chunks kept between windows

  // A column packed at most: every layer, and its index entry.
  double packed_column_bytes() const { return layers * sizeof(float) + sizeof(VoxelField::Column); }
  // The packed tiles the cache keeps over a run: the whole grid, up to the cache's bytes.
  double cached_tile_bytes() const {
    return std::min(static_cast<double>(VoxelFieldSource::max_tile_cache_bytes),
                    columns * packed_column_bytes());
  }
  bool cache_keeps_whole_grid() const {
    return columns > 0.0 &&
           columns * packed_column_bytes() <= VoxelFieldSource::max_tile_cache_bytes;
  }
};

GridShape grid_shape(const VegetationSettings& settings) {
  GridShape g;
  const CanopySettings& canopy = settings.canopy;
  try {
    if (from_cloud(canopy)) {
      const LasHeader h = LasFile(canopy.point_cloud_file).header();
      const double size_m = canopy.voxel_size_m;
      g.cell_x_m = g.cell_y_m = size_m;
      g.inversion_layers = std::ceil(GapFractionSettings{}.max_height_m / size_m);
      g.layers = std::min(g.inversion_layers, std::ceil((h.max[2] - h.min[2]) / size_m) + 1.0);
      g.columns = (std::floor((h.max[0] - h.min[0]) / size_m) + 1.0) *
                  (std::floor((h.max[1] - h.min[1]) / size_m) + 1.0);
      g.points = static_cast<double>(h.point_count);
    } else {
      const VoxelGridFile grid(canopy.voxels_file);
      const VoxelBlock& shape = grid.shape();
      g.cell_x_m = std::abs(shape.dx);
      g.cell_y_m = std::abs(shape.dy);
      g.layers = shape.nz;
      g.columns = static_cast<double>(shape.nx) * shape.ny;
      if (grid.netcdf()) g.cache_bytes = static_cast<double>(grid.read_cache_bytes());
    }
  } catch (const Error&) {
  }
  return g;
}

}  // namespace

double VoxelSource::region_bytes(const VegetationSettings& settings, double side_m) {
  const GridShape g = grid_shape(settings);
  // The window's ground under each column (a double) and its columns' index; one tile as read;
  // and, where the whole grid is more than the tile cache keeps (else source_bytes counts every
  // tile once), the packed tiles the window meets (n columns meet at most ceil((n - 1) / t) + 1
  // tiles of t), all their layers at most: a thread holds them while its shot runs, even once
  // the cache has dropped them.
  const double t = VoxelFieldSource::tile_columns;
  const double across_i = side_m / g.cell_x_m + 1.0, across_j = side_m / g.cell_y_m + 1.0;
  double bytes = across_i * across_j * (sizeof(double) + sizeof(VoxelField::Column)) +
                 t * t * g.layers * sizeof(float);
  if (!g.cache_keeps_whole_grid()) {
    const double tiles =
        (std::ceil((across_i - 1.0) / t) + 1.0) * (std::ceil((across_j - 1.0) / t) + 1.0);
    bytes += std::min(tiles * t * t, g.columns > 0.0 ? g.columns : tiles * t * t) *
             g.packed_column_bytes();
  }
  return bytes;
}

double VoxelSource::source_bytes(const VegetationSettings& settings) {
  const GridShape g = grid_shape(settings);
  const double tiles = g.cached_tile_bytes();
  if (!from_cloud(settings.canopy)) return g.cache_bytes + tiles;
  // Reading: the ground points (three doubles each, at most every point) and a window of a
  // million points. Inverting: each voxel's weight (a double) and density (a float) at once.
  const double reading = g.points * 3.0 * sizeof(double) + (1 << 20) * sizeof(LasPoint);
  const double inverting = g.columns * ((g.inversion_layers + 1.0) * sizeof(double) +
                                        g.inversion_layers * sizeof(float) + 3.0 * sizeof(double));
  return std::max(reading, inverting) + tiles;
}

namespace {
// A voxel file and a point cloud voxelised when the run starts: one source, two kinds, each read
// from an object of measured vegetation's keys; the cloud's ground points may be the terrain.
VegetationKind voxel_kind(std::string memory_key) {
  return {[](const VegetationSettings& s) { return std::make_unique<VoxelSource>(s); },
          &VoxelSource::region_bytes, &VoxelSource::source_bytes, std::move(memory_key)};
}
const VegetationRegistration voxels("voxels", 1,
                                    {"a voxel grid of plant area density",
                                     {.keys = VegetationTraits::Keys::measured}},
                                    voxel_kind("/canopy/voxels/file"));
const VegetationRegistration point_cloud("point_cloud", 2,
                                         {"an airborne lidar point cloud",
                                          {.keys = VegetationTraits::Keys::measured,
                                           .ground_points = true}},
                                         voxel_kind("/canopy/point_cloud/voxel_size_m"));
}  // namespace

}  // namespace glaswave
