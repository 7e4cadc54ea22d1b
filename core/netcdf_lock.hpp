// One lock for libnetcdf and the HDF5 under it (Debian builds neither thread-safe): every call
// into them, from creating a file to aborting it, and every HDF5 granule read, holds it, so that
// runs in several threads of one process (Python's) share them safely. The NetCDF product is
// written while the next batch of shots is simulated, and a DEM read through GDAL may itself be a
// netCDF file (GDAL's driver then calls libnetcdf too): the writer's calls and the DEM's tile reads
// both hold it.
#pragma once

#include <mutex>

namespace glaswave {

inline std::mutex& netcdf_library_mutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace glaswave
