// What the configuration says about the ground: a DEM file, a synthetic plane or a point cloud's
// ground, its roughness and its reflectance. Filled by pipeline/config, read by the terrain
// library.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace glaswave {

// A synthetic tilted plane, anchored at the origin: heights above the WGS84 ellipsoid fall by
// tan(slope) per metre toward `aspect_deg` (the azimuth the slope faces, clockwise from north).
struct PlaneSettings {
  double origin_lat_deg = 0.0;
  double origin_lon_deg = 0.0;
  double elevation_m = 0.0;
  double slope_deg = 0.0;
  double aspect_deg = 0.0;
};

// Random sub-grid relief added to the ground mesh.
struct RoughnessSettings {
  double rms_m = 0.0;
  double correlation_m = 2.0;
};

struct TerrainSettings {
  std::string dem;   // raster path; empty when `plane` is set
  int dem_band = 0;  // 1-based band of the DEM; 0: not given (a one-band raster)
  // What the DEM's heights are measured from when its CRS has no vertical part: "ellipsoid"
  // (its own ellipsoid), "egm96" (the EGM96 geoid, EPSG:5773) or a vertical CRS PROJ knows
  // ("EPSG:3855"). A vertical CRS of the DEM's own is used unless the user gave another datum,
  // which is then refused (vertical_datum_given).
  std::string vertical_datum = "ellipsoid";
  bool vertical_datum_given = false;   // set by the user: a DEM's own other datum is then refused
  std::optional<PlaneSettings> plane;  // exactly one of dem, plane and point_cloud
  // The ground of canopy.point_cloud's cloud (its class-2 points, gridded as `glaswave voxelize`
  // grids them), built by canopy/cloud_terrain.hpp: no DEM file. Set (true) or absent.
  std::optional<bool> point_cloud;
  RoughnessSettings roughness;
  std::vector<double> soil_reflectance;  // Lambertian, one value per sensor band
};

}  // namespace glaswave
