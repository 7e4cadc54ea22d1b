// shots.nc through the netCDF-C API. The per-shot variables are the rows of the product field
// table (product_fields.hpp): definition, attributes, chunking and writing are driven by it,
// so a new product variable is one row there. The variables shared by every shot (bands, bin
// times, the transmitted pulse) are defined here.
#include "pipeline/products/netcdf_writer.hpp"

#include <netcdf.h>
#include <sys/resource.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "core/netcdf_lock.hpp"
#include "core/registry.hpp"
#include "core/write_error.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

// Level 2 already takes most of what deflate can from waveforms (long runs of zero power
// before and after the return); higher levels cost time for little more.
constexpr int kDeflateLevel = 2;
// Every per-shot variable is chunked whole shots at a time, as many as fit in this many bytes
// (a power of two of them, at most kMostShotsPerChunk): a whole variable reads in a few chunks,
// one shot in one chunk of at most this size (16 shots of two bands' waveforms).
constexpr std::size_t kChunkTarget_B = 128 * 1024;
constexpr std::size_t kMostShotsPerChunk = 1024;
// Photon events are chunked along `photon` alone: 4096 of them (32 KiB of a float64 variable).
constexpr std::size_t kPhotonsPerChunk = 4096;
// The coordinates of a trajectory; they carry no `coordinates` attribute themselves.
constexpr const char* kShotCoordinates = "time lat lon";
// The grid mapping variable every geolocated variable names.
constexpr const char* kCrsVariable = "crs";
// EPSG:4979, WGS 84 with ellipsoidal heights: latitude, longitude and every elevation of the
// product are geodetic coordinates on the WGS 84 ellipsoid.
constexpr const char* kCrsWkt =
    R"wkt(GEOGCRS["WGS 84",DATUM["World Geodetic System 1984",ELLIPSOID["WGS 84",6378137,)wkt"
    R"wkt(298.257223563,LENGTHUNIT["metre",1]]],PRIMEM["Greenwich",0,ANGLEUNIT["degree",)wkt"
    R"wkt(0.0174532925199433]],CS[ellipsoidal,3],AXIS["geodetic latitude (Lat)",north,ORDER[1],)wkt"
    R"wkt(ANGLEUNIT["degree",0.0174532925199433]],AXIS["geodetic longitude (Lon)",east,ORDER[2],)wkt"
    R"wkt(ANGLEUNIT["degree",0.0174532925199433]],AXIS["ellipsoidal height (h)",up,ORDER[3],)wkt"
    R"wkt(LENGTHUNIT["metre",1]],ID["EPSG",4979]])wkt";

bool is_shot_coordinate(std::string_view name) {
  return name == "shot" || name == "time" || name == "lat" || name == "lon";
}

// The smallest and largest finite values seen; empty until one is.
struct Bounds {
  double min = std::numeric_limits<double>::infinity();
  double max = -std::numeric_limits<double>::infinity();
  void add(double value) {
    if (!std::isfinite(value)) return;
    min = std::min(min, value);
    max = std::max(max, value);
  }
  bool empty() const { return min > max; }
};

nc_type nc_type_of(StorageType type) {
  switch (type) {
    case StorageType::int64:
      return NC_INT64;
    case StorageType::uint8:
      return NC_UBYTE;
    case StorageType::int32:
      return NC_INT;
    case StorageType::float32:
      return NC_FLOAT;
    case StorageType::float64:
      return NC_DOUBLE;
  }
  return NC_NAT;
}

// Whether a [band][...] nested vector has the shape `shape`.
bool has_shape(const std::vector<double>& values, std::span<const std::size_t> shape) {
  return shape.size() == 1 && values.size() == shape[0];
}
bool has_shape(const std::vector<std::int32_t>& values, std::span<const std::size_t> shape) {
  return shape.size() == 1 && values.size() == shape[0];
}
template <class T>
bool has_shape(const std::vector<std::vector<T>>& values, std::span<const std::size_t> shape) {
  if (shape.empty() || values.size() != shape[0]) return false;
  for (const auto& inner : values) {
    if (!has_shape(inner, shape.subspan(1))) return false;
  }
  return true;
}

// Copies a nested vector of a shape checked by has_shape() to `out` in C order; returns the end.
double* copy_flat(const std::vector<double>& values, double* out) {
  return std::copy(values.begin(), values.end(), out);
}
double* copy_flat(const std::vector<std::int32_t>& values, double* out) {
  return std::copy(values.begin(), values.end(), out);  // exact: every int32 is a double
}
template <class T>
double* copy_flat(const std::vector<std::vector<T>>& values, double* out) {
  for (const auto& inner : values) out = copy_flat(inner, out);
  return out;
}

std::string describe_shape(const std::vector<double>& values) {
  return std::to_string(values.size());
}
std::string describe_shape(const std::vector<std::int32_t>& values) {
  return std::to_string(values.size());
}
template <class T>
std::string describe_shape(const std::vector<std::vector<T>>& values) {
  if (values.empty()) return "0";
  return std::to_string(values.size()) + " x " + describe_shape(values.front());
}

std::string join_shape(std::span<const std::size_t> shape) {
  std::string text;
  for (std::size_t n : shape) text += (text.empty() ? "" : " x ") + std::to_string(n);
  return text;
}

// Owns a netCDF id: closed when the owner goes, whatever happened. One never closed by its
// owner (a run that failed, a full disk) is aborted: closing would flush a file that is to be
// removed anyway, and a failed flush leaves the HDF5 library with a half-closed file.
class NcHandle {
 public:
  NcHandle() = default;
  ~NcHandle() {
    if (id_ >= 0) nc_abort(id_);
  }
  NcHandle(const NcHandle&) = delete;
  NcHandle& operator=(const NcHandle&) = delete;

  int* out() { return &id_; }
  int id() const { return id_; }
  // Lets the file go without closing it (see NetcdfWriter::Impl's destructor).
  void abandon() { id_ = -1; }
  // The id is never used again after nc_close, even when closing failed.
  int close() {
    if (id_ < 0) return NC_NOERR;
    const int status = nc_close(id_);
    id_ = -1;
    return status;
  }

 private:
  int id_ = -1;
};

// Whether writing what HDF5 still holds into `file` could fail: less than this room left on its
// file system (HDF5's caches are tens of megabytes at most), or a file size limit.
bool flush_may_fail(const std::filesystem::path& file) {
  constexpr double kRoomNeeded_B = 1e9;
  struct statvfs fs {};
  if (::statvfs(file.parent_path().empty() ? "." : file.parent_path().c_str(), &fs) != 0)
    return true;
  rlimit limit{};
  const bool limited = ::getrlimit(RLIMIT_FSIZE, &limit) == 0 && limit.rlim_cur != RLIM_INFINITY;
  return limited ||
         static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize) < kRoomNeeded_B;
}

// libnetcdf's lock, with HDF5's error printing off in the calling thread (see
// quiet_hdf5_in_this_thread).
class LibraryLock {
 public:
  LibraryLock() : lock_(netcdf_library_mutex()) { quiet_hdf5_in_this_thread(); }

 private:
  std::lock_guard<std::mutex> lock_;
};

}  // namespace

struct NetcdfWriter::Impl {
  // Which of a ChunkBuffer's arrays holds a variable's values.
  enum class Held : std::uint8_t { reals, int64s, bytes };
  struct DefinedVariable {
    const ProductField* def;
    int varid;
    std::vector<std::size_t> shape;  // lengths after the shot dimension
    std::size_t per_shot = 1;        // values of one shot
    std::size_t chunk_shots = 1;     // shots in one chunk, and in one write
    Held held = Held::reals;
    double fill = 0.0;  // what the file holds where a flagged shot carries no array
  };
  // One chunk's records of one variable, held until all of them have come: the chunk is then
  // written whole in one call and compressed once (a call per value and shot took most of a
  // short shot's time in HDF5's bookkeeping).
  struct ChunkBuffer {
    std::size_t first = 0, count = 0, filled = 0;  // records [first, first + count)
    std::vector<double> reals;                     // every field but the integer scalars
    std::vector<long long> int64s;
    std::vector<unsigned char> bytes;
  };
  struct RaggedVariable {
    const ProductField* def;
    int varid;
  };
  // One record's photon events, a list per ragged variable.
  using RaggedShot = std::vector<std::vector<double>>;
  // The variables shared by every shot, written once the definitions end.
  struct RunVariables {
    int trajectory = -1, band = -1, wavelength = -1, band_name = -1, bin_time = -1, tx_time = -1,
        tx_waveform = -1, order = -1, percentile = -1, crs = -1;
  };

  Impl(std::filesystem::path final_path, std::int64_t shots)
      : file(final_path), ledger(std::move(final_path), shots) {}
  // An unfinished file is given up. Aborting still flushes HDF5's caches, and a flush that
  // fails crashes both netCDF-C's close (H5Iget_name from reportopenobjects) and HDF5's own at
  // exit (H5F__close_cb). Where a flush could fail (little room left, a file size limit) the
  // file is abandoned instead: removed unclosed (the command ends without HDF5's exit handlers).
  ~Impl() {
    if (nc.id() >= 0 && flush_may_fail(file.part_path())) nc.abandon();
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  // Declared before the handle so that it is destroyed after it: the file is closed before
  // an unfinished .part is removed.
  AtomicFile file;
  NcHandle nc;
  std::size_t shots = 0, tx_bins = 0;
  ProductShape shape;  // bands, bins, orders
  struct Dimension {
    std::string name;
    int id;
    std::size_t length;
  };
  std::vector<Dimension> dims;
  std::vector<DefinedVariable> variables;
  std::vector<std::map<std::size_t, ChunkBuffer>> open_chunks;  // per variable, by chunk
  RecordLedger ledger;
  // The photon events (ragged along `photon`, appended in record order: a record that comes
  // early waits here for those before it) and their count variable.
  std::vector<RaggedVariable> ragged;
  int photon_count = -1;
  std::size_t photons_written = 0, next_ragged = 0;
  std::map<std::size_t, RaggedShot> waiting;
  bool broken = false;        // a chunk's write failed: the file lacks records already taken
  bool reproducible = false;  // SOURCE_DATE_EPOCH set: no wall-clock measurement written
  // What ACDD's discovery attributes say of the records written.
  Bounds time_s, lat_deg, lon_deg, elev_m;

  [[noreturn]] void fail(const std::string& message) const {
    throw run_error(file.final_path().string(), message);
  }

  // A failed call; HDF5 says only "HDF error", the write under it left errno (a full disk).
  void check(int status, const std::string& what) const {
    if (status == NC_NOERR) return;
    const int error_number = errno;
    if (no_space(error_number)) fail(write_failure(error_number) + " (" + what + ")");
    fail(what + ": " + nc_strerror(status));
  }

  int dim(const char* name) const {
    for (const Dimension& dimension : dims) {
      if (dimension.name == name) return dimension.id;
    }
    fail(std::string("internal: no dimension '") + name + "'");
  }

  void define_dim(const char* name, std::size_t length) {
    int id = -1;
    check(nc_def_dim(nc.id(), name, length, &id), std::string("defining dimension '") + name + "'");
    dims.push_back({name, id, length});
  }

  void put_text(int varid, const char* variable, const char* name, const std::string& value) const {
    check(nc_put_att_text(nc.id(), varid, name, value.size(), value.c_str()),
          std::string("attribute '") + name + "' of '" + variable + "'");
  }
  void put_text_if(int varid, const char* variable, const char* name, const char* value) const {
    if (value != nullptr) put_text(varid, variable, name, value);
  }

  // A variable with the attributes every variable of the product has.
  int define_variable(const char* name, nc_type type, const std::vector<int>& dimids,
                      const char* units, const char* long_name,
                      const char* standard_name = nullptr) const {
    int varid = -1;
    check(nc_def_var(nc.id(), name, type, static_cast<int>(dimids.size()), dimids.data(), &varid),
          std::string("defining variable '") + name + "'");
    put_text(varid, name, "units", units);
    put_text(varid, name, "long_name", long_name);
    put_text_if(varid, name, "standard_name", standard_name);
    return varid;
  }

  // NaN fill on floating-point data. Integer variables get no _FillValue: finish() refuses a
  // product with a record never written, so they hold no fill, and xarray would turn a masked
  // integer into float.
  void put_fill(int varid, const ProductField& def) const {
    const std::string what = std::string("variable '") + def.name + "' _FillValue";
    if (def.type == StorageType::float32) {
      const auto fill = static_cast<float>(def.fill);
      check(nc_put_att_float(nc.id(), varid, "_FillValue", NC_FLOAT, 1, &fill), what);
    } else if (def.type == StorageType::float64) {
      check(nc_put_att_double(nc.id(), varid, "_FillValue", NC_DOUBLE, 1, &def.fill), what);
    }
  }

  // Whole shots to a chunk, so that write() fills whole chunks (held until complete, in any
  // order: no read-modify-write), compressed; returns the shots of a chunk.
  std::size_t chunk_by_shot(int varid, const ProductField& def,
                            const std::vector<std::size_t>& lengths) const {
    const std::string what = std::string("variable '") + def.name + "'";
    std::size_t shot_B = def.type == StorageType::uint8                                       ? 1
                         : def.type == StorageType::int32 || def.type == StorageType::float32 ? 4
                                                                                              : 8;
    for (std::size_t n : lengths) shot_B *= n;
    std::size_t chunk_shots = kMostShotsPerChunk;
    while (chunk_shots > 1 && chunk_shots * shot_B > kChunkTarget_B) chunk_shots /= 2;
    chunk_shots = std::min(shots, chunk_shots);
    std::vector<std::size_t> chunks = {chunk_shots};
    chunks.insert(chunks.end(), lengths.begin(), lengths.end());
    check(nc_def_var_chunking(nc.id(), varid, NC_CHUNKED, chunks.data()), what + " chunking");
    check(nc_def_var_deflate(nc.id(), varid, 1, 1, kDeflateLevel), what + " compression");
    // Each chunk is written once, whole: with no room to cache it HDF5 compresses and writes it
    // then, beside the next batch's simulation, not all at once when the file closes (a bare slope
    // spent 12 % of its run there, on one thread, after the last shot). netCDF-C 4.9 takes a
    // cache of 0 bytes for "the file's default", so the cache is one byte: smaller than any chunk.
    check(nc_set_var_chunk_cache(nc.id(), varid, 1, 1, 1.0f), what + " chunk cache");
    return chunk_shots;
  }

  // The value HDF5 fills a variable with where nothing was written: its _FillValue, or
  // netCDF's default for an integer type.
  double fill_of(int varid, const ProductField& def) const {
    int no_fill = 0;
    const std::string what = std::string("variable '") + def.name + "' fill value";
    if (def.type == StorageType::float32) {
      float fill = 0.0f;
      check(nc_inq_var_fill(nc.id(), varid, &no_fill, &fill), what);
      return fill;
    }
    if (def.type == StorageType::int32) {
      int fill = 0;
      check(nc_inq_var_fill(nc.id(), varid, &no_fill, &fill), what);
      return fill;
    }
    double fill = 0.0;
    if (def.type == StorageType::float64)
      check(nc_inq_var_fill(nc.id(), varid, &no_fill, &fill), what);
    return fill;
  }

  // A list a shot along `photon` (CF contiguous ragged array), chunked and compressed along it.
  void define_ragged_variable(const ProductField& def) {
    const int varid = define_variable(def.name, nc_type_of(def.type), {dim("photon")}, def.units,
                                      def.long_name, def.standard_name);
    put_text_if(varid, def.name, "comment", def.comment);
    put_fill(varid, def);
    const std::string what = std::string("variable '") + def.name + "'";
    const std::size_t chunk[] = {kPhotonsPerChunk};
    check(nc_def_var_chunking(nc.id(), varid, NC_CHUNKED, chunk), what + " chunking");
    check(nc_def_var_deflate(nc.id(), varid, 1, 1, kDeflateLevel), what + " compression");
    ragged.push_back({&def, varid});
  }

  // CF's count variable of the contiguous ragged arrays: photons a shot, in shot order.
  void define_photon_count() {
    photon_count = define_variable("photon_count", NC_INT, {dim("shot")}, "1",
                                   "number of photon events of the shot");
    put_text(photon_count, "photon_count", "sample_dimension", "photon");
  }

  void define_shot_variable(const ProductField& def) {
    if (def.ragged()) {
      if (shape.photons) define_ragged_variable(def);
      return;
    }
    std::vector<std::size_t> lengths = shape.of(def);
    if (def.per_band() && lengths.empty()) return;  // this run has no such dimension
    std::vector<int> dimids = {dim("shot")};
    if (def.per_band()) dimids.push_back(dim("band"));
    for (const char* inner : def.inner_dims)
      if (inner != nullptr) dimids.push_back(dim(inner));

    const int varid = define_variable(def.name, nc_type_of(def.type), dimids, def.units,
                                      def.long_name, def.standard_name);
    put_text_if(varid, def.name, "comment", def.comment);
    put_text_if(varid, def.name, "gedi_name", def.gedi_name);
    put_text_if(varid, def.name, "glas_name", def.glas_name);
    put_fill(varid, def);
    if (!is_shot_coordinate(def.name)) {
      put_text(varid, def.name, "coordinates", kShotCoordinates);
      put_text(varid, def.name, "grid_mapping", kCrsVariable);
    }
    DefinedVariable variable{&def, varid, lengths};
    variable.chunk_shots = chunk_by_shot(varid, def, lengths);
    for (std::size_t n : lengths) variable.per_shot *= n;
    std::visit(
        [&](auto field) {
          using T = std::remove_cvref_t<decltype(ShotRecord{}.*field)>;
          if constexpr (std::is_same_v<T, std::int64_t>) variable.held = Held::int64s;
          if constexpr (std::is_same_v<T, std::uint8_t>) variable.held = Held::bytes;
        },
        def.field);
    variable.fill = fill_of(varid, def);
    variables.push_back(std::move(variable));
  }

  void define_globals(const RunInfo& info) {
    const std::string title = "glaswave simulated satellite waveform lidar shots";
    const std::string source = std::string("glaswave ") + GLASWAVE_VERSION;
    put_text(NC_GLOBAL, "global", "Conventions", "CF-1.10, ACDD-1.3");
    put_text(NC_GLOBAL, "global", "featureType", "trajectory");
    put_text(NC_GLOBAL, "global", "title", title);
    put_text(NC_GLOBAL, "global", "summary",
             "Waveforms of a satellite laser altimeter (GLAS- or GEDI-like) simulated by Monte "
             "Carlo radiative transfer over terrain and vegetation, one record per shot, with "
             "their geolocation, GLA14- and GEDI L2A-style waveform metrics, and the truth of the "
             "simulated scene under each footprint.");
    put_text(NC_GLOBAL, "global", "keywords",
             "lidar, waveform lidar, laser altimetry, GLAS, ICESat, GEDI, canopy height, "
             "vegetation structure, Monte Carlo radiative transfer, simulation");
    put_text(NC_GLOBAL, "global", "standard_name_vocabulary", "CF Standard Name Table v84");
    put_text(NC_GLOBAL, "global", "processing_level", "simulated L1B/L2A-like waveforms");
    put_text(NC_GLOBAL, "global", "creator_name", "");
    put_text(NC_GLOBAL, "global", "date_created",
             info.created.iso8601.empty() ? product_creation_time().iso8601 : info.created.iso8601);
    put_text(NC_GLOBAL, "global", "history", info.command_line);
    put_text(NC_GLOBAL, "global", "source", source);
    put_text(
        NC_GLOBAL, "global", "references",
        "North et al. (2010), A Monte Carlo radiative transfer model of satellite waveform lidar");
    put_text(NC_GLOBAL, "global", "config", info.config_json);
    // The variables that every shot shares, as coordinates (xarray reads this attribute): runs
    // of parts of a track (`--shots`) then combine with xarray's defaults, which would otherwise
    // stack each part's copy of them along the shot dimension.
    put_text(NC_GLOBAL, "global", "coordinates",
             "trajectory crs wavelength band_name bin_time_ns tx_time_ns tx_waveform");
    if (!info.vertical_datum.empty())
      put_text(NC_GLOBAL, "global", "vertical_datum", info.vertical_datum);
    const unsigned long long seed = info.seed;
    check(nc_put_att_ulonglong(nc.id(), NC_GLOBAL, "seed", NC_UINT64, 1, &seed),
          "global attribute 'seed'");
  }

  void define_dims() {
    define_dim("shot", shots);
    define_dim("band", shape.bands);
    define_dim("bin", shape.bins);
    define_dim("tx_bin", tx_bins);
    define_dim("gaussian", shape.length("gaussian"));
    define_dim("percentile", shape.length("percentile"));
    if (shape.orders > 0) define_dim("order", shape.orders);
    if (shape.photons) define_dim("photon", NC_UNLIMITED);
  }

  RunVariables define_run_variables() const {
    RunVariables v;
    // CF: a single trajectory is identified by a scalar variable with cf_role trajectory_id.
    v.trajectory =
        define_variable("trajectory", NC_STRING, {}, "1", "trajectory (the simulated track)");
    put_text(v.trajectory, "trajectory", "cf_role", "trajectory_id");
    // The band's coordinate is its wavelength, so that ds.sel(band=1064) picks a band;
    // `wavelength` says the same under the name it had first.
    v.band = define_variable("band", NC_DOUBLE, {dim("band")}, "nm", "laser wavelength of the band",
                             "sensor_band_central_radiation_wavelength");
    v.wavelength =
        define_variable("wavelength", NC_DOUBLE, {dim("band")}, "nm",
                        "laser wavelength of the band", "sensor_band_central_radiation_wavelength");
    v.band_name = define_variable("band_name", NC_STRING, {dim("band")}, "1", "name of the band");
    v.bin_time = define_variable("bin_time_ns", NC_DOUBLE, {dim("bin")}, "ns",
                                 "time of each bin centre after the return from range_m (two-way)");
    v.tx_time = define_variable("tx_time_ns", NC_DOUBLE, {dim("tx_bin")}, "ns",
                                "time of each transmitted pulse bin centre about the pulse peak");
    v.tx_waveform = define_variable("tx_waveform", NC_FLOAT, {dim("band"), dim("tx_bin")}, "W",
                                    "transmitted pulse power");
    put_text(v.tx_waveform, "tx_waveform", "gedi_name", "txwaveform");
    v.crs = define_crs();
    if (shape.orders > 0)
      v.order = define_variable("order", NC_INT, {dim("order")}, "1", "scattering order");
    // The coordinate of rh's last dimension, so that ds.rh.sel(percentile=98) reads as GEDI's
    // rh98.
    v.percentile = define_variable("percentile", NC_INT, {dim("percentile")}, "percent",
                                   "percentage of energy_tr counted up from signal end");
    return v;
  }

  // CF's grid mapping of geodetic coordinates on WGS 84, heights above the ellipsoid.
  int define_crs() const {
    const int varid = define_variable(kCrsVariable, NC_INT, {}, "1",
                                      "coordinate reference system: WGS 84 "
                                      "(EPSG:4979), heights above the ellipsoid");
    put_text(varid, kCrsVariable, "grid_mapping_name", "latitude_longitude");
    put_text(varid, kCrsVariable, "crs_wkt", kCrsWkt);
    put_text(varid, kCrsVariable, "geographic_crs_name", "WGS 84");
    put_text(varid, kCrsVariable, "horizontal_datum_name", "World Geodetic System 1984");
    put_text(varid, kCrsVariable, "reference_ellipsoid_name", "WGS 84");
    put_text(varid, kCrsVariable, "prime_meridian_name", "Greenwich");
    const std::pair<const char*, double> numbers[] = {{"semi_major_axis", 6378137.0},
                                                      {"inverse_flattening", 298.257223563},
                                                      {"longitude_of_prime_meridian", 0.0}};
    for (const auto& [name, value] : numbers) {
      check(nc_put_att_double(nc.id(), varid, name, NC_DOUBLE, 1, &value),
            std::string("attribute '") + name + "' of 'crs'");
    }
    return varid;
  }

  void put_flags(int varid, const char* variable, std::span<const unsigned char> values,
                 const char* meanings) const {
    check(nc_put_att_uchar(nc.id(), varid, "flag_values", NC_UBYTE, values.size(), values.data()),
          std::string("attribute 'flag_values' of '") + variable + "'");
    put_text(varid, variable, "flag_meanings", meanings);
  }

  // The few attributes beyond those of the table.
  void define_special_attributes() const {
    for (const DefinedVariable& variable : variables) {
      if (std::string_view(variable.def->name) == "time")
        put_text(variable.varid, "time", "calendar", "standard");
      if (std::string_view(variable.def->name) == "quality_flag") {
        const unsigned char values[] = {quality_invalid, quality_good};
        put_flags(variable.varid, "quality_flag", values, "not_valid valid");
      }
      if (std::string_view(variable.def->name) == "quality_reason") {
        const unsigned char values[] = {reason_none, reason_off_terrain, reason_nodata,
                                        reason_no_signal, reason_low_signal};
        put_flags(variable.varid, "quality_reason", values,
                  "none off_terrain nodata no_signal low_signal");
        put_text(variable.varid, "quality_reason", "comment",
                 "off_terrain: the beam's axis met no terrain (off the DEM, or into a nodata "
                 "hole); nodata: it met the terrain, but nodata or the DEM's edge lies within 3 "
                 "sigma of the beam; no_signal: no band's waveform rises above its threshold; "
                 "low_signal: no band's peak stands 8 noise sd above the noise. Values 5 and up "
                 "are kept for more reasons found in the waveform (saturated).");
      }
    }
  }

  void write_run_variables(const RunInfo& info, const RunVariables& v) const {
    const char* trajectory_id = "track";
    check(nc_put_var_string(nc.id(), v.trajectory, &trajectory_id),
          "writing variable 'trajectory'");
    std::vector<double> wavelengths;
    std::vector<const char*> names;
    for (const ProductBand& band : info.bands) {
      wavelengths.push_back(band.wavelength_nm);
      names.push_back(band.name.c_str());
    }
    check(nc_put_var_double(nc.id(), v.band, wavelengths.data()), "writing variable 'band'");
    check(nc_put_var_double(nc.id(), v.wavelength, wavelengths.data()),
          "writing variable 'wavelength'");
    check(nc_put_var_string(nc.id(), v.band_name, names.data()), "writing variable 'band_name'");
    check(nc_put_var_double(nc.id(), v.bin_time, info.bin_time_ns.data()),
          "writing variable 'bin_time_ns'");
    check(nc_put_var_double(nc.id(), v.tx_time, info.tx_time_ns.data()),
          "writing variable 'tx_time_ns'");
    std::vector<double> tx(shape.bands * tx_bins);
    const std::size_t tx_shape[] = {shape.bands, tx_bins};
    if (!has_shape(info.tx_waveform_W, tx_shape)) {
      fail("tx_waveform must be " + join_shape(tx_shape) + " (band x tx_bin), got " +
           describe_shape(info.tx_waveform_W));
    }
    copy_flat(info.tx_waveform_W, tx.data());
    check(nc_put_var_double(nc.id(), v.tx_waveform, tx.data()), "writing variable 'tx_waveform'");
    std::vector<int> percentiles;
    for (std::size_t k = 0; k < shape.length("percentile"); ++k)
      percentiles.push_back(static_cast<int>(k));
    check(nc_put_var_int(nc.id(), v.percentile, percentiles.data()),
          "writing variable 'percentile'");
    if (v.order >= 0) {
      std::vector<int> numbers;
      for (std::size_t o = 1; o <= shape.orders; ++o) numbers.push_back(static_cast<int>(o));
      check(nc_put_var_int(nc.id(), v.order, numbers.data()), "writing variable 'order'");
    }
  }

  void define(const RunInfo& info) {
    reproducible = info.created.reproducible;
    define_globals(info);
    define_dims();
    const RunVariables run_variables = define_run_variables();
    for (const ProductField& def : product_fields()) define_shot_variable(def);
    if (shape.photons) define_photon_count();
    define_special_attributes();
    open_chunks.resize(variables.size());
    check(nc_enddef(nc.id()), "ending definitions");
    write_run_variables(info, run_variables);
  }

  std::string writing(const char* name, std::size_t index, const ShotRecord& shot) const {
    return std::string("writing variable '") + name + "' of record " + std::to_string(index) +
           " (shot " + std::to_string(shot.shot_number) + ")";
  }

  // Every array of the record checked against its variable's shape before anything is held,
  // so that a refused record leaves the product as it was. An empty array keeps the fill: a
  // flagged shot may carry none.
  void check_shapes(std::size_t index, const ShotRecord& shot) const {
    for (const DefinedVariable& variable : variables) {
      std::visit(
          [&](auto field) {
            const auto& value = shot.*field;
            if constexpr (!std::is_arithmetic_v<std::remove_cvref_t<decltype(value)>>) {
              if (value.empty() && shot.quality_flag != quality_good) return;
              if (!has_shape(value, variable.shape)) {
                fail(writing(variable.def->name, index, shot) + ": expected " +
                     join_shape(variable.shape) + " values, got " + describe_shape(value));
              }
            }
          },
          variable.def->field);
    }
    check_ragged(index, shot);
  }

  // A record's photon events: as many of each ragged field, and none in a run without them.
  void check_ragged(std::size_t index, const ShotRecord& shot) const {
    for (const ProductField& def : product_fields()) {
      if (!def.ragged()) continue;
      const std::size_t n = ragged_size(def, shot), expected = shot.photon_time_ns.size();
      if (!shape.photons && n > 0)
        fail(writing(def.name, index, shot) + ": the run declared no photon events");
      if (n != expected)
        fail(writing(def.name, index, shot) + ": " + std::to_string(n) + " photons, photon_time " +
             std::to_string(expected));
    }
  }

  static std::size_t ragged_size(const ProductField& def, const ShotRecord& shot) {
    return std::visit(
        [&](auto field) -> std::size_t {
          const auto& value = shot.*field;
          if constexpr (std::is_arithmetic_v<std::remove_cvref_t<decltype(value)>>)
            return 0;
          else
            return value.size();
        },
        def.field);
  }

  // Record `index`'s photon events, appended along `photon` once every record before it has.
  void hold_ragged(std::size_t index, const ShotRecord& shot) {
    RaggedShot& events = waiting[index];
    for (const RaggedVariable& variable : ragged)
      std::visit(
          [&](auto field) {
            const auto& value = shot.*field;
            using T = std::remove_cvref_t<decltype(value)>;
            if constexpr (std::is_same_v<T, std::vector<double>> ||
                          std::is_same_v<T, std::vector<std::int32_t>>)
              events.emplace_back(value.begin(), value.end());
          },
          variable.def->field);
    for (auto next = waiting.find(next_ragged); next != waiting.end();
         next = waiting.find(next_ragged)) {
      put_ragged(next_ragged, next->second);
      waiting.erase(next);
      ++next_ragged;
    }
  }

  void put_ragged(std::size_t index, const RaggedShot& events) {
    const std::size_t count = events.empty() ? 0 : events.front().size();
    for (std::size_t i = 0; i < ragged.size() && count > 0; ++i)
      check(
          nc_put_vara_double(nc.id(), ragged[i].varid, &photons_written, &count, events[i].data()),
          std::string("writing variable '") + ragged[i].def->name + "' of record " +
              std::to_string(index));
    const int n = static_cast<int>(count);
    check(nc_put_var1_int(nc.id(), photon_count, &index, &n),
          "writing variable 'photon_count' of record " + std::to_string(index));
    photons_written += count;
  }

  // The buffer of the chunk that holds record `index` of variable `i`, begun full of fill.
  ChunkBuffer& chunk_of(std::size_t i, std::size_t index) {
    const DefinedVariable& variable = variables[i];
    const std::size_t chunk = index / variable.chunk_shots;
    auto [it, begun] = open_chunks[i].try_emplace(chunk);
    ChunkBuffer& buffer = it->second;
    if (begun) {
      buffer.first = chunk * variable.chunk_shots;
      buffer.count = std::min(variable.chunk_shots, shots - buffer.first);
      if (variable.held == Held::int64s) buffer.int64s.assign(buffer.count, 0);
      if (variable.held == Held::bytes) buffer.bytes.assign(buffer.count, 0);
      if (variable.held == Held::reals)
        buffer.reals.assign(buffer.count * variable.per_shot, variable.fill);
    }
    return buffer;
  }

  // Writes a complete chunk in one call.
  void put_chunk(const DefinedVariable& variable, const ChunkBuffer& buffer) const {
    std::vector<std::size_t> start(variable.shape.size() + 1, 0);
    std::vector<std::size_t> count = {buffer.count};
    start[0] = buffer.first;
    count.insert(count.end(), variable.shape.begin(), variable.shape.end());
    int status = NC_NOERR;
    const int id = nc.id();
    if (variable.held == Held::int64s)
      status = nc_put_vara_longlong(id, variable.varid, start.data(), count.data(),
                                    buffer.int64s.data());
    else if (variable.held == Held::bytes)
      status =
          nc_put_vara_uchar(id, variable.varid, start.data(), count.data(), buffer.bytes.data());
    else
      status =
          nc_put_vara_double(id, variable.varid, start.data(), count.data(), buffer.reals.data());
    check(status, std::string("writing variable '") + variable.def->name + "' of records " +
                      std::to_string(buffer.first) + " to " +
                      std::to_string(buffer.first + buffer.count - 1));
  }

  // Record `index`'s value of variable `i` into its chunk's buffer; a chunk whose records
  // have all come is written.
  void hold_value(std::size_t i, std::size_t index, const ShotRecord& shot) {
    const DefinedVariable& variable = variables[i];
    ChunkBuffer& buffer = chunk_of(i, index);
    const std::size_t slot = index - buffer.first;
    std::visit(
        [&](auto field) {
          const auto& value = shot.*field;
          using T = std::remove_cvref_t<decltype(value)>;
          if constexpr (std::is_same_v<T, std::int64_t>) {
            buffer.int64s[slot] = value;
          } else if constexpr (std::is_same_v<T, std::uint8_t>) {
            buffer.bytes[slot] = value;
          } else if constexpr (std::is_same_v<T, double>) {
            buffer.reals[slot] = value;
          } else if (!value.empty()) {
            copy_flat(value, buffer.reals.data() + slot * variable.per_shot);
          }
        },
        variable.def->field);
    if (++buffer.filled < buffer.count) return;
    put_chunk(variable, buffer);
    open_chunks[i].erase(index / variable.chunk_shots);
  }

  void write_record(std::size_t index, const ShotRecord& shot) {
    check_shapes(index, shot);
    broken = true;  // until every value is held: a failed chunk write loses records taken
    for (std::size_t i = 0; i < variables.size(); ++i) hold_value(i, index, shot);
    if (shape.photons) hold_ragged(index, shot);
    broken = false;
    time_s.add(shot.time_s);
    lat_deg.add(shot.lat_deg);
    lon_deg.add(shot.lon_deg);
    elev_m.add(shot.elev_m);
  }

  void put_double(const char* name, double value) const {
    check(nc_put_att_double(nc.id(), NC_GLOBAL, name, NC_DOUBLE, 1, &value),
          std::string("global attribute '") + name + "'");
  }

  // ACDD's time and place of the data, from the records; none where no record has a value.
  void define_coverage() const {
    if (!time_s.empty()) {
      put_text(NC_GLOBAL, "global", "time_coverage_start",
               format_iso8601_utc_microseconds(time_s.min));
      put_text(NC_GLOBAL, "global", "time_coverage_end",
               format_iso8601_utc_microseconds(time_s.max));
    }
    if (!lat_deg.empty()) {
      put_double("geospatial_lat_min", lat_deg.min);
      put_double("geospatial_lat_max", lat_deg.max);
      put_text(NC_GLOBAL, "global", "geospatial_lat_units", "degrees_north");
    }
    if (!lon_deg.empty()) {
      put_double("geospatial_lon_min", lon_deg.min);
      put_double("geospatial_lon_max", lon_deg.max);
      put_text(NC_GLOBAL, "global", "geospatial_lon_units", "degrees_east");
    }
    if (!elev_m.empty()) {
      put_double("geospatial_vertical_min", elev_m.min);
      put_double("geospatial_vertical_max", elev_m.max);
      put_text(NC_GLOBAL, "global", "geospatial_vertical_units", "m");
      put_text(NC_GLOBAL, "global", "geospatial_vertical_positive", "up");
    }
  }
};

NetcdfWriter::NetcdfWriter(std::filesystem::path final_path, const RunInfo& info)
    : final_path_(std::move(final_path)), impl_(std::make_unique<Impl>(final_path_, info.shots)) {
  Impl& impl = *impl_;
  if (info.shots < 1)
    impl.fail("a product needs at least one shot, got " + std::to_string(info.shots));
  if (info.bands.empty()) impl.fail("a product needs at least one band");
  if (info.bin_time_ns.empty() || info.tx_time_ns.empty())
    impl.fail("a product needs bins and tx bins");
  if (info.orders < 0) impl.fail("orders must be >= 0, got " + std::to_string(info.orders));
  impl.shots = static_cast<std::size_t>(info.shots);
  impl.shape = {info.bands.size(), info.bin_time_ns.size(), static_cast<std::size_t>(info.orders),
                info.photon_events, info.atmosphere};
  impl.tx_bins = info.tx_time_ns.size();

  const std::string part = impl.file.part_path().string();
  // libnetcdf is called under its lock only: another run in this process (two Python threads)
  // may be writing, or reading a netCDF DEM, meanwhile.
  const LibraryLock lock;
  try {
    impl.check(nc_create(part.c_str(), NC_NETCDF4 | NC_CLOBBER, impl.nc.out()),
               "cannot create " + part);
    impl.define(info);
  } catch (...) {
    impl_.reset();  // the half-defined file is aborted here, still under the lock
    throw;
  }
}

NetcdfWriter::~NetcdfWriter() {
  // An unfinished product's id is aborted as Impl goes: under the library's lock too.
  const LibraryLock lock;
  impl_.reset();
}

NetcdfWriter::Impl& NetcdfWriter::impl() {
  if (!impl_) throw run_error(final_path_.string(), "the product was aborted");
  return *impl_;
}

void NetcdfWriter::write(std::int64_t index, const ShotRecord& shot) {
  const LibraryLock lock;  // a DEM may be read meanwhile
  Impl& impl = this->impl();
  impl.ledger.check_write(index);
  if (impl.broken) impl.fail("a write failed before: the product lacks records");
  impl.write_record(static_cast<std::size_t>(index), shot);
  impl.ledger.taken(index);
}

void NetcdfWriter::finish(const RunStats& stats) {
  const LibraryLock lock;
  Impl& impl = this->impl();
  if (impl.broken && !impl.ledger.finished())
    impl.fail("a write failed before: the product lacks records");
  impl.ledger.check_finish();
  const int id = impl.nc.id();
  impl.check(nc_redef(id), "reopening definitions");
  impl.define_coverage();
  const long long ray_queries = stats.ray_queries;
  const long long shots_flagged = stats.shots_flagged;
  impl.check(nc_put_att_longlong(id, NC_GLOBAL, "stats_ray_queries", NC_INT64, 1, &ray_queries),
             "global attribute 'stats_ray_queries'");
  if (!impl.reproducible)
    impl.check(nc_put_att_double(id, NC_GLOBAL, "stats_wall_s", NC_DOUBLE, 1, &stats.wall_s),
               "global attribute 'stats_wall_s'");
  impl.check(nc_put_att_longlong(id, NC_GLOBAL, "stats_shots_flagged", NC_INT64, 1, &shots_flagged),
             "global attribute 'stats_shots_flagged'");
  impl.check(nc_enddef(id), "ending definitions");
  // Everything is written before the close: a close whose flush fails crashes in HDF5, a
  // failed sync only says so.
  impl.check(nc_sync(id), "writing " + impl.file.part_path().string());
  impl.check(impl.nc.close(), "closing " + impl.file.part_path().string());
  impl.file.commit();
  impl.ledger.finish();
}

void NetcdfWriter::abort() noexcept {
  // A finished product stays: only an unfinished one has a .part to give up.
  const LibraryLock lock;
  if (impl_ && !impl_->ledger.finished()) impl_.reset();
}

namespace {

// shots.nc, first of a run's products.
const Registration<ProductWriter> netcdf_writer(
    "shots.nc", 10, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!c.settings.netcdf) return nullptr;
      return std::make_unique<NetcdfWriter>(c.out_dir / "shots.nc", c.info);
    });

}  // namespace

}  // namespace glaswave
