// A DEM as the ground (terrain.dem): any single-band raster GDAL reads, with a CRS, geographic or
// projected, nodata honoured, heights brought to the WGS84 ellipsoid with PROJ.
//
// The raster's values are heights at its pixel centres (its nodes). Between nodes the ground is
// linear on triangles, the diagonal of each cell running from node (col, row) to
// (col + 1, row + 1): height_m interpolates so, and mesh() emits exactly those triangles, each
// node carried into the shot's frame. A footprint's height and the ground its rays meet agree.
//
// Only what a shot needs is read: tiles of the raster, each with its nodes' longitude, latitude
// and ellipsoidal height, are read on demand (GDAL RasterIO behind a mutex: a dataset handle is
// not thread-safe) and kept in a least-recently-used cache of bounded size, so that a long pass
// over a raster of several GB stays within a few hundred MB.
#pragma once

#include <cstddef>
#include <memory>

#include "terrain/terrain.hpp"

namespace glaswave {

class DemTerrain final : public Terrain {
 public:
  struct Options {
    std::size_t cache_bytes = std::size_t{128} << 20;  // tiles kept in memory, at most
    int tile_pixels = 64;                              // tiles are this many pixels square
  };

  // Opens the raster and checks it: a missing, unreadable, truncated or corrupt file, one
  // without a CRS or a geotransform, or a multi-band raster without terrain.dem_band is an input
  // error naming the file (exit status 3). GDAL's and PROJ's own messages become its cause and
  // never reach the terminal.
  explicit DemTerrain(const TerrainSettings& settings);
  DemTerrain(const TerrainSettings& settings, const Options& options);
  ~DemTerrain() override;

  double height_m(double lat_deg, double lon_deg) const override;
  double detail_m() const override;
  // The DEM's own nodes over the square (a stride is taken only beyond 2048 nodes a side).
  GroundMesh mesh(const LocalFrame& frame, double half_size_m, double spacing_m) const override;
  // No node without data within the radius (plus a cell), and the disc inside the raster.
  bool has_data(const LocalFrame& frame, double radius_m) const override;
  VerticalDatum vertical_datum() const override;

  // The cache, for tests of its bound: bytes held now, and tiles read since opening.
  std::size_t cached_bytes() const;
  std::size_t tiles_read() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace glaswave
