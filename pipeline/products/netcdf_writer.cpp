// shots.nc through the netCDF-C API. The per-shot variables are the rows of the product field
// table (product_fields.hpp): definition, attributes, chunking and writing are driven by it,
// so a new product variable is one row there. The variables shared by every shot (bands, bin
// times, the transmitted pulse) are defined here.
#include "pipeline/products/netcdf_writer.hpp"

#include <netcdf.h>

#include <cmath>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace {

// Level 2 already takes most of what deflate can from waveforms (long runs of zero power
// before and after the return); higher levels cost time for little more.
constexpr int kDeflateLevel = 2;
// The coordinates of a trajectory; they carry no `coordinates` attribute themselves.
constexpr const char* kShotCoordinates = "time lat lon";

bool is_shot_coordinate(std::string_view name) {
  return name == "time" || name == "lat" || name == "lon";
}

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
    const ProductField* def;
    int varid;
    std::vector<std::size_t> shape;  // lengths after the shot dimension
  };
  // The variables shared by every shot, written once the definitions end.
  struct RunVariables {
    int trajectory = -1, wavelength = -1, band_name = -1, bin_time = -1, tx_time = -1,
        tx_waveform = -1, order = -1, percentile = -1;
  };

  explicit Impl(std::filesystem::path final_path) : file(std::move(final_path)) {}

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
  std::vector<bool> written;
  bool finished = false;

  [[noreturn]] void fail(const std::string& message) const {
    throw run_error(file.final_path().string(), message);
  }

  void check(int status, const std::string& what) const {
    if (status != NC_NOERR) fail(what + ": " + nc_strerror(status));
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

  // Arrays over bins are most of the file: one shot per chunk makes each write() fill whole
  // chunks (no read-modify-write, any order) and lets them be compressed.
  void chunk_by_shot(int varid, const char* name, const std::vector<std::size_t>& lengths) const {
    const std::string what = std::string("variable '") + name + "'";
    std::vector<std::size_t> chunks = {1};
    chunks.insert(chunks.end(), lengths.begin(), lengths.end());
    check(nc_def_var_chunking(nc.id(), varid, NC_CHUNKED, chunks.data()), what + " chunking");
    check(nc_def_var_deflate(nc.id(), varid, 1, 1, kDeflateLevel), what + " compression");
  }

  void define_shot_variable(const ProductField& def) {
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
    if (!is_shot_coordinate(def.name)) put_text(varid, def.name, "coordinates", kShotCoordinates);
    if (dimids.size() >= 3) chunk_by_shot(varid, def.name, lengths);
    variables.push_back({&def, varid, std::move(lengths)});
  }

  void define_globals(const RunInfo& info) {
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
  }

  RunVariables define_run_variables() const {
    RunVariables v;
    // CF: a single trajectory is identified by a scalar variable with cf_role trajectory_id.
    v.trajectory =
        define_variable("trajectory", NC_STRING, {}, "1", "trajectory (the simulated track)");
    put_text(v.trajectory, "trajectory", "cf_role", "trajectory_id");
    v.wavelength = define_variable("wavelength", NC_DOUBLE, {dim("band")}, "nm",
                                   "laser wavelength of the band");
    v.band_name = define_variable("band_name", NC_STRING, {dim("band")}, "1", "name of the band");
    v.bin_time = define_variable("bin_time_ns", NC_DOUBLE, {dim("bin")}, "ns",
                                 "time of each bin centre after the return from range_m (two-way)");
    v.tx_time = define_variable("tx_time_ns", NC_DOUBLE, {dim("tx_bin")}, "ns",
                                "time of each transmitted pulse bin centre about the pulse peak");
    v.tx_waveform = define_variable("tx_waveform", NC_FLOAT, {dim("band"), dim("tx_bin")}, "W",
                                    "transmitted pulse power");
    if (shape.orders > 0)
      v.order = define_variable("order", NC_INT, {dim("order")}, "1", "scattering order");
    // The coordinate of rh's last dimension, so that ds.rh.sel(percentile=98) reads as GEDI's
    // rh98.
    v.percentile = define_variable("percentile", NC_INT, {dim("percentile")}, "percent",
                                   "percentage of energy_tr counted up from signal end");
    return v;
  }

  // The few attributes beyond those of the table.
  void define_special_attributes() const {
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
    check(nc_put_var_double(nc.id(), v.wavelength, wavelengths.data()),
          "writing variable 'wavelength'");
    check(nc_put_var_string(nc.id(), v.band_name, names.data()), "writing variable 'band_name'");
    check(nc_put_var_double(nc.id(), v.bin_time, info.bin_time_ns.data()),
          "writing variable 'bin_time_ns'");
    check(nc_put_var_double(nc.id(), v.tx_time, info.tx_time_ns.data()),
          "writing variable 'tx_time_ns'");
    std::vector<double> tx;
    const std::size_t tx_shape[] = {shape.bands, tx_bins};
    if (!flatten(info.tx_waveform_W, tx_shape, tx)) {
      fail("tx_waveform must be " + join_shape(tx_shape) + " (band x tx_bin), got " +
           describe_shape(info.tx_waveform_W));
    }
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
    define_globals(info);
    define_dims();
    const RunVariables run_variables = define_run_variables();
    for (const ProductField& def : product_fields()) define_shot_variable(def);
    define_special_attributes();
    check(nc_enddef(nc.id()), "ending definitions");
    write_run_variables(info, run_variables);
  }

  std::string writing(const char* name, std::size_t index, const ShotRecord& shot) const {
    return std::string("writing variable '") + name + "' of record " + std::to_string(index) +
           " (shot " + std::to_string(shot.shot_number) + ")";
  }

  // Every array of the record in C order, checked against its variable's shape before anything
  // is written, so that a refused record leaves the file as it was. An empty array keeps the
  // fill: a flagged shot may carry none.
  std::vector<std::vector<double>> flatten_arrays(std::size_t index, const ShotRecord& shot) const {
    std::vector<std::vector<double>> arrays(variables.size());
    for (std::size_t i = 0; i < variables.size(); ++i) {
      std::visit(
          [&](auto field) {
            const auto& value = shot.*field;
            if constexpr (!std::is_arithmetic_v<std::remove_cvref_t<decltype(value)>>) {
              if (value.empty() && shot.quality_flag != quality_good) return;
              if (!flatten(value, variables[i].shape, arrays[i])) {
                fail(writing(variables[i].def->name, index, shot) + ": expected " +
                     join_shape(variables[i].shape) + " values, got " + describe_shape(value));
              }
            }
          },
          variables[i].def->field);
    }
    return arrays;
  }

  void put_value(std::size_t index, const ShotRecord& shot, const DefinedVariable& variable,
                 const std::vector<double>& array) const {
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
            if (array.empty()) return;
            std::vector<std::size_t> start(variable.shape.size() + 1, 0);
            std::vector<std::size_t> count = {1};
            start[0] = index;
            count.insert(count.end(), variable.shape.begin(), variable.shape.end());
            status = nc_put_vara_double(nc.id(), variable.varid, start.data(), count.data(),
                                        array.data());
          }
          check(status, writing(variable.def->name, index, shot));
        },
        variable.def->field);
  }

  void write_record(std::size_t index, const ShotRecord& shot) {
    const std::vector<std::vector<double>> arrays = flatten_arrays(index, shot);
    for (std::size_t i = 0; i < variables.size(); ++i)
      put_value(index, shot, variables[i], arrays[i]);
  }
};

NetcdfWriter::NetcdfWriter(std::filesystem::path final_path, const RunInfo& info)
    : final_path_(std::move(final_path)), impl_(std::make_unique<Impl>(final_path_)) {
  Impl& impl = *impl_;
  if (info.shots < 1)
    impl.fail("a product needs at least one shot, got " + std::to_string(info.shots));
  if (info.bands.empty()) impl.fail("a product needs at least one band");
  if (info.bin_time_ns.empty() || info.tx_time_ns.empty())
    impl.fail("a product needs bins and tx bins");
  if (info.orders < 0) impl.fail("orders must be >= 0, got " + std::to_string(info.orders));
  impl.shots = static_cast<std::size_t>(info.shots);
  impl.shape = {info.bands.size(), info.bin_time_ns.size(), static_cast<std::size_t>(info.orders)};
  impl.tx_bins = info.tx_time_ns.size();
  impl.written.assign(impl.shots, false);

  const std::string part = impl.file.part_path().string();
  impl.check(nc_create(part.c_str(), NC_NETCDF4 | NC_CLOBBER, impl.nc.out()),
             "cannot create " + part);
  impl.define(info);
}

NetcdfWriter::~NetcdfWriter() = default;

NetcdfWriter::Impl& NetcdfWriter::impl() {
  if (!impl_) throw run_error(final_path_.string(), "the product was aborted");
  return *impl_;
}

void NetcdfWriter::write(std::int64_t index, const ShotRecord& shot) {
  Impl& impl = this->impl();
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
  Impl& impl = this->impl();
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

void NetcdfWriter::abort() noexcept {
  // A finished product stays: only an unfinished one has a .part to give up.
  if (impl_ && !impl_->finished) impl_.reset();
}

}  // namespace glaswave
