// A stands file read through GDAL/OGR, and its features turned into the canopies of the stands.
#include "pipeline/config/stands_file.hpp"

#include <cpl_error.h>
#include <gdal.h>
#include <ogr_api.h>
#include <ogr_core.h>
#include <ogr_geometry.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "core/error.hpp"
#include "core/excerpt.hpp"
#include "core/gdal_layer.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/config/section_readers.hpp"
#include "terrain/gdal_source.hpp"

namespace glaswave {
namespace {

using json = nlohmann::json;
using Ring = std::vector<std::array<double, 2>>;

// GDAL's messages go to the error, never to the terminal.
// GDAL's last failure, for a message: " (its text)", or nothing.
std::string gdal_cause(const GdalErrorTrap& trap) {
  return trap.failed() ? " (" + trap.cause("") + ")" : "";
}

// A field's value as the JSON of a canopy key: numbers as numbers, booleans as booleans, lists as
// arrays, and text that reads as a JSON object or array (an `lad` object) as that JSON.
json field_value(const OGRFeature& feature, int i) {
  const OGRFieldDefn* field = feature.GetFieldDefnRef(i);
  switch (field->GetType()) {
    case OFTInteger:
      if (field->GetSubType() == OFSTBoolean) return feature.GetFieldAsInteger(i) != 0;
      return feature.GetFieldAsInteger(i);
    case OFTInteger64:
      return static_cast<std::int64_t>(feature.GetFieldAsInteger64(i));
    case OFTReal:
      return feature.GetFieldAsDouble(i);
    case OFTIntegerList: {
      int n = 0;
      const int* values = feature.GetFieldAsIntegerList(i, &n);
      return json(std::vector<int>(values, values + n));
    }
    case OFTInteger64List: {
      int n = 0;
      const GIntBig* values = feature.GetFieldAsInteger64List(i, &n);
      return json(std::vector<std::int64_t>(values, values + n));
    }
    case OFTRealList: {
      int n = 0;
      const double* values = feature.GetFieldAsDoubleList(i, &n);
      return json(std::vector<double>(values, values + n));
    }
    case OFTStringList: {
      json list = json::array();
      for (char** s = feature.GetFieldAsStringList(i); s != nullptr && *s != nullptr; ++s)
        list.push_back(std::string(*s));
      return list;
    }
    default: {
      const std::string text = feature.GetFieldAsString(i);
      const auto first = text.find_first_not_of(" \t\r\n");
      if (first != std::string::npos && (text[first] == '{' || text[first] == '[')) {
        // Nesting and duplicate keys are checked before anything recurses (an Error); text that
        // is not JSON stays text.
        try {
          return parse_json_checked(text, "");
        } catch (const json::exception&) {
        }
      }
      return text;
    }
  }
}

void add_polygon(const OGRPolygon& polygon, std::vector<Ring>& rings) {
  for (const OGRLinearRing* ring : polygon) {
    Ring points;
    for (const OGRPoint& point : *ring) points.push_back({point.getX(), point.getY()});
    rings.push_back(std::move(points));
  }
}

bool lon_lat(const std::vector<Ring>& rings) {
  for (const Ring& ring : rings)
    for (const auto& [x, y] : ring)
      if (!(std::abs(x) <= 180 && std::abs(y) <= 90)) return false;
  return true;
}

// A position brought to WGS84 that is not on the Earth: longitude outside [-180, 360] (the
// configuration's range), latitude outside [-90, 90], or not finite. Empty when all are.
std::string off_earth(const std::vector<Ring>& rings) {
  for (const Ring& ring : rings)
    for (const auto& [lon, lat] : ring)
      if (!(lon >= -180.0 && lon <= 360.0 && lat >= -90.0 && lat <= 90.0)) {
        char text[96];
        std::snprintf(text, sizeof text, "longitude %.6g, latitude %.6g", lon, lat);
        return text;
      }
  return "";
}

// The feature's attribute fields, as the JSON of the canopy keys they override; a field whose
// JSON nests too deep or repeats a key is the file's fault, at the feature.
json feature_properties(const OGRFeature& feature, const std::string& path,
                        const std::string& name) {
  json properties = json::object();
  for (int i = 0; i < feature.GetFieldCount(); ++i) {
    if (!feature.IsFieldSetAndNotNull(i)) continue;
    const std::string field = feature.GetFieldDefnRef(i)->GetNameRef();
    try {
      properties[field] = field_value(feature, i);
    } catch (const Error& e) {
      throw input_error(path,
                        name + ": property " + excerpt(field) + e.place() + ": " + e.message());
    }
  }
  return properties;
}

// Whether a ring's positions all lie on one line (within 1e-9 degrees, a tenth of a millimetre):
// it encloses no area. The even-odd rule gives any other ring an area, a bow-tie's included.
bool encloses_no_area(const Ring& ring) {
  const auto& [x0, y0] = ring.front();
  std::array<double, 2> far = ring.front();
  double far_d2 = 0.0;
  for (const auto& [x, y] : ring)
    if (const double d2 = (x - x0) * (x - x0) + (y - y0) * (y - y0); d2 > far_d2) {
      far_d2 = d2;
      far = {x, y};
    }
  if (!(far_d2 > 0.0)) return true;
  const double length = std::sqrt(far_d2);
  for (const auto& [x, y] : ring) {
    const double across = std::abs((far[0] - x0) * (y - y0) - (far[1] - y0) * (x - x0)) / length;
    if (across > 1e-9) return false;
  }
  return true;
}

// A GeoJSON file's own `crs` member (the 2008 specification's), which GDAL replaces by WGS84
// longitude and latitude when it cannot read it: a CRS it does not know is refused here, not
// taken as longitude and latitude. Empty when the member is absent or null.
void check_geojson_crs(OGRLayer& layer, const std::string& path) {
  const char* native = layer.GetMetadataItem("NATIVE_DATA", "NATIVE_DATA");
  if (!native) return;
  const json members = json::parse(native, nullptr, false);
  if (!members.is_object() || !members.contains("crs") || members["crs"].is_null()) return;
  const json& crs = members["crs"];
  std::string name;
  if (crs.is_object() && crs.contains("properties") && crs["properties"].is_object()) {
    const json& properties = crs["properties"];
    if (crs.value("type", "") == "name" && properties.contains("name") &&
        properties["name"].is_string())
      name = properties["name"].get<std::string>();
    if (crs.value("type", "") == "EPSG" && properties.contains("code") &&
        properties["code"].is_number_integer())
      name = "EPSG:" + std::to_string(properties["code"].get<std::int64_t>());
  }
  OGRSpatialReference known;
  if (name.empty() ||
      known.SetFromUserInput(
          name.c_str(), OGRSpatialReference::SET_FROM_USER_INPUT_LIMITATIONS_get()) != OGRERR_NONE)
    throw input_error(path, "its crs member " +
                                (name.empty() ? describe(crs) : quoted_excerpt(name)) +
                                " is not a CRS GDAL knows: give one as {\"type\": \"name\", "
                                "\"properties\": {\"name\": \"EPSG:CODE\"}}, or none for "
                                "longitude and latitude (RFC 7946)");
}

// A Shapefile cuts field names to 10 characters (its dBase table's limit), so that
// `leaf_reflectance` arrives as `leaf_refle`: a field of 10 characters that is no canopy key is
// told as that, not as an unknown key.
void check_shapefile_fields(OGRLayer& layer, const std::string& path) {
  const Key& canopy = *configuration_keys().child("canopy");
  OGRFeatureDefn* definition = layer.GetLayerDefn();
  for (int i = 0; i < definition->GetFieldCount(); ++i) {
    const std::string field = definition->GetFieldDefn(i)->GetNameRef();
    if (field.size() != 10 || canopy.child(field)) continue;
    std::string meant;
    for (const Key& key : canopy.children)
      if (key.name.rfind(field, 0) == 0) meant = " (" + quoted_excerpt(key.name) + " cut short?)";
    throw input_error(path, "field " + quoted_excerpt(field) + meant +
                                ": a Shapefile cuts field names to 10 characters, too few for "
                                "some canopy keys; write the stands as GeoPackage (.gpkg) or "
                                "GeoJSON");
  }
}

}  // namespace

std::vector<StandFeature> read_stand_features(const std::string& path) {
  // A pipe or a device would be waited for or read for ever (a Shapefile's folder is fine).
  std::error_code error;
  if (!std::filesystem::is_directory(path, error)) require_gdal_source(path, "the stands file");
  prepare_gdal();
  GdalErrorTrap trap;
  // GeoJSON keeps its FeatureCollection's other members (a `crs`) as NATIVE_DATA when asked.
  const char* const geojson[] = {"GeoJSON", nullptr};
  const char* const native_data[] = {"NATIVE_DATA=YES", nullptr};
  GdalDataset dataset(GDALDataset::FromHandle(
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, geojson, native_data, nullptr)));
  if (!dataset) {
    trap.reset();
    dataset.reset(GDALDataset::FromHandle(
        GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  }
  if (!dataset)
    throw input_error(path, "cannot be read as a vector file (GeoJSON, GeoPackage, Shapefile...)" +
                                gdal_cause(trap));
  const int layers = dataset->GetLayerCount();
  std::vector<StandFeature> features;
  for (int l = 0; l < layers; ++l) {
    OGRLayer* layer = dataset->GetLayer(l);
    const std::string driver = dataset->GetDriver()->GetDescription();
    if (driver == "GeoJSON") check_geojson_crs(*layer, path);
    if (driver == "ESRI Shapefile") check_shapefile_fields(*layer, path);
    const std::string prefix =
        layers > 1 ? "layer " + std::string(layer->GetName()) + " feature " : "feature ";
    std::unique_ptr<OGRCoordinateTransformation> to_wgs84;
    if (const OGRSpatialReference* crs = layer->GetSpatialRef()) {
      to_wgs84 = transformation_to_wgs84(*crs);
      if (!to_wgs84)
        throw input_error(path,
                          (layers > 1 ? "layer " + std::string(layer->GetName()) + ": " : "") +
                              "its CRS cannot be brought to WGS84 longitude and latitude" +
                              gdal_cause(trap));
    }
    layer->ResetReading();
    int index = 0;
    for (std::unique_ptr<OGRFeature> feature(layer->GetNextFeature()); feature;
         feature.reset(layer->GetNextFeature()), ++index) {
      StandFeature stand;
      stand.name = prefix + std::to_string(index);
      OGRGeometry* geometry = feature->GetGeometryRef();
      const auto type = geometry ? wkbFlatten(geometry->getGeometryType()) : wkbNone;
      if (type != wkbPolygon && type != wkbMultiPolygon)
        throw input_error(path, stand.name + ": the geometry must be a Polygon or MultiPolygon");
      if (to_wgs84 && geometry->transform(to_wgs84.get()) != OGRERR_NONE)
        throw input_error(
            path, stand.name + ": its coordinates cannot be brought to WGS84" + gdal_cause(trap));
      if (type == wkbPolygon)
        add_polygon(*geometry->toPolygon(), stand.rings);
      else
        for (const OGRPolygon* polygon : *geometry->toMultiPolygon())
          add_polygon(*polygon, stand.rings);
      for (const Ring& ring : stand.rings)
        if (ring.size() < 4)
          throw input_error(path,
                            stand.name + ": bad coordinates (a ring needs at least 4 positions)");
      if (!to_wgs84 && !lon_lat(stand.rings))
        throw input_error(path, stand.name +
                                    ": the file has no CRS and its coordinates are not longitude "
                                    "and latitude: give the file a CRS (a .prj for a Shapefile)");
      if (const std::string where = off_earth(stand.rings); !where.empty())
        throw input_error(path, stand.name + ": a position is not on the Earth (" + where +
                                    " in WGS84): longitude must be in [-180, 360], latitude in "
                                    "[-90, 90]");
      for (const Ring& ring : stand.rings)
        if (encloses_no_area(ring))
          throw input_error(path, stand.name +
                                      ": a ring encloses no area (its positions lie on one "
                                      "line): a stand is a polygon with an area");
      stand.properties = feature_properties(*feature, path, stand.name);
      features.push_back(std::move(stand));
    }
  }
  // An empty file would change nothing, without a word.
  if (features.empty()) throw input_error(path, "holds no feature: no stand to place");
  return features;
}

// A stands file: polygons in any vector format and CRS OGR reads (read_stand_features), whose
// attribute fields override canopy keys inside them. Each feature's canopy is the scene's with
// its fields applied, checked as the configuration is; a fault is the file's (exit status 3),
// named by its feature and key.
std::vector<StandArea> read_stands(const std::string& path, const json& scene_canopy,
                                   const std::vector<LidarBand>& bands) {
  std::vector<StandArea> areas;
  for (StandFeature& feature : read_stand_features(path)) {
    const std::string& where = feature.name;
    StandArea area;
    area.rings = std::move(feature.rings);
    // A stand overrides the scene's canopy inside it: its own stands or crowns would be
    // silently ignored.
    for (const char* key : {"stands", "crowns_file"})
      if (feature.properties.contains(key))
        throw input_error(path, where + ": property " + key +
                                    " cannot be set by a stand (the scene's canopy has one " + key +
                                    " for all of it)");
    json canopy = scene_canopy;
    canopy.erase("stands");
    canopy.erase("crowns_file");
    for (const auto& [key, value] : feature.properties.items()) canopy[key] = value;
    const json document_of_stand = {{"canopy", canopy}};  // the reader keeps a pointer to it
    json resolved = json::object();
    JsonReader root(document_of_stand, "", resolved, configuration_keys());
    try {
      area.canopy = *read_canopy(root, bands);
    } catch (const Error& e) {
      // "/canopy/pai: must be >= 0" becomes "feature 2: pai: must be >= 0".
      const std::string key = e.place().size() > 8 ? e.place().substr(8) : e.place();
      throw input_error(path, where + ": property " + key + ": " + e.message());
    }
    if (area.canopy.crown_shape == CrownShape::layer ||
        scene_canopy.value("crown_shape", "") == "layer")
      throw input_error(
          path, where + ": a layer covers the whole scene: it cannot be a stand, nor have stands");
    areas.push_back(std::move(area));
  }
  return areas;
}

}  // namespace glaswave
