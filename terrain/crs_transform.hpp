// A raster's coordinates and heights to and from WGS84 longitude, latitude and ellipsoidal
// height, with PROJ: the raster's CRS, its vertical CRS when it has one, else the vertical datum
// the configuration names (terrain.vertical_datum). Thread-safe: PROJ objects are not, so each
// call borrows one of its own from a pool.
#pragma once

#include <array>
#include <cstddef>
#include <memory>
#include <string>

#include "terrain/terrain.hpp"

namespace glaswave {

class CrsTransform {
 public:
  // `crs_wkt`: the raster's CRS (WKT). `vertical_datum`: "ellipsoid", "egm96" or a vertical CRS
  // ("EPSG:3855"), used only when the CRS has no vertical part. `place` names the raster in
  // errors: an unusable CRS or a missing geoid grid is an input error there; a vertical datum
  // PROJ does not know is a configuration error at /terrain/vertical_datum. When
  // `vertical_datum_given` (the user set it) and the CRS has a vertical part of its own that is
  // another datum, the conflict is a configuration error there too: neither wins silently.
  CrsTransform(const std::string& crs_wkt, const std::string& vertical_datum,
               const std::string& place, bool vertical_datum_given = false);
  ~CrsTransform();
  CrsTransform(const CrsTransform&) = delete;
  CrsTransform& operator=(const CrsTransform&) = delete;

  // In place, `count` points: x, y in the raster's CRS (easting first) and z its heights ->
  // longitude, latitude (deg) and height above the WGS84 ellipsoid (m). Points PROJ cannot
  // transform come out NaN.
  void to_wgs84(std::size_t count, double* x, double* y, double* z) const;

  // Longitude and latitude (deg) -> x, y in the raster's CRS.
  std::array<double, 2> from_wgs84(double lon_deg, double lat_deg) const;

  // Whether x and y are longitude and latitude in degrees (a geographic CRS).
  bool geographic() const;

  const VerticalDatum& vertical_datum() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace glaswave
