// Small GEDI L2A and GLAH14 granules in their real layouts, written with the HDF5 C API.
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace glaswave::testing {

// Writes one-dimensional datasets into an HDF5 file, making the groups on their paths.
class Hdf5Writer {
 public:
  explicit Hdf5Writer(const std::filesystem::path& file)
      : file_(H5Fcreate(file.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT)) {
    link_ = H5Pcreate(H5P_LINK_CREATE);
    H5Pset_create_intermediate_group(link_, 1);
  }
  Hdf5Writer(const Hdf5Writer&) = delete;
  Hdf5Writer& operator=(const Hdf5Writer&) = delete;
  ~Hdf5Writer() {
    H5Pclose(link_);
    H5Fclose(file_);
  }
  void group(const std::string& path) {
    H5Gclose(H5Gcreate2(file_, path.c_str(), link_, H5P_DEFAULT, H5P_DEFAULT));
  }
  void doubles(const std::string& path, const std::vector<double>& v) {
    write(path, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, v.size(), v.data());
  }
  void uint64s(const std::string& path, const std::vector<std::uint64_t>& v) {
    write(path, H5T_STD_U64LE, H5T_NATIVE_UINT64, v.size(), v.data());
  }
  void int32s(const std::string& path, const std::vector<std::int32_t>& v) {
    write(path, H5T_STD_I32BE, H5T_NATIVE_INT32, v.size(), v.data());
  }
  void int64s(const std::string& path, const std::vector<std::int64_t>& v) {
    write(path, H5T_STD_I64LE, H5T_NATIVE_INT64, v.size(), v.data());
  }
  void uint8s(const std::string& path, const std::vector<std::uint8_t>& v) {
    write(path, H5T_STD_U8LE, H5T_NATIVE_UINT8, v.size(), v.data());
  }
  // A chunked dataset that declares `n` doubles and stores none of them (a file of a few KB).
  void declared_doubles(const std::string& path, hsize_t n) {
    const hid_t space = H5Screate_simple(1, &n, nullptr);
    const hid_t create = H5Pcreate(H5P_DATASET_CREATE);
    const hsize_t chunk = 1024;
    H5Pset_chunk(create, 1, &chunk);
    H5Dclose(H5Dcreate2(file_, path.c_str(), H5T_IEEE_F64LE, space, link_, create, H5P_DEFAULT));
    H5Pclose(create);
    H5Sclose(space);
  }

 private:
  void write(const std::string& path, hid_t file_type, hid_t memory_type, std::size_t n,
             const void* data) {
    const hsize_t size = n;
    const hid_t space = H5Screate_simple(1, &size, nullptr);
    const hid_t set =
        H5Dcreate2(file_, path.c_str(), file_type, space, link_, H5P_DEFAULT, H5P_DEFAULT);
    H5Dwrite(set, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
    H5Dclose(set);
    H5Sclose(space);
  }
  hid_t file_;
  hid_t link_;
};

constexpr double gedi_fill = -999999.0;

// Two beams of three shots; BEAM0101's second shot has a fill latitude and longitude.
// delta_time is seconds since 2018-01-01T00:00:00Z, 568036800 s after the GLAS epoch.
inline void write_gedi_l2a(const std::filesystem::path& file) {
  Hdf5Writer h5(file);
  h5.group("METADATA");
  h5.uint64s("BEAM0101/shot_number", {11110101000001ULL, 11110101000002ULL, 11110101000003ULL});
  h5.doubles("BEAM0101/lat_lowestmode", {34.30, gedi_fill, 34.30050});
  h5.doubles("BEAM0101/lon_lowestmode", {-118.20, gedi_fill, -118.19990});
  h5.doubles("BEAM0101/delta_time", {100.0, 100.0083, 100.0166});
  h5.doubles("BEAM0101/elev_lowestmode", {0.0, -9999.0, 0.0});
  h5.uint64s("BEAM1011/shot_number", {11111011000001ULL, 11111011000002ULL, 11111011000003ULL});
  h5.doubles("BEAM1011/lat_lowestmode", {34.31, 34.31050, 34.31100});
  h5.doubles("BEAM1011/lon_lowestmode", {-118.21, -118.20990, -118.20980});
  h5.doubles("BEAM1011/delta_time", {200.0, 200.0083, 200.0166});
  h5.doubles("BEAM1011/elev_lowestmode", {0.0, 0.0, 0.0});
}

// Two 1 s records of 40 Hz shots, the first record's last two (an incomplete record: its first
// 38 shots are missing) and the second's first three; the fourth shot's position is a fill
// value (GLAH14 stores lon in [0, 360)).
inline void write_glah14(const std::filesystem::path& file) {
  Hdf5Writer h5(file);
  h5.group("ANCILLARY_DATA");
  h5.doubles("Data_40HZ/Geolocation/d_lat",
             {34.30, 34.3015, 34.3030, 1.7976931348623157e308, 34.3060});
  h5.doubles("Data_40HZ/Geolocation/d_lon",
             {241.80, 241.8002, 241.8004, 1.7976931348623157e308, 241.8008});
  h5.doubles("Data_40HZ/Time/d_UTCTime_40",
             {181000000.0, 181000000.025, 181000000.050, 181000000.075, 181000000.100});
  h5.int32s("Data_40HZ/Time/i_rec_ndx", {5000, 5000, 5001, 5001, 5001});
  h5.int32s("Data_40HZ/Time/i_shot_count", {39, 40, 1, 2, 3});
}

}  // namespace glaswave::testing
