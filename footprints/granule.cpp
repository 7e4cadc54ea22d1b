// Reading GEDI L2A and GLAH14 granules with the HDF5 C API.
#include "footprints/granule.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <system_error>

#include "core/error.hpp"
#include "core/input_file.hpp"
#include "core/netcdf_lock.hpp"
#include "footprints/glas_time.hpp"

namespace glaswave {
namespace {

// An HDF5 identifier closed with its own function.
class Handle {
 public:
  Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  Handle(const Handle&) = delete;
  Handle& operator=(const Handle&) = delete;
  ~Handle() {
    if (id_ >= 0) close_(id_);
  }
  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

bool has_link(hid_t location, const std::string& path) {
  // Every part of the path must exist before H5Lexists may be asked about the next.
  std::size_t slash = 0;
  while (true) {
    slash = path.find('/', slash + 1);
    const std::string part = path.substr(0, slash);
    if (H5Lexists(location, part.c_str(), H5P_DEFAULT) <= 0) return false;
    if (slash == std::string::npos) return true;
  }
}

// A one-dimensional dataset read as `type` (HDF5 converts the stored type).
template <typename T>
std::vector<T> read_vector(hid_t group, const std::string& name, hid_t type,
                           const std::string& file, const std::string& group_name) {
  const std::string place = file + ": " + group_name;
  if (!has_link(group, name)) throw input_error(place, "no dataset \"" + name + "\"");
  Handle dataset(H5Dopen2(group, name.c_str(), H5P_DEFAULT), H5Dclose);
  if (!dataset.valid()) throw input_error(place, "\"" + name + "\" is not a dataset");
  Handle space(H5Dget_space(dataset.get()), H5Sclose);
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(space.get()) : -1;
  if (rank != 1) throw input_error(place, "\"" + name + "\" is not one-dimensional");
  hsize_t size = 0;
  H5Sget_simple_extent_dims(space.get(), &size, nullptr);
  std::vector<T> values(static_cast<std::size_t>(size));
  if (size > 0 && H5Dread(dataset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()) < 0)
    throw input_error(place, "cannot read \"" + name + "\" as numbers");
  return values;
}

bool valid_position(double lat_deg, double lon_deg) {
  return std::isfinite(lat_deg) && std::isfinite(lon_deg) && std::abs(lat_deg) <= 90.0 &&
         lon_deg >= -180.0 && lon_deg <= 360.0;
}

void check_lengths(std::size_t n, std::initializer_list<std::size_t> others,
                   const std::string& place) {
  for (std::size_t other : others)
    if (other != n)
      throw input_error(place, "its datasets differ in length (" + std::to_string(n) + " and " +
                                   std::to_string(other) + " values)");
}

void read_gedi_beam(hid_t file, const std::string& beam, const std::string& path,
                    std::vector<GranuleShot>& shots) {
  Handle group(H5Gopen2(file, beam.c_str(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) throw input_error(path + ": " + beam, "is not a group");
  const auto numbers =
      read_vector<std::uint64_t>(group.get(), "shot_number", H5T_NATIVE_UINT64, path, beam);
  const auto lat =
      read_vector<double>(group.get(), "lat_lowestmode", H5T_NATIVE_DOUBLE, path, beam);
  const auto lon =
      read_vector<double>(group.get(), "lon_lowestmode", H5T_NATIVE_DOUBLE, path, beam);
  const auto time = read_vector<double>(group.get(), "delta_time", H5T_NATIVE_DOUBLE, path, beam);
  check_lengths(numbers.size(), {lat.size(), lon.size(), time.size()}, path + ": " + beam);
  static const double gedi_epoch_s = parse_iso8601_utc("2018-01-01T00:00:00Z");
  for (std::size_t i = 0; i < numbers.size(); ++i) {
    if (!valid_position(lat[i], lon[i])) continue;
    shots.push_back(
        {static_cast<std::int64_t>(numbers[i]), gedi_epoch_s + time[i], lat[i], lon[i]});
  }
}

void read_glah14(hid_t file, const std::string& path, std::vector<GranuleShot>& shots) {
  const std::string beam = "Data_40HZ";
  Handle group(H5Gopen2(file, beam.c_str(), H5P_DEFAULT), H5Gclose);
  if (!group.valid()) throw input_error(path + ": " + beam, "is not a group");
  const auto lat =
      read_vector<double>(group.get(), "Geolocation/d_lat", H5T_NATIVE_DOUBLE, path, beam);
  const auto lon =
      read_vector<double>(group.get(), "Geolocation/d_lon", H5T_NATIVE_DOUBLE, path, beam);
  const auto time =
      read_vector<double>(group.get(), "Time/d_UTCTime_40", H5T_NATIVE_DOUBLE, path, beam);
  const auto record =
      read_vector<std::int64_t>(group.get(), "Time/i_rec_ndx", H5T_NATIVE_INT64, path, beam);
  check_lengths(lat.size(), {lon.size(), time.size(), record.size()}, path + ": " + beam);
  std::int64_t in_record = 0;
  for (std::size_t i = 0; i < lat.size(); ++i) {
    in_record = i > 0 && record[i] == record[i - 1] ? in_record + 1 : 0;
    if (!valid_position(lat[i], lon[i])) continue;
    shots.push_back({record[i] * 40 + in_record, time[i], lat[i], lon[i]});
  }
}

// The root's groups named BEAM..., in name order.
std::vector<std::string> gedi_beams(hid_t file) {
  std::vector<std::string> names;
  H5Literate(
      file, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
        if (std::string(name).rfind("BEAM", 0) == 0)
          static_cast<std::vector<std::string>*>(data)->push_back(name);
        return 0;
      },
      &names);
  return names;
}

}  // namespace

std::vector<GranuleShot> read_granule(const std::filesystem::path& file,
                                      const std::vector<std::string>& beams) {
  const std::string path = file.string();
  // HDF5 (Debian's, not built thread-safe) is the library under libnetcdf: one lock for both,
  // held until every handle below is closed.
  const std::lock_guard lock(netcdf_library_mutex());
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are ours to report
  require_input_file(path, "the granule");
  if (H5Fis_hdf5(path.c_str()) <= 0)
    throw input_error(path, "the granule is not an HDF5 file (GEDI L2A or GLAH14)");
  Handle h5(H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT), H5Fclose);
  if (!h5.valid()) throw input_error(path, "cannot open the granule");

  std::vector<GranuleShot> shots;
  const std::vector<std::string> all_beams = gedi_beams(h5.get());
  if (!all_beams.empty()) {
    for (const std::string& beam : beams)
      if (std::find(all_beams.begin(), all_beams.end(), beam) == all_beams.end())
        throw input_error(path + ": " + beam, "no such beam in the GEDI granule (it has " +
                                                  std::to_string(all_beams.size()) +
                                                  " BEAM groups, from " + all_beams.front() + ")");
    for (const std::string& beam : beams.empty() ? all_beams : beams)
      read_gedi_beam(h5.get(), beam, path, shots);
  } else if (has_link(h5.get(), "Data_40HZ")) {
    for (const std::string& beam : beams)
      if (beam != "Data_40HZ")
        throw input_error(path + ": " + beam,
                          "no such beam in the GLAH14 granule (its one beam is Data_40HZ)");
    read_glah14(h5.get(), path, shots);
  } else {
    throw input_error(path,
                      "neither a GEDI L2A granule (no BEAMxxxx group) nor a GLAH14 granule (no "
                      "Data_40HZ group)");
  }
  if (shots.empty())
    throw input_error(path, "the granule holds no shot with a valid latitude and longitude");
  return shots;
}

}  // namespace glaswave
