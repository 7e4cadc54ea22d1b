// One lock for libnetcdf, which is not thread-safe. The NetCDF product is written while the next
// batch of shots is simulated, and a DEM read through GDAL may itself be a netCDF file (GDAL's
// driver then calls libnetcdf too): the writer's calls and the DEM's tile reads both hold it.
#pragma once

#include <mutex>

namespace glaswave {

inline std::mutex& netcdf_library_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace glaswave
