// A stands file through GDAL/OGR: any vector format it reads (GeoJSON, GeoPackage, Shapefile,
// FlatGeobuf...), in any CRS, its polygons' rings brought to WGS84 longitude and latitude and its
// features' attribute fields as the JSON of the canopy keys they override; and those features
// turned into the canopies of the stands, each checked as the configuration's canopy is.
#pragma once

#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "canopy/canopy_settings.hpp"
#include "pipeline/config/config.hpp"

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

// The stands of the file at `path`: each feature's canopy is `scene_canopy` (the configuration's
// resolved canopy) with the feature's fields applied, read as the configuration's canopy is, its
// per-band optics in the order of `bands`. A fault is the file's (exit status 3), named by its
// feature and key.
std::vector<StandArea> read_stands(const std::string& path, const nlohmann::json& scene_canopy,
                                   const std::vector<LidarBand>& bands);

}  // namespace glaswave
