// Checks across keys (issue 28): keys of another track type, bands sharing a wavelength, a
// point cloud's ground without a point cloud.
#include "pipeline/config/cross_checks.hpp"

#include <string>

#include "canopy/vegetation_traits.hpp"
#include "core/error.hpp"
#include "core/part_kind.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/config/keys.hpp"

namespace glaswave {
namespace {

struct TrackKey {
  const char* key;
  TrackType type;  // the one type that reads it
};

// The keys that one type of track alone reads (footprints/track.cpp); the others (shots,
// rate_hz, altitude_m, start_time, the pointing) are shared.
constexpr TrackKey track_keys[] = {
    {"start_lat_deg", TrackType::pass},     {"start_lon_deg", TrackType::pass},
    {"heading_deg", TrackType::pass},       {"spacing_m", TrackType::pass},
    {"points", TrackType::points},          {"semi_major_axis_m", TrackType::orbit},
    {"eccentricity", TrackType::orbit},     {"inclination_deg", TrackType::orbit},
    {"raan_deg", TrackType::orbit},         {"arg_perigee_deg", TrackType::orbit},
    {"mean_anomaly_deg", TrackType::orbit}, {"epoch", TrackType::orbit},
    {"ephemeris", TrackType::ephemeris},    {"file", TrackType::granule},
    {"beams", TrackType::granule},
};

const char* type_name(TrackType type) {
  switch (type) {
    case TrackType::pass:
      return "pass";
    case TrackType::points:
      return "points";
    case TrackType::orbit:
      return "orbit";
    case TrackType::ephemeris:
      return "ephemeris";
    case TrackType::granule:
      return "granule";
  }
  return "?";
}

// Whether `value` of another type's key says no more than its absence would: null, an empty
// list, its declared default, or (epoch) the start time. The resolved configuration holds these
// for every key, and parses back.
bool as_if_absent(const char* key, const nlohmann::json& value, const nlohmann::json& resolved) {
  if (value.is_null() || (value.is_array() && value.empty())) return true;
  if (std::string(key) == "epoch") {
    if (!resolved.is_object()) return false;
    const auto start_time = resolved.find("start_time");
    return start_time != resolved.end() && value == *start_time;
  }
  const Key* declared = configuration_keys().child("track")->child(key);
  return declared && !declared->default_value.is_null() && value == declared->default_value;
}

}  // namespace

void check_track_type_keys(const nlohmann::json& document, TrackType type,
                           const nlohmann::json& resolved_track) {
  if (!document.is_object()) return;
  const auto track = document.find("track");
  if (track == document.end() || !track->is_object()) return;
  for (const TrackKey& owned : track_keys) {
    if (owned.type == type) continue;
    const auto value = track->find(owned.key);
    if (value == track->end() || as_if_absent(owned.key, *value, resolved_track)) continue;
    throw config_error(std::string("/track/") + owned.key,
                       std::string("is a key of a track of type \"") + type_name(owned.type) +
                           "\", which this track (type \"" + type_name(type) +
                           "\") would ignore: remove it or set track.type");
  }
}

void check_band_wavelengths(const std::vector<LidarBand>& bands) {
  for (std::size_t b = 1; b < bands.size(); ++b) {
    for (std::size_t a = 0; a < b; ++a) {
      if (bands[a].wavelength_nm != bands[b].wavelength_nm) continue;
      throw config_error("/sensor/bands/" + std::to_string(b) + "/wavelength_nm",
                         "is also that of band " + quoted_excerpt(bands[a].name) + " (" +
                             format_number(bands[a].wavelength_nm) +
                             " nm): the products' band coordinate needs a wavelength of its own "
                             "for each band");
    }
  }
}

void check_point_cloud_ground(const Config& config) {
  if (!config.terrain.point_cloud ||
      (config.canopy && declared_traits<VegetationTraits>(config.canopy->kind)
                            .value_or(VegetationTraits{})
                            .ground_points))
    return;
  throw config_error("/terrain/point_cloud",
                     "is the ground of canopy.point_cloud's cloud, and the canopy has no point "
                     "cloud: give canopy.point_cloud, or the ground as \"dem\" or \"plane\"");
}

void check_across_keys(const nlohmann::json& document, const Config& config) {
  check_track_type_keys(document, config.track.type, config.resolved["track"]);
  check_band_wavelengths(config.sensor.bands);
  check_point_cloud_ground(config);
}

}  // namespace glaswave
