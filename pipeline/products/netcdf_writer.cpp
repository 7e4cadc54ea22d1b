// shots.nc through the netCDF-C API. The per-shot variables are one table (kShotVariables):
// each row names a ShotRecord member and its metadata, and definition, chunking and writing
// are driven by the table, so a new product variable is one row.
#include "pipeline/products/netcdf_writer.hpp"

#include <netcdf.h>

#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"

namespace glaswave {
namespace {

constexpr std::size_t kGaussians = 6;  // PRODUCT.md: decomposition into up to 6 Gaussians
constexpr std::size_t kPercentiles = 101;  // rh0 .. rh100
// Level 2 already takes most of what deflate can from waveforms (long runs of zero power
// before and after the return); higher levels cost time for little more.
constexpr int kDeflateLevel = 2;
constexpr const char* kShotCoordinates = "time lat lon";

// The ShotRecord member a per-shot variable comes from. Nested vectors are [band][...].
using Int64Field = std::int64_t ShotRecord::*;
using UByteField = std::uint8_t ShotRecord::*;
using DoubleField = double ShotRecord::*;
using BandField = std::vector<double> ShotRecord::*;
using BandIntField = std::vector<std::int32_t> ShotRecord::*;
using BandArrayField = std::vector<std::vector<double>> ShotRecord::*;
using BandArray2Field = std::vector<std::vector<std::vector<double>>> ShotRecord::*;
using Field =
    std::variant<Int64Field, UByteField, DoubleField, BandField, BandIntField, BandArrayField,
                 BandArray2Field>;

struct ShotVariable {
  const char* name;
  nc_type type;  // storage type; values are converted by the netCDF library
  Field field;
  const char* units;
  const char* long_name;
  const char* standard_name = nullptr;  // only where CF has one
  // Dimensions after (shot, band) for array fields. A variable whose dimensions this run
  // lacks (`order` without per-order output) is left out of the file.
  std::array<const char*, 2> inner_dims = {nullptr, nullptr};
  const char* comment = nullptr;  // how a derived quantity is defined
};

// Spacecraft latitude/longitude carry no standard_name on purpose: tools that find the
// geolocation by standard_name must find the footprint, not the spacecraft.
const ShotVariable kShotVariables[] = {
    {"shot_number", NC_INT64, &ShotRecord::shot_number, "1", "shot number in the track, from 0"},
    {"time", NC_DOUBLE, &ShotRecord::time_s, "seconds since 2000-01-01 12:00:00",
     "time of the shot (seconds since the GLAS epoch)", "time"},
    {"lat", NC_DOUBLE, &ShotRecord::lat_deg, "degrees_north",
     "latitude of the footprint centre on the terrain", "latitude"},
    {"lon", NC_DOUBLE, &ShotRecord::lon_deg, "degrees_east",
     "longitude of the footprint centre on the terrain", "longitude"},
    {"elev", NC_DOUBLE, &ShotRecord::elev_m, "m",
     "elevation of the footprint centre above the WGS84 ellipsoid",
     "height_above_reference_ellipsoid"},
    {"sc_lat", NC_DOUBLE, &ShotRecord::sc_lat_deg, "degrees_north", "latitude of the spacecraft"},
    {"sc_lon", NC_DOUBLE, &ShotRecord::sc_lon_deg, "degrees_east", "longitude of the spacecraft"},
    {"sc_alt", NC_DOUBLE, &ShotRecord::sc_alt_m, "m",
     "altitude of the spacecraft above the WGS84 ellipsoid"},
    {"off_nadir_deg", NC_DOUBLE, &ShotRecord::off_nadir_deg, "degree",
     "angle between the laser pointing and geodetic nadir"},
    {"range_m", NC_DOUBLE, &ShotRecord::range_m, "m",
     "range from the spacecraft to the footprint centre"},
    {"slope_deg", NC_DOUBLE, &ShotRecord::slope_deg, "degree", "terrain slope over the footprint"},
    {"aspect_deg", NC_DOUBLE, &ShotRecord::aspect_deg, "degree",
     "terrain aspect over the footprint (direction the slope faces, clockwise from north)"},
    {"elev_bin0", NC_DOUBLE, &ShotRecord::elev_bin0_m, "m",
     "elevation of the first waveform bin (nearest the spacecraft) above the WGS84 ellipsoid"},
    {"elev_lastbin", NC_DOUBLE, &ShotRecord::elev_lastbin_m, "m",
     "elevation of the last waveform bin above the WGS84 ellipsoid"},
    {"quality_flag", NC_UBYTE, &ShotRecord::quality_flag, "1", "quality flag of the shot"},
    {"rx_waveform", NC_FLOAT, &ShotRecord::rx_waveform_W, "W", "received power", nullptr, {"bin"}},
    {"rx_waveform_canopy",
     NC_FLOAT,
     &ShotRecord::rx_waveform_canopy_W,
     "W",
     "received power whose last scattering was on vegetation",
     nullptr,
     {"bin"}},
    {"rx_waveform_ground",
     NC_FLOAT,
     &ShotRecord::rx_waveform_ground_W,
     "W",
     "received power whose last scattering was on the ground",
     nullptr,
     {"bin"}},
    {"rx_waveform_order",
     NC_FLOAT,
     &ShotRecord::rx_waveform_order_W,
     "W",
     "received power by scattering order",
     nullptr,
     {"order", "bin"}},
    {"rx_energy", NC_DOUBLE, &ShotRecord::rx_energy_J, "J",
     "received energy (integral of rx_waveform)"},
    {"rx_energy_canopy", NC_DOUBLE, &ShotRecord::rx_energy_canopy_J, "J",
     "received energy whose last scattering was on vegetation (integral of rx_waveform_canopy)"},
    {"rx_energy_ground", NC_DOUBLE, &ShotRecord::rx_energy_ground_J, "J",
     "received energy whose last scattering was on the ground (integral of rx_waveform_ground)"},
    {"reflectance", NC_DOUBLE, &ShotRecord::reflectance, "1",
     "surface reflectance from the waveform, pi E_rec R^2 / (E_trans A_t T_atm) "
     "(North et al. 2010, eq. 1)"},
    // Waveform processing (pipeline/products/waveform_metrics.hpp states the rules).
    {"energy_tr", NC_DOUBLE, &ShotRecord::energy_tr_J, "J",
     "total return: energy above the noise between signal begin and end (seed TR)", nullptr,
     {}, "energy_tr = energy_cr + energy_gr"},
    {"energy_cr", NC_DOUBLE, &ShotRecord::energy_cr_J, "J",
     "canopy return: the part of energy_tr above the canopy/ground split (seed CR)", nullptr, {},
     "split 4 sigma of the lowest Gaussian above its centre, or lower where the other Gaussians "
     "outweigh it"},
    {"energy_gr", NC_DOUBLE, &ShotRecord::energy_gr_J, "J",
     "ground return: the part of energy_tr below the canopy/ground split (seed GR)"},
    {"waveform_index", NC_DOUBLE, &ShotRecord::waveform_index, "1",
     "waveform index (CR - GR) / (CR + GR) (North et al. 2010, eq. 3)"},
    {"sig_begin_m", NC_DOUBLE, &ShotRecord::sig_begin_m, "m",
     "elevation of signal begin: first crossing of the threshold by the smoothed waveform",
     "height_above_reference_ellipsoid", {},
     "threshold = noise mean + max(4 noise sd, 0.01 (peak - noise mean)) on the waveform "
     "smoothed with the pulse's width"},
    {"sig_end_m", NC_DOUBLE, &ShotRecord::sig_end_m, "m",
     "elevation of signal end: last crossing of the threshold by the smoothed waveform",
     "height_above_reference_ellipsoid"},
    {"centroid_m", NC_DOUBLE, &ShotRecord::centroid_m, "m",
     "elevation of the waveform's centroid between signal begin and end",
     "height_above_reference_ellipsoid"},
    {"n_peaks", NC_INT, &ShotRecord::n_peaks, "1", "number of Gaussians fitted to the waveform"},
    {"gauss_amp", NC_DOUBLE, &ShotRecord::gauss_amp_W, "W", "amplitude of each fitted Gaussian",
     nullptr, {"gaussian"}},
    {"gauss_center_m", NC_DOUBLE, &ShotRecord::gauss_center_m, "m",
     "elevation of the centre of each fitted Gaussian (in waveform order, highest first)",
     "height_above_reference_ellipsoid", {"gaussian"}},
    {"gauss_sigma_ns", NC_DOUBLE, &ShotRecord::gauss_sigma_ns, "ns",
     "standard deviation of each fitted Gaussian", nullptr, {"gaussian"}},
    {"gauss_area", NC_DOUBLE, &ShotRecord::gauss_area_J, "J",
     "energy of each fitted Gaussian (its integral)", nullptr, {"gaussian"}},
    {"ground_elev_est", NC_DOUBLE, &ShotRecord::ground_elev_est_m, "m",
     "ground elevation estimated from the waveform: centre of the lowest Gaussian",
     "height_above_reference_ellipsoid"},
    {"canopy_height_est", NC_DOUBLE, &ShotRecord::canopy_height_est_m, "m",
     "canopy height estimated from the waveform: signal begin above ground_elev_est",
     "canopy_height", {},
     "as GLA14: it includes the pulse's own rise to the threshold (about 3.2 m over bare ground "
     "for a 5 ns pulse without noise); equal to rh100"},
    {"rh", NC_FLOAT, &ShotRecord::rh_m, "m",
     "relative height above ground_elev_est at which the energy counted up from signal end "
     "reaches percentile % of energy_tr (GEDI L2A)",
     nullptr, {"percentile"}},
    {"cover_true", NC_DOUBLE, &ShotRecord::cover_true, "1",
     "crown cover over the footprint, weighted by the beam (simulation truth)",
     "vegetation_area_fraction"},
    {"pai_true", NC_DOUBLE, &ShotRecord::pai_true, "1",
     "plant area index over the footprint, weighted by the beam (simulation truth)"},
    {"canopy_height_true", NC_DOUBLE, &ShotRecord::canopy_height_true_m, "m",
     "highest vegetation above the ground over the footprint (simulation truth)",
     "canopy_height"},
};

// Copies a [band][...] nested vector into `out` in C order when its shape is `shape`.
bool flatten(const std::vector<double>& values, std::span<const std::size_t> shape,
             std::vector<double>& out) {
  if (shape.size() != 1 || values.size() != shape[0]) return false;
  out.insert(out.end(), values.begin(), values.end());
  return true;
}
bool flatten(const std::vector<std::int32_t>& values, std::span<const std::size_t> shape,
             std::vector<double>& out) {
  if (shape.size() != 1 || values.size() != shape[0]) return false;
  out.insert(out.end(), values.begin(), values.end());  // exact: every int32 is a double
  return true;
}
template <class T>
bool flatten(const std::vector<std::vector<T>>& values, std::span<const std::size_t> shape,
             std::vector<double>& out) {
  if (shape.empty() || values.size() != shape[0]) return false;
  for (const auto& inner : values) {
    if (!flatten(inner, shape.subspan(1), out)) return false;
  }
  return true;
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

}  // namespace

struct NetcdfWriter::Impl {
  struct DefinedVariable {
    const ShotVariable* def;
    int varid;
    std::vector<std::size_t> shape;  // lengths after the shot dimension
  };

  explicit Impl(std::filesystem::path final_path) : file(std::move(final_path)) {}

  // Declared before the handle so that it is destroyed after it: the file is closed before
  // an unfinished .part is removed.
  AtomicFile file;
  NcHandle nc;
  std::size_t shots = 0, bands = 0, bins = 0, tx_bins = 0, orders = 0;
  struct Dimension {
    std::string name;
    int id;
    std::size_t length;
  };
  std::vector<Dimension> dims;
  std::vector<DefinedVariable> variables;
  std::vector<bool> written;
  bool finished = false;

  [[noreturn]] void fail(const std::string& message) const {
    throw run_error(file.final_path().string(), message);
  }

  void check(int status, const std::string& what) const {
    if (status != NC_NOERR) fail(what + ": " + nc_strerror(status));
  }

  const Dimension* find_dim(const char* name) const {
    for (const Dimension& dimension : dims) {
      if (dimension.name == name) return &dimension;
    }
    return nullptr;
  }
  int dim(const char* name) const { return find_dim(name)->id; }

  void define_dim(const char* name, std::size_t length) {
    int id = -1;
    check(nc_def_dim(nc.id(), name, length, &id), std::string("defining dimension '") + name + "'");
    dims.push_back({name, id, length});
  }

  void put_text(int varid, const char* variable, const char* name, const std::string& value) const {
    check(nc_put_att_text(nc.id(), varid, name, value.size(), value.c_str()),
          std::string("attribute '") + name + "' of '" + variable + "'");
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
    if (standard_name != nullptr) put_text(varid, name, "standard_name", standard_name);
    return varid;
  }

  void define_shot_variable(const ShotVariable& def) {
    std::vector<int> dimids = {dim("shot")};
    std::vector<std::size_t> shape;
    const bool scalar = std::holds_alternative<Int64Field>(def.field) ||
                        std::holds_alternative<UByteField>(def.field) ||
                        std::holds_alternative<DoubleField>(def.field);
    if (!scalar) {
      dimids.push_back(dim("band"));
      shape.push_back(bands);
      for (const char* inner : def.inner_dims) {
        if (inner == nullptr) continue;
        const Dimension* dimension = find_dim(inner);
        if (dimension == nullptr) return;  // this run has no such dimension
        dimids.push_back(dimension->id);
        shape.push_back(dimension->length);
      }
    }
    const std::size_t expected_rank = std::holds_alternative<BandArray2Field>(def.field)  ? 3
                                      : std::holds_alternative<BandArrayField>(def.field) ? 2
                                      : scalar                                            ? 0
                                                                                          : 1;
    if (shape.size() != expected_rank) {
      fail(std::string("internal: variable '") + def.name +
           "' has dimensions that do not match its field");
    }

    const int varid =
        define_variable(def.name, def.type, dimids, def.units, def.long_name, def.standard_name);
    if (def.comment != nullptr) put_text(varid, def.name, "comment", def.comment);
    const std::string what = std::string("variable '") + def.name + "'";
    if (def.type == NC_FLOAT) {
      const float fill = std::numeric_limits<float>::quiet_NaN();
      check(nc_put_att_float(nc.id(), varid, "_FillValue", NC_FLOAT, 1, &fill),
            what + " _FillValue");
    } else if (def.type == NC_DOUBLE) {
      const double fill = std::numeric_limits<double>::quiet_NaN();
      check(nc_put_att_double(nc.id(), varid, "_FillValue", NC_DOUBLE, 1, &fill),
            what + " _FillValue");
    }
    // Integer variables get no _FillValue: finish() refuses a product with a record never
    // written, so they hold no fill, and xarray would turn a masked integer into float.
    if (std::string_view(def.name) != "time" && std::string_view(def.name) != "lat" &&
        std::string_view(def.name) != "lon") {
      put_text(varid, def.name, "coordinates", kShotCoordinates);
    }
    // Arrays over bins are most of the file: one shot per chunk makes each write() fill whole
    // chunks (no read-modify-write, any order) and lets them be compressed.
    if (dimids.size() >= 3) {
      std::vector<std::size_t> chunks = {1};
      chunks.insert(chunks.end(), shape.begin(), shape.end());
      check(nc_def_var_chunking(nc.id(), varid, NC_CHUNKED, chunks.data()), what + " chunking");
      check(nc_def_var_deflate(nc.id(), varid, 1, 1, kDeflateLevel), what + " compression");
    }
    variables.push_back({&def, varid, std::move(shape)});
  }

  void define(const RunInfo& info) {
    const std::string title = "glaswave simulated satellite waveform lidar shots";
    const std::string source = std::string("glaswave ") + GLASWAVE_VERSION;
    put_text(NC_GLOBAL, "global", "Conventions", "CF-1.10");
    put_text(NC_GLOBAL, "global", "featureType", "trajectory");
    put_text(NC_GLOBAL, "global", "title", title);
    put_text(NC_GLOBAL, "global", "history", info.command_line);
    put_text(NC_GLOBAL, "global", "source", source);
    put_text(
        NC_GLOBAL, "global", "references",
        "North et al. (2010), A Monte Carlo radiative transfer model of satellite waveform lidar");
    put_text(NC_GLOBAL, "global", "config", info.config_json);
    if (!info.vertical_datum.empty()) put_text(NC_GLOBAL, "global", "vertical_datum", info.vertical_datum);
    const unsigned long long seed = info.seed;
    check(nc_put_att_ulonglong(nc.id(), NC_GLOBAL, "seed", NC_UINT64, 1, &seed),
          "global attribute 'seed'");

    define_dim("shot", shots);
    define_dim("band", bands);
    define_dim("bin", bins);
    define_dim("tx_bin", tx_bins);
    define_dim("gaussian", kGaussians);
    define_dim("percentile", kPercentiles);
    if (orders > 0) define_dim("order", orders);

    // CF: a single trajectory is identified by a scalar variable with cf_role trajectory_id.
    const int trajectory =
        define_variable("trajectory", NC_STRING, {}, "1", "trajectory (the simulated track)");
    put_text(trajectory, "trajectory", "cf_role", "trajectory_id");
    const int wavelength = define_variable("wavelength", NC_DOUBLE, {dim("band")}, "nm",
                                           "laser wavelength of the band");
    const int band_name =
        define_variable("band_name", NC_STRING, {dim("band")}, "1", "name of the band");
    const int bin_time =
        define_variable("bin_time_ns", NC_DOUBLE, {dim("bin")}, "ns",
                        "time of each bin centre after the return from range_m (two-way)");
    const int tx_time =
        define_variable("tx_time_ns", NC_DOUBLE, {dim("tx_bin")}, "ns",
                        "time of each transmitted pulse bin centre about the pulse peak");
    const int tx_waveform = define_variable("tx_waveform", NC_FLOAT, {dim("band"), dim("tx_bin")},
                                            "W", "transmitted pulse power");
    const int order =
        orders > 0 ? define_variable("order", NC_INT, {dim("order")}, "1", "scattering order") : -1;
    // The coordinate of rh's last dimension, so that ds.rh.sel(percentile=98) reads as GEDI's rh98.
    const int percentile = define_variable("percentile", NC_INT, {dim("percentile")}, "percent",
                                           "percentage of energy_tr counted up from signal end");

    for (const ShotVariable& def : kShotVariables) define_shot_variable(def);
    // The few attributes beyond the common ones.
    for (const DefinedVariable& variable : variables) {
      if (std::string_view(variable.def->name) == "time")
        put_text(variable.varid, "time", "calendar", "standard");
      if (std::string_view(variable.def->name) == "quality_flag") {
        const unsigned char values[] = {quality_good, quality_no_terrain};
        check(nc_put_att_uchar(nc.id(), variable.varid, "flag_values", NC_UBYTE, 2, values),
              "attribute 'flag_values' of 'quality_flag'");
        put_text(variable.varid, "quality_flag", "flag_meanings", "good no_terrain");
      }
    }

    check(nc_enddef(nc.id()), "ending definitions");

    const char* trajectory_id = "track";
    check(nc_put_var_string(nc.id(), trajectory, &trajectory_id), "writing variable 'trajectory'");
    std::vector<double> wavelengths;
    std::vector<const char*> names;
    for (const ProductBand& band : info.bands) {
      wavelengths.push_back(band.wavelength_nm);
      names.push_back(band.name.c_str());
    }
    check(nc_put_var_double(nc.id(), wavelength, wavelengths.data()),
          "writing variable 'wavelength'");
    check(nc_put_var_string(nc.id(), band_name, names.data()), "writing variable 'band_name'");
    check(nc_put_var_double(nc.id(), bin_time, info.bin_time_ns.data()),
          "writing variable 'bin_time_ns'");
    check(nc_put_var_double(nc.id(), tx_time, info.tx_time_ns.data()),
          "writing variable 'tx_time_ns'");
    std::vector<double> tx;
    const std::size_t tx_shape[] = {bands, tx_bins};
    if (!flatten(info.tx_waveform_W, tx_shape, tx)) {
      fail("tx_waveform must be " + join_shape(tx_shape) + " (band x tx_bin), got " +
           describe_shape(info.tx_waveform_W));
    }
    check(nc_put_var_double(nc.id(), tx_waveform, tx.data()), "writing variable 'tx_waveform'");
    std::vector<int> percentiles;
    for (std::size_t k = 0; k < kPercentiles; ++k) percentiles.push_back(static_cast<int>(k));
    check(nc_put_var_int(nc.id(), percentile, percentiles.data()), "writing variable 'percentile'");
    if (order >= 0) {
      std::vector<int> numbers;
      for (std::size_t o = 1; o <= orders; ++o) numbers.push_back(static_cast<int>(o));
      check(nc_put_var_int(nc.id(), order, numbers.data()), "writing variable 'order'");
    }
  }

  std::string writing(const char* name, std::size_t index, const ShotRecord& shot) const {
    return std::string("writing variable '") + name + "' of record " + std::to_string(index) +
           " (shot " + std::to_string(shot.shot_number) + ")";
  }

  // Every array is checked before anything is written, so a refused record leaves the file
  // as it was.
  void write_record(std::size_t index, const ShotRecord& shot) {
    std::vector<std::vector<double>> arrays(variables.size());  // C order; empty keeps the fill
    for (std::size_t i = 0; i < variables.size(); ++i) {
      std::visit(
          [&](auto field) {
            const auto& value = shot.*field;
            if constexpr (!std::is_arithmetic_v<std::remove_cvref_t<decltype(value)>>) {
              // A flagged shot may carry no arrays: its record keeps the fill value.
              if (value.empty() && shot.quality_flag != quality_good) return;
              if (!flatten(value, variables[i].shape, arrays[i])) {
                fail(writing(variables[i].def->name, index, shot) + ": expected " +
                     join_shape(variables[i].shape) + " values, got " + describe_shape(value));
              }
            }
          },
          variables[i].def->field);
    }
    for (std::size_t i = 0; i < variables.size(); ++i) {
      const DefinedVariable& variable = variables[i];
      std::visit(
          [&](auto field) {
            const auto& value = shot.*field;
            using T = std::remove_cvref_t<decltype(value)>;
            int status = NC_NOERR;
            if constexpr (std::is_same_v<T, std::int64_t>) {
              const long long v = value;
              status = nc_put_var1_longlong(nc.id(), variable.varid, &index, &v);
            } else if constexpr (std::is_same_v<T, std::uint8_t>) {
              const unsigned char v = value;
              status = nc_put_var1_uchar(nc.id(), variable.varid, &index, &v);
            } else if constexpr (std::is_same_v<T, double>) {
              status = nc_put_var1_double(nc.id(), variable.varid, &index, &value);
            } else {
              if (arrays[i].empty()) return;
              std::vector<std::size_t> start(variable.shape.size() + 1, 0);
              std::vector<std::size_t> count = {1};
              start[0] = index;
              count.insert(count.end(), variable.shape.begin(), variable.shape.end());
              status = nc_put_vara_double(nc.id(), variable.varid, start.data(), count.data(),
                                          arrays[i].data());
            }
            check(status, writing(variable.def->name, index, shot));
          },
          variable.def->field);
    }
  }
};

NetcdfWriter::NetcdfWriter(std::filesystem::path final_path, const RunInfo& info)
    : impl_(std::make_unique<Impl>(std::move(final_path))) {
  Impl& impl = *impl_;
  if (info.shots < 1)
    impl.fail("a product needs at least one shot, got " + std::to_string(info.shots));
  if (info.bands.empty()) impl.fail("a product needs at least one band");
  if (info.bin_time_ns.empty() || info.tx_time_ns.empty())
    impl.fail("a product needs bins and tx bins");
  if (info.orders < 0) impl.fail("orders must be >= 0, got " + std::to_string(info.orders));
  impl.shots = static_cast<std::size_t>(info.shots);
  impl.bands = info.bands.size();
  impl.bins = info.bin_time_ns.size();
  impl.tx_bins = info.tx_time_ns.size();
  impl.orders = static_cast<std::size_t>(info.orders);
  impl.written.assign(impl.shots, false);

  const std::string part = impl.file.part_path().string();
  impl.check(nc_create(part.c_str(), NC_NETCDF4 | NC_CLOBBER, impl.nc.out()),
             "cannot create " + part);
  impl.define(info);
}

NetcdfWriter::~NetcdfWriter() = default;

void NetcdfWriter::write(std::int64_t index, const ShotRecord& shot) {
  Impl& impl = *impl_;
  if (impl.finished) impl.fail("write after finish");
  if (index < 0 || index >= static_cast<std::int64_t>(impl.shots)) {
    impl.fail("record index " + std::to_string(index) + " outside [0, " +
              std::to_string(impl.shots) + ")");
  }
  const auto record = static_cast<std::size_t>(index);
  if (impl.written[record]) impl.fail("record " + std::to_string(index) + " written twice");
  impl.write_record(record, shot);
  impl.written[record] = true;
}

void NetcdfWriter::finish(const RunStats& stats) {
  Impl& impl = *impl_;
  if (impl.finished) impl.fail("finished twice");
  for (std::size_t i = 0; i < impl.written.size(); ++i) {
    if (!impl.written[i]) impl.fail("record " + std::to_string(i) + " was never written");
  }
  const int id = impl.nc.id();
  impl.check(nc_redef(id), "reopening definitions");
  const long long ray_queries = stats.ray_queries;
  const long long shots_flagged = stats.shots_flagged;
  impl.check(nc_put_att_longlong(id, NC_GLOBAL, "stats_ray_queries", NC_INT64, 1, &ray_queries),
             "global attribute 'stats_ray_queries'");
  impl.check(nc_put_att_double(id, NC_GLOBAL, "stats_wall_s", NC_DOUBLE, 1, &stats.wall_s),
             "global attribute 'stats_wall_s'");
  impl.check(nc_put_att_longlong(id, NC_GLOBAL, "stats_shots_flagged", NC_INT64, 1, &shots_flagged),
             "global attribute 'stats_shots_flagged'");
  impl.check(nc_enddef(id), "ending definitions");
  impl.check(impl.nc.close(), "closing " + impl.file.part_path().string());
  impl.file.commit();
  impl.finished = true;
}

}  // namespace glaswave
