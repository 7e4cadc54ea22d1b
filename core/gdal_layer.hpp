// The one GDAL layer, used by every reader and writer of rasters and vectors: GDAL's drivers
// registered once, its messages trapped as the cause of our one-line errors (library code never
// prints), datasets closed by RAII under the NetCDF lock, and the transformation of a layer's
// coordinates into WGS 84 longitude and latitude.
#pragma once

#include <memory>
#include <string>

class GDALDataset;
class OGRSpatialReference;
class OGRCoordinateTransformation;

namespace glaswave {

// Registers GDAL's drivers, once a process, from any thread. GDAL's own block cache is limited
// to 32 MiB (its default is 5 % of the machine's memory; the readers cache what they need
// themselves); a user's GDAL_CACHEMAX still wins.
void prepare_gdal();

// While alive, GDAL's messages on this thread are kept here instead of going to stderr; the
// user sees one line of ours, with GDAL's message as its cause. Traps nest.
class GdalErrorTrap {
 public:
  GdalErrorTrap();
  ~GdalErrorTrap();
  GdalErrorTrap(const GdalErrorTrap&) = delete;
  GdalErrorTrap& operator=(const GdalErrorTrap&) = delete;

  bool failed() const { return !first_.empty(); }
  // Forgets what GDAL said so far (before a second try).
  void reset() { first_.clear(), last_.clear(); }
  // The last failure GDAL reported (on one line), or `fallback` when it reported none.
  std::string cause(const std::string& fallback) const { return last_.empty() ? fallback : last_; }
  // "`what`: the first failure", or `what` when GDAL reported none.
  std::string failure(const std::string& what) const {
    return first_.empty() ? what : what + ": " + first_;
  }

 private:
  std::string first_, last_;

 public:
  // GDAL's handler calls this (with the innermost trap of the thread as its user data).
  static void handle_message(int level, int number, const char* text);
};

// Closes a dataset with GDALClose, holding the NetCDF lock (a netCDF or HDF5 file closes through
// libnetcdf: core/netcdf_lock.hpp) and trapping what GDAL says.
struct GdalDatasetCloser {
  void operator()(GDALDataset* dataset) const;
};
using GdalDataset = std::unique_ptr<GDALDataset, GdalDatasetCloser>;

// The transformation from `source` to WGS 84 in longitude, latitude order (RFC 7946's and the
// products'); null when PROJ cannot make it.
std::unique_ptr<OGRCoordinateTransformation> transformation_to_wgs84(
    const OGRSpatialReference& source);

}  // namespace glaswave
