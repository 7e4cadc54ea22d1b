// NetcdfWriter's insides, shared by its two files: netcdf_layout.cpp defines shots.nc's
// dimensions, variables and attributes, netcdf_writer.cpp takes the records and makes the file
// appear. The products' own files only; no other code includes it.
#pragma once

#include <netcdf.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/write_error.hpp"
#include "pipeline/products/netcdf_writer.hpp"
#include "pipeline/products/product_fields.hpp"

namespace glaswave {
namespace shots_nc {

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

// Whether a [band][...] nested vector has the shape `shape`.
inline bool has_shape(const std::vector<double>& values, std::span<const std::size_t> shape) {
  return shape.size() == 1 && values.size() == shape[0];
}
inline bool has_shape(const std::vector<std::int32_t>& values, std::span<const std::size_t> shape) {
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
inline double* copy_flat(const std::vector<double>& values, double* out) {
  return std::copy(values.begin(), values.end(), out);
}
inline double* copy_flat(const std::vector<std::int32_t>& values, double* out) {
  return std::copy(values.begin(), values.end(), out);  // exact: every int32 is a double
}
template <class T>
double* copy_flat(const std::vector<std::vector<T>>& values, double* out) {
  for (const auto& inner : values) out = copy_flat(inner, out);
  return out;
}

inline std::string describe_shape(const std::vector<double>& values) {
  return std::to_string(values.size());
}
inline std::string describe_shape(const std::vector<std::int32_t>& values) {
  return std::to_string(values.size());
}
template <class T>
std::string describe_shape(const std::vector<std::vector<T>>& values) {
  if (values.empty()) return "0";
  return std::to_string(values.size()) + " x " + describe_shape(values.front());
}

inline std::string join_shape(std::span<const std::size_t> shape) {
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

}  // namespace shots_nc

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
  ~Impl();  // netcdf_writer.cpp
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  // Declared before the handle so that it is destroyed after it: the file is closed before
  // an unfinished .part is removed.
  AtomicFile file;
  shots_nc::NcHandle nc;
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
  shots_nc::Bounds time_s, lat_deg, lon_deg, elev_m;

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

  // shots.nc's layout (netcdf_layout.cpp).
  int dim(const char* name) const;
  void define_dim(const char* name, std::size_t length);
  void put_text(int varid, const char* variable, const char* name, const std::string& value) const;
  void put_text_if(int varid, const char* variable, const char* name, const char* value) const;
  int define_variable(const char* name, nc_type type, const std::vector<int>& dimids,
                      const char* units, const char* long_name,
                      const char* standard_name = nullptr) const;
  void put_fill(int varid, const ProductField& def) const;
  std::size_t chunk_by_shot(int varid, const ProductField& def,
                            const std::vector<std::size_t>& lengths) const;
  double fill_of(int varid, const ProductField& def) const;
  void define_ragged_variable(const ProductField& def);
  void define_photon_count();
  void define_shot_variable(const ProductField& def);
  void define_globals(const RunInfo& info);
  void define_dims();
  RunVariables define_run_variables() const;
  int define_crs() const;
  void put_flags(int varid, const char* variable, std::span<const unsigned char> values,
                 const char* meanings) const;
  void define_special_attributes() const;
  void write_run_variables(const RunInfo& info, const RunVariables& v) const;
  void define(const RunInfo& info);

  // The records (netcdf_writer.cpp).
  std::string writing(const char* name, std::size_t index, const ShotRecord& shot) const;
  void check_shapes(std::size_t index, const ShotRecord& shot) const;
  void check_ragged(std::size_t index, const ShotRecord& shot) const;
  static std::size_t ragged_size(const ProductField& def, const ShotRecord& shot);
  void hold_ragged(std::size_t index, const ShotRecord& shot);
  void put_ragged(std::size_t index, const RaggedShot& events);
  ChunkBuffer& chunk_of(std::size_t i, std::size_t index);
  void put_chunk(const DefinedVariable& variable, const ChunkBuffer& buffer) const;
  void hold_value(std::size_t i, std::size_t index, const ShotRecord& shot);
  void write_record(std::size_t index, const ShotRecord& shot);
  void put_double(const char* name, double value) const;
  void define_coverage() const;
};

}  // namespace glaswave
