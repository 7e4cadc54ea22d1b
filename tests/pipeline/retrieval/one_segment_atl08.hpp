// A real-layout ATL08 (the data dictionary's names and dtypes) of one land segment, gt1l's 20 m
// ATL03 segments 101-105 on a terrain slope of 0.1: the ATL03 tests' and the retrieval fuzzer's
// companion. The caller holds libnetcdf's lock (core/netcdf_lock.hpp).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/hdf5_file.hpp"

namespace glaswave::test_support {

inline void write_one_segment_atl08(const std::filesystem::path& path) {
  Hdf5Writer f(path);
  const std::string land = "gt1l/land_segments/";
  f.write(land + "segment_id_beg", std::vector<std::int32_t>{101});
  f.write(land + "segment_id_end", std::vector<std::int32_t>{105});
  f.write(land + "latitude", std::vector<float>{10.0f});
  f.write(land + "longitude", std::vector<float>{20.0f});
  f.write(land + "canopy/h_canopy", std::vector<float>{12.0f});
  f.write(land + "terrain/h_te_best_fit", std::vector<float>{250.25f});
  f.write(land + "terrain/terrain_slope", std::vector<float>{0.1f});
  f.write(land + "canopy/n_ca_photons", std::vector<std::int32_t>{3});
  f.write(land + "canopy/n_toc_photons", std::vector<std::int32_t>{1});
  f.write(land + "terrain/n_te_photons", std::vector<std::int32_t>{4});
  f.close();
}

}  // namespace glaswave::test_support
