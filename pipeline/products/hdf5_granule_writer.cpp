// The HDF5 granule writers' shared parts, over the HDF5 C API.
#include "pipeline/products/hdf5_granule_writer.hpp"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>

#include "core/error.hpp"
#include "core/netcdf_lock.hpp"

namespace glaswave {
namespace {

template <typename T>
struct Hdf5Type;
template <>
struct Hdf5Type<double> {
  static hid_t file() { return H5T_IEEE_F64LE; }
  static hid_t memory() { return H5T_NATIVE_DOUBLE; }
};
template <>
struct Hdf5Type<float> {
  static hid_t file() { return H5T_IEEE_F32LE; }
  static hid_t memory() { return H5T_NATIVE_FLOAT; }
};
template <>
struct Hdf5Type<std::uint64_t> {
  static hid_t file() { return H5T_STD_U64LE; }
  static hid_t memory() { return H5T_NATIVE_UINT64; }
};
template <>
struct Hdf5Type<std::int32_t> {
  static hid_t file() { return H5T_STD_I32LE; }
  static hid_t memory() { return H5T_NATIVE_INT32; }
};
template <>
struct Hdf5Type<std::uint16_t> {
  static hid_t file() { return H5T_STD_U16LE; }
  static hid_t memory() { return H5T_NATIVE_UINT16; }
};
template <>
struct Hdf5Type<std::int16_t> {
  static hid_t file() { return H5T_STD_I16LE; }
  static hid_t memory() { return H5T_NATIVE_INT16; }
};
template <>
struct Hdf5Type<std::uint8_t> {
  static hid_t file() { return H5T_STD_U8LE; }
  static hid_t memory() { return H5T_NATIVE_UINT8; }
};

// Arrays above this many values are chunked and deflated.
constexpr std::size_t kChunkedFrom = 4096;

}  // namespace

Hdf5File::Hdf5File(const std::filesystem::path& path) : path_(path.string()) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are ours to report
  file_ = H5Fcreate(path_.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  check(file_ >= 0, "cannot create the file");
  link_ = H5Pcreate(H5P_LINK_CREATE);
  check(link_ >= 0 && H5Pset_create_intermediate_group(link_, 1) >= 0, "cannot create the file");
}

Hdf5File::~Hdf5File() {
  if (link_ >= 0) H5Pclose(link_);
  if (file_ >= 0) H5Fclose(file_);
}

void Hdf5File::check(bool ok, const std::string& what) const {
  if (!ok) throw run_error(path_, what);
}

void Hdf5File::close() {
  check(H5Fflush(file_, H5F_SCOPE_GLOBAL) >= 0, "cannot write the file (disk full?)");
  H5Pclose(link_);
  link_ = -1;
  const herr_t closed = H5Fclose(file_);
  file_ = -1;
  check(closed >= 0, "cannot close the file (disk full?)");
}

void Hdf5File::group(const std::string& path, const char* description) {
  if (H5Lexists(file_, path.c_str(), H5P_DEFAULT) <= 0) {
    const hid_t g = H5Gcreate2(file_, path.c_str(), link_, H5P_DEFAULT, H5P_DEFAULT);
    check(g >= 0, "cannot create the group " + path);
    H5Gclose(g);
  }
  if (description) string_attribute(path, "description", description);
}

void Hdf5File::string_attribute(const std::string& object, const char* name,
                                const std::string& value) {
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, std::max<std::size_t>(value.size(), 1));
  H5Tset_strpad(type, H5T_STR_NULLTERM);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate_by_name(file_, object.c_str(), name, type, space, H5P_DEFAULT,
                                       H5P_DEFAULT, H5P_DEFAULT);
  const bool ok = attr >= 0 && H5Awrite(attr, type, value.c_str()) >= 0;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
  check(ok, std::string("cannot write the attribute ") + name + " of " + object);
}

void Hdf5File::double_attribute(const std::string& object, const char* name, double value) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate_by_name(file_, object.c_str(), name, H5T_IEEE_F64LE, space,
                                       H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
  const bool ok = attr >= 0 && H5Awrite(attr, H5T_NATIVE_DOUBLE, &value) >= 0;
  if (attr >= 0) H5Aclose(attr);
  H5Sclose(space);
  check(ok, std::string("cannot write the attribute ") + name + " of " + object);
}

template <typename T>
void Hdf5File::write(const std::string& path, const std::vector<T>& values,
                     const Hdf5Attributes& attrs, std::vector<hsize_t> dims) {
  write_raw(path, Hdf5Type<T>::file(), Hdf5Type<T>::memory(), values.data(), values.size(),
            std::move(dims), attrs);
  if (attrs.fill) {
    const T fill = static_cast<T>(*attrs.fill);
    const hid_t space = H5Screate(H5S_SCALAR);
    const hid_t attr = H5Acreate_by_name(file_, path.c_str(), "_FillValue", Hdf5Type<T>::file(),
                                         space, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    const bool ok = attr >= 0 && H5Awrite(attr, Hdf5Type<T>::memory(), &fill) >= 0;
    if (attr >= 0) H5Aclose(attr);
    H5Sclose(space);
    check(ok, "cannot write the _FillValue of " + path);
  }
}

template void Hdf5File::write(const std::string&, const std::vector<double>&, const Hdf5Attributes&,
                              std::vector<hsize_t>);
template void Hdf5File::write(const std::string&, const std::vector<float>&, const Hdf5Attributes&,
                              std::vector<hsize_t>);
template void Hdf5File::write(const std::string&, const std::vector<std::uint64_t>&,
                              const Hdf5Attributes&, std::vector<hsize_t>);
template void Hdf5File::write(const std::string&, const std::vector<std::int32_t>&,
                              const Hdf5Attributes&, std::vector<hsize_t>);
template void Hdf5File::write(const std::string&, const std::vector<std::uint16_t>&,
                              const Hdf5Attributes&, std::vector<hsize_t>);
template void Hdf5File::write(const std::string&, const std::vector<std::int16_t>&,
                              const Hdf5Attributes&, std::vector<hsize_t>);
template void Hdf5File::write(const std::string&, const std::vector<std::uint8_t>&,
                              const Hdf5Attributes&, std::vector<hsize_t>);

void Hdf5File::write_raw(const std::string& path, hid_t file_type, hid_t memory_type,
                         const void* data, std::size_t count, std::vector<hsize_t> dims,
                         const Hdf5Attributes& attrs) {
  if (dims.empty()) dims = {static_cast<hsize_t>(count)};
  const hsize_t total =
      std::accumulate(dims.begin(), dims.end(), hsize_t{1}, std::multiplies<hsize_t>());
  check(total == count,
        "internal: " + path + " has " + std::to_string(count) + " values for its dimensions");
  const hid_t space = H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
  const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
  if (count > kChunkedFrom) {
    // Chunks of whole rows (a shot's 101 rh, its 544 bins), about 64k values each.
    std::vector<hsize_t> chunk = dims;
    const hsize_t row = total / dims[0];
    chunk[0] = std::max<hsize_t>(1, std::min<hsize_t>(dims[0], 65536 / std::max<hsize_t>(row, 1)));
    H5Pset_chunk(create, static_cast<int>(chunk.size()), chunk.data());
    H5Pset_deflate(create, 4);
  }
  const hid_t set = H5Dcreate2(file_, path.c_str(), file_type, space, link_, create, H5P_DEFAULT);
  const bool ok = set >= 0 && (count == 0 || H5Dwrite(set, memory_type, H5S_ALL, H5S_ALL,
                                                      H5P_DEFAULT, data) >= 0);
  if (set >= 0) H5Dclose(set);
  H5Pclose(create);
  H5Sclose(space);
  check(ok, "cannot write " + path);
  if (attrs.units) string_attribute(path, "units", attrs.units);
  if (attrs.description) string_attribute(path, "description", attrs.description);
}

std::size_t nearest_band(const RunInfo& info, double wavelength_nm) {
  std::size_t best = 0;
  for (std::size_t b = 1; b < info.bands.size(); ++b)
    if (std::abs(info.bands[b].wavelength_nm - wavelength_nm) <
        std::abs(info.bands[best].wavelength_nm - wavelength_nm))
      best = b;
  return best;
}

std::vector<float> to_counts(const std::vector<double>& power_W, double counts_per_W) {
  std::vector<float> counts(power_W.size());
  for (std::size_t i = 0; i < power_W.size(); ++i)
    counts[i] = static_cast<float>(power_W[i] * counts_per_W);
  return counts;
}

WaveformNoise waveform_noise(const std::vector<float>& counts, double elev_bin0_m,
                             double elev_lastbin_m, double signal_begin_m) {
  const std::size_t n = counts.size();
  if (n == 0) return {};
  std::size_t noise_bins = std::max<std::size_t>(std::min<std::size_t>(8, n), n / 8);
  if (std::isfinite(signal_begin_m) && n > 1) {
    const double step_m = (elev_bin0_m - elev_lastbin_m) / static_cast<double>(n - 1);
    if (step_m > 0) {
      const double before = std::floor((elev_bin0_m - signal_begin_m) / step_m);
      if (before >= 8) noise_bins = static_cast<std::size_t>(std::min<double>(before, n));
    }
  }
  double sum = 0.0;
  for (std::size_t i = 0; i < noise_bins; ++i) sum += counts[i];
  const double mean = sum / static_cast<double>(noise_bins);
  double squares = 0.0;
  for (std::size_t i = 0; i < noise_bins; ++i) squares += (counts[i] - mean) * (counts[i] - mean);
  return {mean, std::sqrt(squares / static_cast<double>(noise_bins))};
}

LatLon beam_point(const ShotRecord& shot, double elevation_m) {
  const double rise_m = shot.sc_alt_m - shot.elev_m;
  if (!std::isfinite(elevation_m) || !std::isfinite(shot.elev_m) || !(rise_m > 0))
    return {shot.lat_deg, shot.lon_deg};
  const double t = (elevation_m - shot.elev_m) / rise_m;
  double dlon = shot.sc_lon_deg - shot.lon_deg;
  if (dlon > 180) dlon -= 360;
  if (dlon < -180) dlon += 360;
  return {shot.lat_deg + t * (shot.sc_lat_deg - shot.lat_deg), shot.lon_deg + t * dlon};
}

Hdf5GranuleWriter::Hdf5GranuleWriter(const std::filesystem::path& final_path, const RunInfo& info)
    : info_(info), file_(final_path), written_(static_cast<std::size_t>(info.shots), false) {}

Hdf5GranuleWriter::~Hdf5GranuleWriter() = default;

void Hdf5GranuleWriter::write(std::int64_t index, const ShotRecord& shot) {
  if (done_) throw run_error(file_.final_path().string(), "a record after the product ended");
  if (index < 0 || index >= info_.shots || written_[static_cast<std::size_t>(index)])
    throw run_error(file_.final_path().string(),
                    "record " + std::to_string(index) + " out of range or written twice");
  keep(index, shot);
  written_[static_cast<std::size_t>(index)] = true;
}

void Hdf5GranuleWriter::finish(const RunStats&) {
  if (std::find(written_.begin(), written_.end(), false) != written_.end())
    throw run_error(file_.final_path().string(), "a record was never written");
  {
    // libhdf5 is libnetcdf's too, and neither is thread-safe: one lock for both.
    std::lock_guard lock(netcdf_library_mutex());
    Hdf5File file(file_.part_path());
    write_file(file);
    file.close();
  }
  file_.commit();
  done_ = true;
}

void Hdf5GranuleWriter::abort() noexcept {
  done_ = true;
  std::error_code ignored;
  std::filesystem::remove(file_.part_path(), ignored);
}

}  // namespace glaswave
