// A stands file through GDAL/OGR: any vector format it reads (GeoJSON, GeoPackage, Shapefile,
// FlatGeobuf...), in any CRS, its polygons' rings brought to WGS84 longitude and latitude and its
// features' attribute fields as the JSON of the canopy keys they override.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace glaswave {

struct StandFeature {
  std::string name;  // "feature 2" (or "layer trees feature 2" in a file of several layers)
  std::vector<std::vector<std::array<double, 2>>> rings;  // lon, lat (deg), every polygon's
  nlohmann::json properties = nlohmann::json::object();   // set fields, typed; JSON text parsed
};

// Every feature of every layer. A file OGR cannot open, a geometry other than a Polygon or
// MultiPolygon, a ring of fewer than 4 positions, a layer with no CRS whose coordinates are not
// longitudes and latitudes, or points its CRS cannot bring to WGS84: input errors at `path`.
std::vector<StandFeature> read_stand_features(const std::string& path);

}  // namespace glaswave
