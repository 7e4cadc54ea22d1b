// Voxel grids of plant area density: NetCDF through NetCDF-C, other rasters through GDAL.
#include "canopy/voxel_grid.hpp"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>
#include <netcdf.h>
#include <ogr_spatialref.h>
#include <ogr_srs_api.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "canopy/netcdf_classic_header.hpp"
#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/gdal_layer.hpp"
#include "core/length_units.hpp"
#include "core/netcdf_lock.hpp"
#include "core/spawned_reader.hpp"
#include "terrain/gdal_source.hpp"

namespace glaswave {

bool VoxelBlock::column_of(double x, double y, int& i, int& j) const {
  const double u = (x - x0) / dx, v = (y - y0) / dy;
  if (!(u >= 0.0 && u < nx && v >= 0.0 && v < ny)) return false;
  i = static_cast<int>(u);
  j = static_cast<int>(v);
  return true;
}

double VoxelBlock::plant_area_index(int i, int j) const {
  double sum = 0.0;
  for (int k = 0; k < nz; ++k) sum += at(i, j, k) * (z_edges_m[k + 1] - z_edges_m[k]);
  return sum;
}

namespace {

// Regular coordinates: their spacing (signed); an input error when they are not.
double regular_step(const std::vector<double>& c, const std::string& place, const char* axis) {
  if (c.size() < 2) throw input_error(place, std::string("the ") + axis + " axis needs 2 cells");
  const double step = c[1] - c[0];
  if (!(std::isfinite(step) && step != 0.0))
    throw input_error(place, std::string("the ") + axis + " coordinates are not regular");
  for (std::size_t i = 1; i < c.size(); ++i)
    if (!(std::abs((c[i] - c[0]) - i * step) <= 1e-6 * std::abs(step) * (i + 1)))
      throw input_error(place, std::string("the ") + axis + " coordinates are not regular");
  return step;
}

// No vegetation stands 10 km above or below its ground: a height beyond is a grid in other
// units or a corrupt one, and Embree cannot hold boxes near 1e300 m.
constexpr double max_layer_height_m = 1.0e4;

void check_layers(const std::vector<double>& edges, const std::string& place) {
  for (std::size_t k = 0; k < edges.size(); ++k)
    if (!(std::abs(edges[k]) <= max_layer_height_m))
      throw input_error(place, "layer " + std::to_string(k == 0 ? 0 : k - 1) + "'s " +
                                   (k == 0 ? "bottom" : "top") +
                                   " is not a height within 10000 m of the ground");
  for (std::size_t k = 0; k + 1 < edges.size(); ++k)
    if (!(edges[k + 1] > edges[k]))
      throw input_error(place,
                        "the layers' heights do not increase (layer " + std::to_string(k) + ")");
  // Heights are above the ground under each column: a layer below it holds plants in the soil.
  if (edges.front() < -1e-6)
    throw input_error(place, "layer 0's bottom is " + std::to_string(edges.front()) +
                                 " m, under the ground (heights are above the ground under "
                                 "each column, from 0)");
}

// The first bad value among [from, to): an input error naming its voxel.
void check_each_value(const VoxelBlock& block, const std::string& place, double fill,
                      std::size_t from, std::size_t to, int i0, int j0) {
  for (std::size_t n = from; n < to; ++n) {
    const float v = block.pad[n];
    if (!(v >= 0.0f) || !std::isfinite(v) ||
        (std::isfinite(static_cast<float>(fill)) && v == static_cast<float>(fill))) {
      const std::size_t i = n % block.nx + i0, j = n / block.nx % block.ny + j0,
                        k = n / block.nx / block.ny;
      throw input_error(place, "plant area density at voxel (x " + std::to_string(i) + ", y " +
                                   std::to_string(j) + ", z " + std::to_string(k) +
                                   " of the grid) is negative, missing or not finite");
    }
  }
}

void check_values(const VoxelBlock& block, const std::string& place, double fill, int i0, int j0) {
  // Every window of every shot is checked: blocks of values without a branch (the compiler
  // vectorises them), each value again only in a block that holds a bad one. Values are read as
  // floats: a double variable's fill value is compared as the float it is read as.
  const float fill_f = std::isfinite(fill) ? static_cast<float>(fill) : 0.0f;
  const bool fill_is_float = std::isfinite(fill_f);
  const float* pad = block.pad.data();
  constexpr std::size_t stretch = 4096;
  for (std::size_t n0 = 0; n0 < block.pad.size(); n0 += stretch) {
    const std::size_t n1 = std::min(block.pad.size(), n0 + stretch);
    unsigned bad = 0;
    for (std::size_t n = n0; n < n1; ++n) {
      const float v = pad[n];
      bad |= static_cast<unsigned>(!(v >= 0.0f)) |
             static_cast<unsigned>(!(v <= std::numeric_limits<float>::max())) |
             static_cast<unsigned>(fill_is_float && v == fill_f);
    }
    if (bad) check_each_value(block, place, fill, n0, n1, i0, j0);
  }
}

// The columns [first, first + count) of an axis of `n` cells from `origin` by `step` that meet
// [lo, hi]; count 0 when none.
void axis_window(double origin, double step, int n, double lo, double hi, int& first, int& count) {
  double a = (lo - origin) / step, b = (hi - origin) / step;
  if (a > b) std::swap(a, b);
  const double f = std::max(0.0, std::floor(a)), l = std::min<double>(n, std::ceil(b));
  if (!(l > f)) {
    first = count = 0;
    return;
  }
  first = static_cast<int>(f);
  count = static_cast<int>(l) - first;
}

// A text attribute, NC_CHAR or a single NC_STRING (netCDF4-python writes a str holding other
// than ASCII, a WKT's "°", as NC_STRING); empty when absent or of another type.
std::string text_attribute(int ncid, int varid, const char* name) {
  std::size_t length = 0;
  nc_type type;
  if (nc_inq_att(ncid, varid, name, &type, &length) != NC_NOERR) return {};
  if (type == NC_STRING) {
    if (length != 1) return {};
    char* value = nullptr;
    if (nc_get_att_string(ncid, varid, name, &value) != NC_NOERR) return {};
    std::string text = value ? value : "";
    nc_free_string(1, &value);
    return text;
  }
  if (type != NC_CHAR) return {};
  std::string text(length, '\0');
  if (nc_get_att_text(ncid, varid, name, text.data()) != NC_NOERR) return {};
  while (!text.empty() && text.back() == '\0') text.pop_back();
  return text;
}

// The metres in a unit of a coordinate variable's `units` (absent: metres); an input error
// naming the variable and the unit when it is no length known here.
double length_unit(int ncid, int var, const std::string& name, const std::string& place) {
  const std::string units = text_attribute(ncid, var, "units");
  const std::optional<double> metres = metres_per_unit(units);
  if (!metres)
    throw input_error(place, "the units of " + name + " are \"" + units.substr(0, 40) +
                                 "\", not a length glaswave knows (m, dm, cm, mm, km, ft, US "
                                 "survey ft)");
  return *metres;
}

// m^-1 in a unit of plant area density `units` (absent: m2 m-3); an input error naming `what`
// otherwise (cm2 cm-3 is 100 m2 m-3).
double density_unit(const std::string& units, const std::string& what, const std::string& place) {
  const std::optional<double> per_metre = per_metre_per_density_unit(units);
  if (!per_metre)
    throw input_error(place, what + "'s units are \"" + units.substr(0, 40) +
                                 "\", not a plant area density glaswave knows (an area per "
                                 "volume of m, cm, mm, km or ft: m2 m-3, cm2 cm-3, m-1)");
  return *per_metre;
}

// The axis ('X', 'Y', 'Z') a coordinate variable says it is, by CF's `axis`, its standard_name,
// `positive` or its name; 0 when it says none.
char coordinate_axis(int ncid, int var, const std::string& name) {
  const auto lower = [](std::string text) {
    std::transform(text.begin(), text.end(), text.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return text;
  };
  const std::string axis = lower(text_attribute(ncid, var, "axis"));
  if (axis == "x" || axis == "y" || axis == "z") return static_cast<char>(std::toupper(axis[0]));
  const std::string standard = lower(text_attribute(ncid, var, "standard_name"));
  if (standard == "projection_x_coordinate" || standard == "longitude" ||
      standard == "grid_longitude")
    return 'X';
  if (standard == "projection_y_coordinate" || standard == "latitude" ||
      standard == "grid_latitude")
    return 'Y';
  if (standard == "height" || standard == "altitude" ||
      !text_attribute(ncid, var, "positive").empty())
    return 'Z';
  const std::string n = lower(name);
  if (n == "x" || n == "lon" || n == "longitude" || n == "easting") return 'X';
  if (n == "y" || n == "lat" || n == "latitude" || n == "northing") return 'Y';
  if (n == "z" || n == "height" || n == "level") return 'Z';
  return 0;
}

// NetCDF's default fill value of a variable of `type` (read as double), for a variable that
// names none: a value never written reads as it.
double default_fill(nc_type type) {
  switch (type) {
    case NC_BYTE:
      return NC_FILL_BYTE;
    case NC_UBYTE:
      return NC_FILL_UBYTE;
    case NC_SHORT:
      return NC_FILL_SHORT;
    case NC_USHORT:
      return NC_FILL_USHORT;
    case NC_INT:
      return NC_FILL_INT;
    case NC_UINT:
      return NC_FILL_UINT;
    case NC_FLOAT:
      return NC_FILL_FLOAT;
    case NC_DOUBLE:
      return NC_FILL_DOUBLE;
    default:
      return std::numeric_limits<double>::quiet_NaN();
  }
}

// A height of a GeoTIFF band's metadata: a decimal number of metres and nothing else.
double height_metadata(const char* text, int band, const char* key, const std::string& place) {
  std::string_view value(text);
  while (!value.empty() && value.front() == ' ') value.remove_prefix(1);
  while (!value.empty() && value.back() == ' ') value.remove_suffix(1);
  if (!value.empty() && value.front() == '+') value.remove_prefix(1);
  double number = 0.0;
  const auto [end, status] = std::from_chars(value.data(), value.data() + value.size(), number);
  if (value.empty() || status != std::errc() || end != value.data() + value.size() ||
      !std::isfinite(number)) {
    const std::string shown(std::string_view(text).substr(0, 40));
    throw input_error(place, "band " + std::to_string(band) + "'s " + key + " \"" + shown +
                                 "\" is not a number of metres");
  }
  return number;
}

// glaswave-read-voxels's first bytes; the number changes with its messages' layout.
constexpr std::string_view kReaderHello = "glaswave-read-voxels 1\n";
const std::string kReaderRefused =
    "HDF5 failed reading the voxel grid (a corrupt file): it is refused";

}  // namespace

struct VoxelGridFile::Impl {
  // Closed here, so that a grid refused while it is opened (the constructor throwing, the
  // VoxelGridFile never made) leaves no file open: NetCDF kept it, and HDF5 refused to write it
  // again.
  ~Impl() {
    if (ncid >= 0) {
      std::lock_guard lock(netcdf_library_mutex());
      nc_close(ncid);
    }
    if (dataset) GDALClose(dataset);
  }
  std::string place;
  VoxelBlock shape;
  bool netcdf = false;
  int ncid = -1, pad_var = -1;
  double fill = std::numeric_limits<double>::quiet_NaN();
  // CF packing (NetCDF scale_factor and add_offset) or a GDAL band's scale and offset, a layer
  // each; empty when no layer is packed.
  std::vector<double> scale, offset;
  GDALDatasetH dataset = nullptr;
  bool memory = false;                    // shape holds the whole grid, pad included
  std::size_t cache_bytes = 0;            // NetCDF's chunk cache for `pad`
  std::vector<int> band_of_layer;         // GDAL band (1-based) of each layer, bottom up
  std::unique_ptr<SpawnedReader> reader;  // a NetCDF-4 grid's glaswave-read-voxels
  mutable std::mutex mutex;

  void open_spawned(const std::filesystem::path& file);
  void open_netcdf(const std::filesystem::path& file);
  void open_gdal(const std::filesystem::path& file);
  void convert_xy_to_crs_units(const std::array<double, 2>& xy_metres);
};

void VoxelGridFile::Impl::open_netcdf(const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  netcdf = true;
  if (nc_open(file.c_str(), NC_NOWRITE, &ncid) != NC_NOERR)
    throw input_error(place, "cannot open the voxel grid as NetCDF");
  if (nc_inq_varid(ncid, "pad", &pad_var) != NC_NOERR)
    throw input_error(place, "no variable `pad` (plant area density over z, y, x)");
  int ndims = 0;
  nc_inq_varndims(ncid, pad_var, &ndims);
  if (ndims != 3) throw input_error(place, "`pad` must have three dimensions (z, y, x)");
  int dims[3];
  nc_inq_vardimid(ncid, pad_var, dims);
  std::size_t sizes[3];
  std::vector<double> coords[3];
  const char* names[3] = {"z", "y", "x"};
  for (int d = 0; d < 3; ++d) {
    char name[NC_MAX_NAME + 1] = {};
    nc_inq_dim(ncid, dims[d], name, &sizes[d]);
    if (sizes[d] == 0 || sizes[d] > (std::size_t{1} << 24))
      throw input_error(place, std::string("the ") + names[d] + " dimension's size is unusable");
    int var = -1;
    if (nc_inq_varid(ncid, name, &var) != NC_NOERR)
      throw input_error(place, std::string("no coordinate variable for `pad`'s ") + names[d] +
                                   " dimension (" + name + ")");
    int coord_dims = 0, coord_dim = -1;
    nc_inq_varndims(ncid, var, &coord_dims);
    if (coord_dims == 1) nc_inq_vardimid(ncid, var, &coord_dim);
    if (coord_dims != 1 || coord_dim != dims[d])
      throw input_error(place, std::string("the coordinate variable ") + name +
                                   " is not one-dimensional over its own dimension");
    const char axis = coordinate_axis(ncid, var, name);
    if (axis != 0 && axis != "ZYX"[d])
      throw input_error(place, std::string("`pad`'s dimension ") + std::to_string(d + 1) + " (" +
                                   name + ") is its " + axis +
                                   " axis: `pad` must be ordered (z, y, x)");
    coords[d].resize(sizes[d]);
    if (nc_get_var_double(ncid, var, coords[d].data()) != NC_NOERR)
      throw input_error(place, std::string("cannot read the ") + names[d] + " coordinates");
    if (d == 0) {
      const std::string bounds = text_attribute(ncid, var, "bounds");
      int bvar = -1;
      std::vector<double>& edges = shape.z_edges_m;
      if (!bounds.empty() && nc_inq_varid(ncid, bounds.c_str(), &bvar) == NC_NOERR) {
        std::vector<double> b(2 * sizes[0]);
        int bdims = 0;
        nc_inq_varndims(ncid, bvar, &bdims);
        std::size_t first = 0, second = 0;
        if (bdims == 2) {
          int bd[2];
          nc_inq_vardimid(ncid, bvar, bd);
          nc_inq_dimlen(ncid, bd[0], &first);
          nc_inq_dimlen(ncid, bd[1], &second);
        }
        if (first != sizes[0] || second != 2 || nc_get_var_double(ncid, bvar, b.data()) != NC_NOERR)
          throw input_error(place, "the z bounds are not (z, 2)");
        // The bounds' own units, else z's (CF lets bounds leave them out).
        const double metres = text_attribute(ncid, bvar, "units").empty()
                                  ? length_unit(ncid, var, name, place)
                                  : length_unit(ncid, bvar, bounds, place);
        for (double& v : b) v *= metres;
        const double z_metres = length_unit(ncid, var, name, place);
        // Each centre within its layer (CF's rule): centres repeated or out of order, with
        // bounds that increase, say the grid is not what its bounds say.
        for (std::size_t k = 0; k < sizes[0]; ++k) {
          const double centre = coords[0][k] * z_metres;
          if (!(centre >= std::min(b[2 * k], b[2 * k + 1]) - 1e-6 &&
                centre <= std::max(b[2 * k], b[2 * k + 1]) + 1e-6))
            throw input_error(place, "z centre " + std::to_string(k) + " (" +
                                         std::to_string(centre) + " m) lies outside its bounds [" +
                                         std::to_string(b[2 * k]) + ", " +
                                         std::to_string(b[2 * k + 1]) + "] m");
        }
        edges.assign(1, b[0]);
        for (std::size_t k = 0; k < sizes[0]; ++k) {
          if (std::abs(b[2 * k] - edges.back()) > 1e-6)
            throw input_error(place,
                              "the layers leave a gap or overlap at layer " + std::to_string(k));
          edges.push_back(b[2 * k + 1]);
        }
      } else {
        std::vector<double> c = coords[0];
        const double z_metres = length_unit(ncid, var, name, place);
        for (double& v : c) v *= z_metres;
        if (c.size() < 2)
          throw input_error(place, "one layer and no z bounds: its thickness is unknown");
        edges.push_back(c[0] - (c[1] - c[0]) / 2);
        for (std::size_t k = 0; k + 1 < c.size(); ++k) edges.push_back((c[k] + c[k + 1]) / 2);
        edges.push_back(c.back() + (c.back() - c[c.size() - 2]) / 2);
      }
      check_layers(edges, place);
    }
  }
  shape.nz = static_cast<int>(sizes[0]);
  shape.ny = static_cast<int>(sizes[1]);
  shape.nx = static_cast<int>(sizes[2]);
  std::array<double, 2> xy_metres = {0.0, 0.0};  // y's and x's metres a unit; 0: the CRS's
  // x and y in the CRS's units: a length unit of their own (x in km over a CRS in metres) is
  // converted to the CRS's (read below), degrees left as they are.
  for (int d = 1; d < 3; ++d) {
    int var = -1;
    char name[NC_MAX_NAME + 1] = {};
    nc_inq_dimname(ncid, dims[d], name);
    nc_inq_varid(ncid, name, &var);
    std::string units = text_attribute(ncid, var, "units");
    std::transform(units.begin(), units.end(), units.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (units.empty() || units.rfind("degree", 0) == 0) continue;  // the CRS's own
    xy_metres[d - 1] = length_unit(ncid, var, name, place);
  }
  shape.dy = regular_step(coords[1], place, "y");
  shape.dx = regular_step(coords[2], place, "x");
  if (shape.dx < 0.0) throw input_error(place, "x must increase");
  shape.x0 = coords[2][0] - shape.dx / 2;
  shape.y0 = coords[1][0] - shape.dy / 2;
  // The chunks that 2 x 2 read blocks meet, whole (a chunk at the grid's far edge counts in
  // full): along x and y, 2 blocks' columns meet at most ceil(2 b / c) + 1 chunks of c, and
  // never more than the grid's; every layer. A contiguous or NetCDF-3 variable has no chunk
  // cache: the call then changes nothing.
  int storage = NC_CONTIGUOUS;
  std::size_t chunk[3] = {0, 0, 0};
  double chunk_bytes = 0.0;
  if (nc_inq_var_chunking(ncid, pad_var, &storage, chunk) == NC_NOERR && storage == NC_CHUNKED &&
      chunk[0] > 0 && chunk[1] > 0 && chunk[2] > 0) {
    const double blocks = 2.0 * VoxelGridFile::read_block_columns;
    chunk_bytes = sizeof(float) * double((sizes[0] + chunk[0] - 1) / chunk[0] * chunk[0]);
    for (int d = 1; d < 3; ++d) {
      const double c = double(chunk[d]);
      const double whole = std::ceil(double(sizes[d]) / c) * c;
      chunk_bytes *= std::min(whole, (std::ceil(blocks / c) + 1.0) * c);
    }
  }
  cache_bytes =
      static_cast<std::size_t>(std::min(chunk_bytes, double(VoxelGridFile::max_read_cache_bytes)));
  nc_set_var_chunk_cache(ncid, pad_var, cache_bytes, 10007, 0.75f);
  double fill_value = 0.0;
  nc_type pad_type = NC_NAT;
  nc_inq_vartype(ncid, pad_var, &pad_type);
  if (nc_get_att_double(ncid, pad_var, "_FillValue", &fill_value) == NC_NOERR)
    fill = fill_value;
  else
    fill = default_fill(pad_type);
  double factor = 1.0, add = 0.0;
  const bool scaled = nc_get_att_double(ncid, pad_var, "scale_factor", &factor) == NC_NOERR;
  const bool shifted = nc_get_att_double(ncid, pad_var, "add_offset", &add) == NC_NOERR;
  if (scaled || shifted) {
    if (!(std::isfinite(factor) && std::isfinite(add)))
      throw input_error(place, "`pad`'s scale_factor or add_offset is not finite");
    scale.assign(sizes[0], factor);
    offset.assign(sizes[0], add);
  }
  std::string mapping = text_attribute(ncid, pad_var, "grid_mapping");
  int crs_var = -1;
  if (mapping.empty() || nc_inq_varid(ncid, mapping.c_str(), &crs_var) != NC_NOERR)
    nc_inq_varid(ncid, "crs", &crs_var);
  if (crs_var >= 0) {
    shape.crs_wkt = text_attribute(ncid, crs_var, "crs_wkt");
    if (shape.crs_wkt.empty()) shape.crs_wkt = text_attribute(ncid, crs_var, "spatial_ref");
  }
  if (shape.crs_wkt.empty())
    throw input_error(place, "no CRS (a grid_mapping variable with crs_wkt or spatial_ref)");
  convert_xy_to_crs_units(xy_metres);
  // pad's units: an area per volume, as m2 m-3 (cm2 cm-3 is 100 of them).
  const double per_metre = density_unit(text_attribute(ncid, pad_var, "units"), "`pad`", place);
  if (per_metre != 1.0) {
    if (scale.empty()) {
      scale.assign(sizes[0], 1.0);
      offset.assign(sizes[0], 0.0);
    }
    for (double& f : scale) f *= per_metre;
    for (double& a : offset) a *= per_metre;
  }
}

// x and y from the units their variables give (metres each: xy_metres) to the CRS's own: the
// grid's corner and steps scaled; an input error when the CRS measures no length (geographic).
void VoxelGridFile::Impl::convert_xy_to_crs_units(const std::array<double, 2>& xy_metres) {
  if (xy_metres[0] == 0.0 && xy_metres[1] == 0.0) return;  // no length units given
  OGRSpatialReference crs;
  double crs_metres = 0.0;
  {
    const GdalErrorTrap trap;
    if (crs.SetFromUserInput(shape.crs_wkt.c_str(),
                             OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) !=
        OGRERR_NONE)
      return;  // said when placed
    if (crs.IsGeographic())
      throw input_error(place,
                        "x and y are in units of length, and the CRS is geographic "
                        "(degrees)");
    crs_metres = crs.GetLinearUnits();
  }
  if (!(crs_metres > 0.0)) return;
  const double fy = xy_metres[0] > 0.0 ? xy_metres[0] / crs_metres : 1.0;
  const double fx = xy_metres[1] > 0.0 ? xy_metres[1] / crs_metres : 1.0;
  shape.x0 *= fx;
  shape.dx *= fx;
  shape.y0 *= fy;
  shape.dy *= fy;
}

void VoxelGridFile::Impl::open_gdal(const std::filesystem::path& file) {
  prepare_gdal();
  {
    const GdalErrorTrap trap;
    dataset = GDALOpen(file.c_str(), GA_ReadOnly);
  }
  if (!dataset) throw input_error(place, "cannot open the voxel grid (not a raster GDAL reads)");
  double t[6];
  if (GDALGetGeoTransform(dataset, t) != CE_None)
    throw input_error(place, "the voxel grid has no geotransform");
  if (!std::all_of(t, t + 6, [](double v) { return std::isfinite(v); }))
    throw input_error(place, "the voxel grid's geotransform (origin, cell size) is not finite");
  if (t[2] != 0.0 || t[4] != 0.0 || !(t[1] > 0.0) || t[5] == 0.0)
    throw input_error(place, "the voxel grid is rotated or has no cell size");
  OGRSpatialReferenceH srs = GDALGetSpatialRef(dataset);
  if (!srs) throw input_error(place, "the voxel grid has no CRS");
  char* wkt = nullptr;
  const char* options[] = {"FORMAT=WKT2_2019", nullptr};
  OSRExportToWktEx(srs, &wkt, options);
  shape.crs_wkt = wkt ? wkt : "";
  CPLFree(wkt);
  shape.nx = GDALGetRasterXSize(dataset);
  shape.ny = GDALGetRasterYSize(dataset);
  shape.x0 = t[0];
  shape.y0 = t[3];
  shape.dx = t[1];
  shape.dy = t[5];
  const int bands = GDALGetRasterCount(dataset);
  if (bands < 1) throw input_error(place, "the voxel grid has no band");
  std::vector<std::pair<double, int>> bottoms;
  std::vector<double> tops(bands + 1);
  for (int b = 1; b <= bands; ++b) {
    GDALRasterBandH band = GDALGetRasterBand(dataset, b);
    const char* bottom = GDALGetMetadataItem(band, "z_bottom_m", nullptr);
    const char* top = GDALGetMetadataItem(band, "z_top_m", nullptr);
    if (!bottom || !top)
      throw input_error(place, "band " + std::to_string(b) +
                                   " has no z_bottom_m and z_top_m metadata (its heights)");
    bottoms.emplace_back(height_metadata(bottom, b, "z_bottom_m", place), b);
    tops[b] = height_metadata(top, b, "z_top_m", place);
  }
  std::sort(bottoms.begin(), bottoms.end());
  shape.z_edges_m.assign(1, bottoms.front().first);
  for (const auto& [bottom, b] : bottoms) {
    if (std::abs(bottom - shape.z_edges_m.back()) > 1e-6)
      throw input_error(
          place, "band " + std::to_string(b) + "'s layer leaves a gap or overlaps the one below");
    shape.z_edges_m.push_back(tops[b]);
    band_of_layer.push_back(b);
    int has_nodata = 0;
    const double nodata = GDALGetRasterNoDataValue(GDALGetRasterBand(dataset, b), &has_nodata);
    if (has_nodata) fill = nodata;
    int has_scale = 0, has_offset = 0;
    double band_scale = GDALGetRasterScale(GDALGetRasterBand(dataset, b), &has_scale);
    double band_offset = GDALGetRasterOffset(GDALGetRasterBand(dataset, b), &has_offset);
    if (!has_scale) band_scale = 1.0;
    if (!has_offset) band_offset = 0.0;
    // The band's unit: an area per volume, as m2 m-3 (cm2 cm-3 is 100 of them).
    const double per_metre = density_unit(GDALGetRasterUnitType(GDALGetRasterBand(dataset, b)),
                                          "band " + std::to_string(b), place);
    band_scale *= per_metre;
    band_offset *= per_metre;
    if (band_scale != 1.0 || band_offset != 0.0) {
      if (!(std::isfinite(band_scale) && std::isfinite(band_offset)))
        throw input_error(place, "band " + std::to_string(b) + "'s scale or offset is not finite");
      scale.resize(bands, 1.0);
      offset.resize(bands, 0.0);
      scale[band_of_layer.size() - 1] = band_scale;
      offset[band_of_layer.size() - 1] = band_offset;
    }
  }
  shape.nz = bands;
  check_layers(shape.z_edges_m, place);
}

// NetCDF-4 grids are read by the reader program (canopy/voxel_grid.hpp says why): it sends the
// grid's shape, or the error, here.
void VoxelGridFile::Impl::open_spawned(const std::filesystem::path& file) {
  netcdf = true;
  const std::filesystem::path program = find_reader_program(
      "glaswave-read-voxels", {GLASWAVE_VOXEL_READER_BUILT, GLASWAVE_VOXEL_READER_INSTALLED});
  if (program.empty())
    throw run_error(place,
                    "cannot read the voxel grid: the program glaswave-read-voxels, which reads "
                    "NetCDF-4 grids, is missing from this installation (install it as `cmake "
                    "--install` does, in PREFIX/libexec/glaswave/)");
  reader = std::make_unique<SpawnedReader>(program, std::vector<std::string>{file.string()}, place,
                                           "the voxel grid", std::string(kReaderHello));
  const std::string reply = reader->receive();
  try {
    MessageIn in(reply);
    if (in.get<char>() != 'S') throw in.get_error();
    shape.crs_wkt = in.get_string();
    shape.nx = in.get<int>();
    shape.ny = in.get<int>();
    shape.nz = in.get<int>();
    shape.x0 = in.get<double>();
    shape.y0 = in.get<double>();
    shape.dx = in.get<double>();
    shape.dy = in.get<double>();
    const auto edges = in.get<std::uint64_t>();
    if (shape.nz < 1 || edges != static_cast<std::uint64_t>(shape.nz) + 1)
      throw std::length_error("layers");
    shape.z_edges_m.resize(edges);
    in.get_bytes(shape.z_edges_m.data(), edges * sizeof(double));
    cache_bytes = in.get<std::uint64_t>();
  } catch (const std::length_error&) {
    throw input_error(place, kReaderRefused);
  }
}

VoxelGridFile::VoxelGridFile(const std::filesystem::path& file) : impl_(std::make_unique<Impl>()) {
  open(file, true);
}

VoxelGridFile::VoxelGridFile(const std::filesystem::path& file, InProcess)
    : impl_(std::make_unique<Impl>()) {
  open(file, false);
}

void VoxelGridFile::open(const std::filesystem::path& file, bool spawn) {
  impl_->place = file.string();
  // A FIFO or a device (or a VRT naming one) is refused before it is opened.
  require_gdal_source(file.native(), "the voxel grid");
  std::ifstream in(file, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  in.close();
  const bool classic = magic[0] == 'C' && magic[1] == 'D' && magic[2] == 'F';
  const bool hdf5 = magic[1] == 'H' && magic[2] == 'D' && magic[3] == 'F';
  if (classic) {
    check_classic_netcdf_header(file, impl_->place);
    impl_->open_netcdf(file);
  } else if (hdf5) {
    if (spawn)
      impl_->open_spawned(file);
    else
      impl_->open_netcdf(file);
  } else {
    impl_->open_gdal(file);
  }
}

VoxelGridFile::VoxelGridFile(VoxelBlock grid) : impl_(std::make_unique<Impl>()) {
  impl_->place = "the voxelised point cloud";
  impl_->memory = true;
  if (grid.nx <= 0 || grid.ny <= 0 || grid.nz <= 0 ||
      grid.pad.size() != std::size_t(grid.nx) * grid.ny * grid.nz ||
      grid.z_edges_m.size() != std::size_t(grid.nz) + 1)
    throw run_error(impl_->place, "a voxel grid whose sizes do not agree");
  check_layers(grid.z_edges_m, impl_->place);
  impl_->shape = std::move(grid);
}

VoxelGridFile::~VoxelGridFile() = default;

const VoxelBlock& VoxelGridFile::shape() const { return impl_->shape; }

bool VoxelGridFile::netcdf() const { return impl_->netcdf; }

std::size_t VoxelGridFile::read_cache_bytes() const { return impl_->cache_bytes; }

void VoxelGridFile::window_columns(double x_min, double x_max, double y_min, double y_max, int& i0,
                                   int& ni, int& j0, int& nj) const {
  const VoxelBlock& s = impl_->shape;
  axis_window(s.x0, s.dx, s.nx, x_min, x_max, i0, ni);
  axis_window(s.y0, s.dy, s.ny, y_min, y_max, j0, nj);
  if (ni == 0 || nj == 0) {
    i0 = ni = j0 = nj = 0;
    return;
  }
  const std::size_t voxels = std::size_t(ni) * nj * s.nz;
  if (voxels > max_window_voxels)
    throw input_error(impl_->place, "a window of " + std::to_string(voxels) +
                                        " voxels is more than the limit of " +
                                        std::to_string(max_window_voxels));
}

VoxelBlock VoxelGridFile::window(double x_min, double x_max, double y_min, double y_max) const {
  int i0 = 0, ni = 0, j0 = 0, nj = 0;
  window_columns(x_min, x_max, y_min, y_max, i0, ni, j0, nj);
  return columns(i0, ni, j0, nj);
}

VoxelBlock VoxelGridFile::columns(int i0, int ni, int j0, int nj) const {
  const VoxelBlock& s = impl_->shape;
  VoxelBlock block;
  block.crs_wkt = s.crs_wkt;
  block.z_edges_m = s.z_edges_m;
  block.nz = s.nz;
  block.dx = s.dx;
  block.dy = s.dy;
  if (ni <= 0 || nj <= 0) return block;
  const std::size_t voxels = std::size_t(ni) * nj * s.nz;
  block.nx = ni;
  block.ny = nj;
  block.x0 = s.x0 + i0 * s.dx;
  block.y0 = s.y0 + j0 * s.dy;
  block.pad.resize(voxels);
  if (impl_->reader) {
    // Read, unpacked and checked by the reader program.
    MessageOut request;
    for (int n : {i0, ni, j0, nj}) request.put(std::int32_t{n});
    std::string reply;
    {
      std::lock_guard lock(impl_->mutex);
      impl_->reader->send(request.text());
      reply = impl_->reader->receive();
    }
    try {
      MessageIn in(reply);
      if (in.get<char>() != 'S') throw in.get_error();
      if (in.left() != voxels * sizeof(float)) throw std::length_error("densities");
      in.get_bytes(block.pad.data(), voxels * sizeof(float));
    } catch (const std::length_error&) {
      throw input_error(impl_->place, kReaderRefused);
    }
    return block;
  }
  if (impl_->memory) {
    for (int k = 0; k < s.nz; ++k)
      for (int j = 0; j < nj; ++j)
        for (int i = 0; i < ni; ++i)
          block.pad[(std::size_t(k) * nj + j) * ni + i] = s.at(i0 + i, j0 + j, k);
  } else if (impl_->netcdf) {
    std::lock_guard lock(netcdf_library_mutex());
    const std::size_t start[3] = {0, std::size_t(j0), std::size_t(i0)};
    const std::size_t count[3] = {std::size_t(s.nz), std::size_t(nj), std::size_t(ni)};
    if (nc_get_vara_float(impl_->ncid, impl_->pad_var, start, count, block.pad.data()) != NC_NOERR)
      throw input_error(impl_->place, "cannot read the plant area density");
  } else {
    std::lock_guard lock(impl_->mutex);
    for (int k = 0; k < s.nz; ++k) {
      GDALRasterBandH band = GDALGetRasterBand(impl_->dataset, impl_->band_of_layer[k]);
      const GdalErrorTrap trap;
      const CPLErr status =
          GDALRasterIO(band, GF_Read, i0, j0, ni, nj, block.pad.data() + std::size_t(k) * ni * nj,
                       ni, nj, GDT_Float32, 0, 0);
      if (status != CE_None)
        throw input_error(impl_->place, "cannot read band " +
                                            std::to_string(impl_->band_of_layer[k]) +
                                            " (truncated or corrupt)");
    }
  }
  double fill = impl_->fill;
  if (!impl_->scale.empty()) {
    // Packed values: the fill value is a packed one, marked missing before values are unpacked.
    const float packed_fill = std::isfinite(fill) ? static_cast<float>(fill) : 0.0f;
    const bool has_fill = std::isfinite(fill) && std::isfinite(packed_fill);
    const std::size_t layer = std::size_t(ni) * nj;
    for (int k = 0; k < s.nz; ++k) {
      const double a = impl_->scale[k], b = impl_->offset[k];
      float* values = block.pad.data() + k * layer;
      for (std::size_t n = 0; n < layer; ++n)
        values[n] = has_fill && values[n] == packed_fill ? std::numeric_limits<float>::quiet_NaN()
                                                         : static_cast<float>(values[n] * a + b);
    }
    fill = std::numeric_limits<double>::quiet_NaN();
  }
  check_values(block, impl_->place, fill, i0, j0);
  return block;
}

int voxel_reader_main(int argc, char** argv) {
  const int channel = take_reply_channel();
  if (argc != 2 || channel < 0) return 2;
  bound_request_cpu(argv[1]);
  std::unique_ptr<VoxelGridFile> grid;
  MessageOut opened;
  const auto refuse = [&](MessageOut& out, const std::exception& e) {
    out.put('E');
    if (const auto* error = dynamic_cast<const Error*>(&e))
      out.put_error(*error);
    else
      out.put_error(input_error(argv[1], std::string("cannot read the voxel grid: ") + e.what()));
  };
  try {
    grid.reset(new VoxelGridFile(argv[1], VoxelGridFile::InProcess{}));
    const VoxelBlock& s = grid->shape();
    opened.put('S');
    opened.put_string(s.crs_wkt);
    for (int n : {s.nx, s.ny, s.nz}) opened.put(n);
    for (double v : {s.x0, s.y0, s.dx, s.dy}) opened.put(v);
    opened.put(std::uint64_t{s.z_edges_m.size()});
    opened.put_bytes(s.z_edges_m.data(), s.z_edges_m.size() * sizeof(double));
    opened.put(std::uint64_t{grid->read_cache_bytes()});
  } catch (const std::exception& e) {
    refuse(opened, e);
  }
  if (!write_hello(channel, kReaderHello) || !write_message(channel, opened.text())) return 2;
  if (!grid) return 0;
  for (std::string request; read_message(STDIN_FILENO, request);) {
    MessageOut reply;
    try {
      MessageIn in(request);
      const auto i0 = in.get<std::int32_t>(), ni = in.get<std::int32_t>();
      const auto j0 = in.get<std::int32_t>(), nj = in.get<std::int32_t>();
      bound_request_cpu(argv[1], std::uint64_t(std::max(ni, 0)) * std::max(nj, 0) *
                                     std::max(grid->shape().nz, 0) * sizeof(float));
      const VoxelBlock block = grid->columns(i0, ni, j0, nj);
      reply.put('S');
      reply.put_bytes(block.pad.data(), block.pad.size() * sizeof(float));
    } catch (const std::exception& e) {
      reply = MessageOut();
      refuse(reply, e);
    }
    if (!write_message(channel, reply.text())) return 2;
  }
  return 0;
}

}  // namespace glaswave
