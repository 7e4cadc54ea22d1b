// DEM terrain: GDAL behind a small RAII layer whose errors become input errors, a tile cache,
// and meshes on the DEM's own nodes.
#include "terrain/dem_terrain.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <future>
#include <initializer_list>
#include <limits>
#include <list>
#include <mutex>
#include <numbers>
#include <optional>
#include <unordered_map>
#include <vector>

#include "core/error.hpp"
#include "core/gdal_layer.hpp"
#include "core/length_units.hpp"
#include "core/netcdf_lock.hpp"
#include "terrain/crs_transform.hpp"
#include "terrain/gdal_source.hpp"
#include "terrain/ground_mesh.hpp"

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// A number for a message, as %g writes it.
std::string format_value(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}
// Beyond this many nodes a side a mesh takes every k-th node (memory), and no longer matches
// height_m exactly; a shot's patch is a few hundred nodes of a 1 m DEM.
constexpr int max_mesh_nodes_per_side = 2048;

// Beyond these a DEM's scale (metres per stored unit, after its unit) or offset gives no height on
// the Earth: refused as such, before PROJ is handed infinities.
constexpr double max_scale_m = 1e4;
constexpr double max_offset_m = 1e5;
constexpr double max_height_m = 1e5;  // a height (after scale and offset) beyond: no terrain
// Nodes closer than this are a geotransform's fault (a pixel of 1e-300 degrees), no DEM's.
constexpr double min_spacing_m = 1e-3;

// One tile of the raster's nodes, in WGS84: longitude, latitude (deg) and ellipsoidal height
// (m; NaN where there is no data).
struct Tile {
  int col0 = 0, row0 = 0, cols = 0, rows = 0;
  std::vector<double> lon_deg, lat_deg, h_m;
};
using TilePtr = std::shared_ptr<const Tile>;

struct Node {
  double lon_deg, lat_deg, h_m;
  bool valid() const { return std::isfinite(h_m); }
};

}  // namespace

struct DemTerrain::Impl {
  std::string path;
  Options options;
  GdalDataset dataset;
  GDALRasterBand* band = nullptr;
  int width = 0, height = 0;
  std::array<double, 6> geotransform{}, inverse{};
  std::optional<double> nodata;
  bool use_mask = false;
  double scale = 1.0, offset = 0.0;
  std::unique_ptr<CrsTransform> crs;
  double detail_m = 1.0;  // node spacing (m) about the raster's centre, the finer way
  double cell_m = 1.0;    // the coarser way

  std::mutex io_mutex;  // GDAL dataset handles are not thread-safe
  int tiles_x = 0, tiles_y = 0;

  struct Entry {
    std::shared_future<TilePtr> tile;
    std::list<std::int64_t>::iterator recent;
    std::size_t bytes;
  };
  mutable std::mutex cache_mutex;
  std::list<std::int64_t> recent;  // most recently used first
  std::unordered_map<std::int64_t, Entry> cache;
  std::size_t cached_bytes = 0;
  std::size_t tiles_read = 0;

  void open(const TerrainSettings& settings);
  void open_dataset();
  void choose_band(int dem_band);
  void read_georeferencing(const std::string& vertical_datum, bool vertical_datum_given);
  void require_readable_corners();
  void read_encoding();
  void measure_spacing();
  TilePtr load(int tx, int ty);
  TilePtr tile(int tx, int ty);
  Node node(int i, int j) {
    const TilePtr t = tile(i / options.tile_pixels, j / options.tile_pixels);
    const std::size_t k = static_cast<std::size_t>(j - t->row0) * t->cols + (i - t->col0);
    return {t->lon_deg[k], t->lat_deg[k], t->h_m[k]};
  }
  // Fractional node coordinates (u along columns, v along rows; node (i, j) at (i, j)) of a
  // geodetic position, NaN where PROJ cannot say. A geographic raster is tried a turn of
  // longitude either way when the position falls off it.
  std::array<double, 2> node_coordinates(double lat_deg, double lon_deg) const;
  bool inside(const std::array<double, 2>& uv) const {
    return uv[0] >= 0.0 && uv[0] <= width - 1 && uv[1] >= 0.0 && uv[1] <= height - 1;
  }
  // The nodes (clamped to the raster) around positions sampled on a shape about the frame's
  // origin; `inside_all` tells whether every sample fell on the raster.
  struct Window {
    int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
    bool inside_all = true;
    bool empty() const { return i1 < i0 || j1 < j0; }
  };
  Window window(const LocalFrame& frame, const std::vector<std::array<double, 2>>& samples_m) const;

  // A block of nodes gathered once, tile by tile, so that a mesh reads them without locking.
  class NodeBlock {
   public:
    NodeBlock(Impl& dem, int i0, int i1, int j0, int j1) : dem_(dem) {
      const int t = dem.options.tile_pixels;
      tx0_ = i0 / t;
      ty0_ = j0 / t;
      nx_ = i1 / t - tx0_ + 1;
      const int ny = j1 / t - ty0_ + 1;
      for (int ty = 0; ty < ny; ++ty)
        for (int tx = 0; tx < nx_; ++tx) tiles_.push_back(dem.tile(tx0_ + tx, ty0_ + ty));
    }
    Node operator()(int i, int j) const {
      const int t = dem_.options.tile_pixels;
      const Tile& tile = *tiles_[static_cast<std::size_t>(j / t - ty0_) * nx_ + (i / t - tx0_)];
      const std::size_t k = static_cast<std::size_t>(j - tile.row0) * tile.cols + (i - tile.col0);
      return {tile.lon_deg[k], tile.lat_deg[k], tile.h_m[k]};
    }

   private:
    Impl& dem_;
    int tx0_ = 0, ty0_ = 0, nx_ = 0;
    std::vector<TilePtr> tiles_;
  };
};

void DemTerrain::Impl::open(const TerrainSettings& settings) {
  prepare_gdal();
  const GdalErrorTrap quiet;  // GDAL's warnings about the file stay off the terminal too
  open_dataset();
  choose_band(settings.dem_band);
  read_georeferencing(settings.vertical_datum, settings.vertical_datum_given);
  read_encoding();
  tiles_x = (width + options.tile_pixels - 1) / options.tile_pixels;
  tiles_y = (height + options.tile_pixels - 1) / options.tile_pixels;

  // A truncated or corrupt file often opens: read the tiles at its start, middle and end now,
  // so that it fails here and not halfway through a run.
  for (const auto& [tx, ty] :
       {std::array<int, 2>{0, 0}, {tiles_x / 2, tiles_y / 2}, {tiles_x - 1, tiles_y - 1}})
    tile(tx, ty);

  measure_spacing();
}

void DemTerrain::Impl::open_dataset() {
  // A FIFO, a device, /vsistdin/ or a VRT naming one would be waited on or read for ever.
  require_gdal_source(path, "the DEM");
  {
    const GdalErrorTrap trap;
    const std::lock_guard lock(netcdf_library_mutex());  // a netCDF DEM opens libnetcdf
    dataset.reset(GDALDataset::Open(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    if (!dataset)
      throw input_error(
          path, "cannot read the DEM: " + trap.cause("GDAL does not recognise it as a raster"));
  }
}

// The band with the heights: the one there is, or terrain.dem_band's.
void DemTerrain::Impl::choose_band(int dem_band) {
  const int bands = dataset->GetRasterCount();
  if (bands < 1) throw input_error(path, "the DEM has no raster band");
  if (dem_band == 0 && bands > 1) {
    throw input_error(path, "the DEM has " + std::to_string(bands) +
                                " bands: choose the one with heights with terrain.dem_band (1 to " +
                                std::to_string(bands) + ")");
  }
  const int band_number = dem_band == 0 ? 1 : dem_band;
  if (band_number > bands) {
    throw input_error(path, "the DEM has " + std::to_string(bands) + " band" +
                                (bands > 1 ? "s" : "") + ", terrain.dem_band asks for band " +
                                std::to_string(band_number));
  }
  band = dataset->GetRasterBand(band_number);
  // Colour indices and complex numbers are no heights, whatever the numbers they hold.
  const std::string which = "band " + std::to_string(band_number) + " of the DEM";
  if (band->GetColorInterpretation() == GCI_PaletteIndex || band->GetColorTable() != nullptr)
    throw input_error(path, which + " is paletted (colour indices, not heights)" +
                                (bands > 1 ? ": choose another with terrain.dem_band" : ""));
  if (GDALDataTypeIsComplex(band->GetRasterDataType()))
    throw input_error(path, which + " holds complex numbers (" +
                                GDALGetDataTypeName(band->GetRasterDataType()) + "), not heights");
  width = dataset->GetRasterXSize();
  height = dataset->GetRasterYSize();
  if (width < 2 || height < 2)
    throw input_error(path, "the DEM is too small: at least 2 x 2 cells are needed");
}

// Where the raster lies: its CRS and geotransform, and the transform of its nodes to WGS84.
void DemTerrain::Impl::read_georeferencing(const std::string& vertical_datum,
                                           bool vertical_datum_given) {
  const OGRSpatialReference* srs = dataset->GetSpatialRef();
  if (!srs || srs->IsEmpty()) {
    // A file cut short loses the CRS it held past the cut (a BigTIFF's GeoKeys): if its data
    // cannot be read either, that is what to say.
    require_readable_corners();
    throw input_error(path,
                      "the DEM has no coordinate reference system, so where it lies is unknown "
                      "(assign one with gdal_edit.py -a_srs)");
  }
  {
    const GdalErrorTrap trap;
    if (dataset->GetGeoTransform(geotransform.data()) != CE_None)
      throw input_error(
          path,
          "the DEM has no geotransform (georeferenced by control points? warp it with gdalwarp)");
    if (!GDALInvGeoTransform(geotransform.data(), inverse.data()))
      throw input_error(path, "the DEM's geotransform cannot be inverted");
  }
  char* wkt = nullptr;
  const char* const wkt_options[] = {"FORMAT=WKT2_2019", nullptr};
  {
    const GdalErrorTrap trap;
    if (srs->exportToWkt(&wkt, wkt_options) != OGRERR_NONE || !wkt) {
      CPLFree(wkt);
      throw input_error(path,
                        "cannot write the DEM's CRS as WKT: " + trap.cause("GDAL gave no reason"));
    }
  }
  const std::string crs_wkt = wkt;
  CPLFree(wkt);
  crs = std::make_unique<CrsTransform>(crs_wkt, vertical_datum, path, vertical_datum_given);
}

// Throws an input error naming the file truncated or corrupt unless the raster's first and last
// pixels can be read.
void DemTerrain::Impl::require_readable_corners() {
  const GdalErrorTrap trap;
  const std::lock_guard lock(netcdf_library_mutex());
  double value = 0.0;
  for (const auto& [x, y] : {std::array<int, 2>{0, 0}, {width - 1, height - 1}})
    if (band->RasterIO(GF_Read, x, y, 1, 1, &value, 1, 1, GDT_Float64, 0, 0, nullptr) != CE_None)
      throw input_error(path, "the DEM is truncated or corrupt: its data cannot be read (" +
                                  trap.cause("GDAL gave no reason") + ")");
}

// How heights are stored: nodata value or mask, scale and offset, and their unit.
void DemTerrain::Impl::read_encoding() {
  int has_nodata = 0;
  const double nodata_value = band->GetNoDataValue(&has_nodata);
  if (has_nodata) nodata = nodata_value;
  const int mask_flags = band->GetMaskFlags();
  use_mask = !(mask_flags & GMF_ALL_VALID) && !(mask_flags & GMF_NODATA);
  int has_scale = 0, has_offset = 0;
  scale = band->GetScale(&has_scale);
  offset = band->GetOffset(&has_offset);
  if (!has_scale) scale = 1.0;
  if (!has_offset) offset = 0.0;
  // A vertical CRS carries the unit of its heights; without one, the band's unit says.
  if (!dataset->GetSpatialRef()->IsCompound()) {
    const char* unit = band->GetUnitType();
    const std::optional<double> metres = metres_per_unit(unit ? unit : "");
    if (!metres)
      throw input_error(path, "the DEM's heights are in \"" + std::string(unit).substr(0, 40) +
                                  "\", a unit glaswave does not know (it converts m, dm, cm, mm, "
                                  "km, ft and US survey ft); set the band's unit with "
                                  "gdal_edit.py -units");
    scale *= *metres;
    offset *= *metres;
  }
  if (!std::isfinite(scale) || scale == 0.0 || std::abs(scale) > max_scale_m)
    throw input_error(path, "the DEM's scale gives " + format_value(scale) +
                                " m per stored unit, outside (0, " + format_value(max_scale_m) +
                                "] m: no height on the Earth");
  if (!std::isfinite(offset) || std::abs(offset) > max_offset_m)
    throw input_error(path, "the DEM's offset is " + format_value(offset) + " m, beyond +-" +
                                format_value(max_offset_m) + " m: no height on the Earth");
}

void DemTerrain::Impl::measure_spacing() {
  // The node spacing in metres about the raster's centre.
  const int ci = width / 2 - 1, cj = height / 2 - 1;
  const Node centre = node(ci, cj), east = node(ci + 1, cj), south = node(ci, cj + 1);
  const LocalFrame frame({centre.lat_deg, centre.lon_deg, 0.0});
  const Vec3 e = frame.to_local({east.lat_deg, east.lon_deg, 0.0});
  const Vec3 s = frame.to_local({south.lat_deg, south.lon_deg, 0.0});
  detail_m = std::min(std::hypot(e[0], e[1]), std::hypot(s[0], s[1]));
  cell_m = std::max(std::hypot(e[0], e[1]), std::hypot(s[0], s[1]));
  const bool placed = std::isfinite(centre.lat_deg) && std::isfinite(centre.lon_deg) &&
                      std::isfinite(east.lat_deg) && std::isfinite(east.lon_deg) &&
                      std::isfinite(south.lat_deg) && std::isfinite(south.lon_deg);
  if (!placed || !std::isfinite(detail_m))
    throw input_error(path, "PROJ cannot place the DEM's nodes on the Earth (is its CRS right?)");
  // Placed, but (nearly) on one another: the geotransform's pixel size is the fault, not PROJ.
  if (detail_m < min_spacing_m)
    throw input_error(path, "the DEM's nodes are " + format_value(detail_m) +
                                " m apart (its geotransform's pixel is " +
                                format_value(geotransform[1]) + " by " +
                                format_value(std::abs(geotransform[5])) +
                                " in its CRS's units), under the " + format_value(min_spacing_m) +
                                " m a DEM may have: is its geotransform right?");
}

TilePtr DemTerrain::Impl::load(int tx, int ty) {
  auto t = std::make_shared<Tile>();
  t->col0 = tx * options.tile_pixels;
  t->row0 = ty * options.tile_pixels;
  t->cols = std::min(options.tile_pixels, width - t->col0);
  t->rows = std::min(options.tile_pixels, height - t->row0);
  const std::size_t n = static_cast<std::size_t>(t->cols) * t->rows;
  std::vector<double> values(n);
  std::vector<GByte> mask;
  {
    const std::scoped_lock lock(io_mutex, netcdf_library_mutex());
    const GdalErrorTrap trap;
    const auto read = [&](GDALRasterBand* from, void* into, GDALDataType type) {
      if (from->RasterIO(GF_Read, t->col0, t->row0, t->cols, t->rows, into, t->cols, t->rows, type,
                         0, 0, nullptr) != CE_None)
        throw input_error(path, "cannot read the DEM's data (truncated or corrupt?): " +
                                    trap.cause("GDAL gave no reason"));
    };
    read(band, values.data(), GDT_Float64);
    if (use_mask) {
      mask.resize(n);
      read(band->GetMaskBand(), mask.data(), GDT_Byte);
    }
    ++tiles_read;
  }
  t->lon_deg.resize(n);
  t->lat_deg.resize(n);
  t->h_m.resize(n);
  std::vector<bool> valid(n);
  const auto& g = geotransform;
  for (int r = 0; r < t->rows; ++r) {
    for (int c = 0; c < t->cols; ++c) {
      const std::size_t k = static_cast<std::size_t>(r) * t->cols + c;
      const double v = values[k];
      bool ok = std::isfinite(v) && (mask.empty() || mask[k] != 0);
      // Float rasters store nodata in single precision: compare as the file does.
      if (ok && nodata)
        ok = !(v == *nodata || static_cast<float>(v) == static_cast<float>(*nodata));
      valid[k] = ok;
      const double col = t->col0 + c + 0.5, row = t->row0 + r + 0.5;  // pixel centres
      t->lon_deg[k] = g[0] + col * g[1] + row * g[2];
      t->lat_deg[k] = g[3] + col * g[4] + row * g[5];
      t->h_m[k] = ok ? v * scale + offset : 0.0;
      // Heights of 1e38 m (a fill value not declared as nodata) ended in "the track never meets
      // the terrain", or in Embree: what no terrain holds is named at its pixel.
      if (ok && !(std::abs(t->h_m[k]) <= max_height_m))
        throw input_error(path, "the height at pixel (" + std::to_string(t->col0 + c) + ", " +
                                    std::to_string(t->row0 + r) + ") is " +
                                    format_value(t->h_m[k]) + " m, beyond +-" +
                                    format_value(max_height_m) +
                                    " m: no height on the Earth (a fill value the DEM does not "
                                    "declare as nodata? set it with gdal_edit.py -a_nodata)");
    }
  }
  crs->to_wgs84(n, t->lon_deg.data(), t->lat_deg.data(), t->h_m.data());
  for (std::size_t k = 0; k < n; ++k)
    if (!valid[k]) t->h_m[k] = nan;
  return t;
}

TilePtr DemTerrain::Impl::tile(int tx, int ty) {
  const std::int64_t key = static_cast<std::int64_t>(ty) * tiles_x + tx;
  std::promise<TilePtr> promise;
  std::shared_future<TilePtr> future;
  bool read_here = false;
  {
    const std::lock_guard lock(cache_mutex);
    const auto found = cache.find(key);
    if (found != cache.end()) {
      recent.splice(recent.begin(), recent, found->second.recent);
      future = found->second.tile;
    } else {
      // Claim the tile, then read it outside the lock: threads asking for it wait on the
      // future, threads asking for other tiles go on.
      future = promise.get_future().share();
      read_here = true;
      recent.push_front(key);
      const int cols = std::min(options.tile_pixels, width - tx * options.tile_pixels);
      const int rows = std::min(options.tile_pixels, height - ty * options.tile_pixels);
      const std::size_t bytes =
          sizeof(Tile) + 3 * sizeof(double) * static_cast<std::size_t>(cols) * rows;
      cache.emplace(key, Entry{future, recent.begin(), bytes});
      cached_bytes += bytes;
      // The least recently used go; tiles still in use elsewhere live on in their users' hands.
      while (cached_bytes > options.cache_bytes && recent.size() > 1) {
        const auto last = cache.find(recent.back());
        cached_bytes -= last->second.bytes;
        cache.erase(last);
        recent.pop_back();
      }
    }
  }
  if (read_here) {
    try {
      promise.set_value(load(tx, ty));
    } catch (...) {
      promise.set_exception(std::current_exception());
    }
  }
  return future.get();
}

std::array<double, 2> DemTerrain::Impl::node_coordinates(double lat_deg, double lon_deg) const {
  const auto [x, y] = crs->from_wgs84(lon_deg, lat_deg);
  if (!std::isfinite(x) || !std::isfinite(y)) return {nan, nan};
  const auto& g = inverse;
  auto at = [&, y = y](double x_shifted) {  // y copied: clang 14 cannot capture a binding
    // Pixel coordinates count from the raster's corner; nodes sit at pixel centres.
    return std::array<double, 2>{g[0] + x_shifted * g[1] + y * g[2] - 0.5,
                                 g[3] + x_shifted * g[4] + y * g[5] - 0.5};
  };
  std::array<double, 2> uv = at(x);
  if (crs->geographic() && !inside(uv)) {
    for (double turn : {360.0, -360.0}) {
      const std::array<double, 2> other = at(x + turn);
      if (inside(other)) return other;
    }
  }
  return uv;
}

DemTerrain::Impl::Window DemTerrain::Impl::window(
    const LocalFrame& frame, const std::vector<std::array<double, 2>>& samples_m) const {
  Window w;
  double u0 = std::numeric_limits<double>::infinity(), v0 = u0, u1 = -u0, v1 = -u0;
  for (const auto& [x, y] : samples_m) {
    const Geodetic p = frame.to_geodetic({x, y, 0.0});
    const std::array<double, 2> uv = node_coordinates(p.lat_deg, p.lon_deg);
    if (!std::isfinite(uv[0]) || !std::isfinite(uv[1])) {
      w.inside_all = false;
      continue;
    }
    w.inside_all = w.inside_all && inside(uv);
    u0 = std::min(u0, uv[0]);
    u1 = std::max(u1, uv[0]);
    v0 = std::min(v0, uv[1]);
    v1 = std::max(v1, uv[1]);
  }
  if (!(u0 <= u1) || !(v0 <= v1)) return w;
  // A node beyond the samples: the samples are a polygon about a curved outline in node space.
  w.i0 = static_cast<int>(std::max(0.0, std::floor(u0) - 1.0));
  w.i1 = static_cast<int>(std::min(width - 1.0, std::ceil(u1) + 1.0));
  w.j0 = static_cast<int>(std::max(0.0, std::floor(v0) - 1.0));
  w.j1 = static_cast<int>(std::min(height - 1.0, std::ceil(v1) + 1.0));
  return w;
}

DemTerrain::DemTerrain(const TerrainSettings& settings) : DemTerrain(settings, Options{}) {}

DemTerrain::DemTerrain(const TerrainSettings& settings, const Options& options)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = settings.dem;
  impl_->options = options;
  impl_->options.tile_pixels = std::max(options.tile_pixels, 2);
  impl_->open(settings);
}

DemTerrain::~DemTerrain() = default;

double DemTerrain::height_m(double lat_deg, double lon_deg) const {
  Impl& dem = *impl_;
  const std::array<double, 2> uv = dem.node_coordinates(lat_deg, lon_deg);
  if (!dem.inside(uv)) return nan;
  const int i = std::min(static_cast<int>(std::floor(uv[0])), dem.width - 2);
  const int j = std::min(static_cast<int>(std::floor(uv[1])), dem.height - 2);
  return cell_height(uv[0] - i, uv[1] - j,
                     [&](int di, int dj) { return dem.node(i + di, j + dj).h_m; });
}

double DemTerrain::detail_m() const { return impl_->detail_m; }

GroundMesh DemTerrain::mesh(const LocalFrame& frame, double half_size_m, double) const {
  Impl& dem = *impl_;
  GroundMesh mesh;
  const double r = half_size_m;
  const Impl::Window w = dem.window(
      frame, {{-r, -r}, {0, -r}, {r, -r}, {r, 0}, {r, r}, {0, r}, {-r, r}, {-r, 0}, {0, 0}});
  if (w.empty()) return mesh;
  const int stride =
      std::max(1, (std::max(w.i1 - w.i0, w.j1 - w.j0) + max_mesh_nodes_per_side - 1) /
                      max_mesh_nodes_per_side);
  const int ni = (w.i1 - w.i0) / stride + 1, nj = (w.j1 - w.j0) / stride + 1;
  const Impl::NodeBlock nodes(dem, w.i0, w.i0 + (ni - 1) * stride, w.j0, w.j0 + (nj - 1) * stride);

  mesh.vertices_m.reserve(3 * static_cast<std::size_t>(ni) * nj);
  std::vector<std::uint32_t> node_vertex(static_cast<std::size_t>(ni) * nj, no_vertex);
  mesh.min_height_m = std::numeric_limits<double>::infinity();
  mesh.max_height_m = -std::numeric_limits<double>::infinity();
  for (int jj = 0; jj < nj; ++jj) {
    for (int ii = 0; ii < ni; ++ii) {
      const Node n = nodes(w.i0 + ii * stride, w.j0 + jj * stride);
      const std::size_t k = static_cast<std::size_t>(jj) * ni + ii;
      const Vec3 p =
          n.valid() ? frame.to_local({n.lat_deg, n.lon_deg, n.h_m}) : Vec3{0.0, 0.0, 0.0};
      for (double coordinate : p) mesh.vertices_m.push_back(static_cast<float>(coordinate));
      if (n.valid()) {
        node_vertex[k] = static_cast<std::uint32_t>(k);
        mesh.min_height_m = std::min(mesh.min_height_m, p[2]);
        mesh.max_height_m = std::max(mesh.max_height_m, p[2]);
      }
    }
  }
  triangulate_grid(ni, nj, node_vertex, mesh.triangles);
  if (mesh.triangles.empty()) mesh.min_height_m = mesh.max_height_m = 0.0;
  return mesh;
}

bool DemTerrain::has_data(const LocalFrame& frame, double radius_m) const {
  Impl& dem = *impl_;
  std::vector<std::array<double, 2>> circle = {{0.0, 0.0}};
  constexpr int points = 32;
  for (int k = 0; k < points; ++k) {
    const double azimuth = 2.0 * std::numbers::pi * k / points;
    // Outside the circle by the chord's sagitta, so that the polygon holds the disc.
    const double out_m = radius_m / std::cos(std::numbers::pi / points);
    circle.push_back({out_m * std::sin(azimuth), out_m * std::cos(azimuth)});
  }
  const Impl::Window w = dem.window(frame, circle);
  if (!w.inside_all || w.empty()) return false;
  const Impl::NodeBlock nodes(dem, w.i0, w.i1, w.j0, w.j1);
  // A hole matters if it touches a triangle that reaches into the disc.
  const double reach_m = radius_m + 1.5 * dem.cell_m;
  for (int j = w.j0; j <= w.j1; ++j) {
    for (int i = w.i0; i <= w.i1; ++i) {
      const Node n = nodes(i, j);
      if (n.valid()) continue;
      if (!std::isfinite(n.lat_deg)) return false;
      const Vec3 p = frame.to_local({n.lat_deg, n.lon_deg, frame.origin().h_m});
      if (std::hypot(p[0], p[1]) <= reach_m) return false;
    }
  }
  return true;
}

VerticalDatum DemTerrain::vertical_datum() const { return impl_->crs->vertical_datum(); }

std::size_t DemTerrain::cached_bytes() const {
  const std::lock_guard lock(impl_->cache_mutex);
  return impl_->cached_bytes;
}

std::size_t DemTerrain::tiles_read() const {
  const std::lock_guard lock(impl_->io_mutex);
  return impl_->tiles_read;
}

}  // namespace glaswave
