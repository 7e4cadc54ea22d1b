// Checks across keys, made on the whole configuration once its sections are read: what no
// single key's reading can see (issue 28). check, run, brf and Python refuse alike, since
// parse_config makes them.
#pragma once

#include <nlohmann/json.hpp>

#include "pipeline/config/config.hpp"

namespace glaswave {

// Keys of one type of track given with another (`points` with a pass, `start_lat_deg` with an
// orbit or a granule), which that track would ignore, are refused at their place: exit 2. A value
// that says no more than the key's absence (its default, an empty list: what the resolved
// configuration holds) passes, so that a resolved configuration parses back.
void check_track_type_keys(const nlohmann::json& document, TrackType type,
                           const nlohmann::json& resolved_track);

// Two bands with one wavelength (the products' `band` coordinate would not be unique) are
// refused at the second one's wavelength_nm.
void check_band_wavelengths(const std::vector<LidarBand>& bands);

// terrain.point_cloud without a canopy.point_cloud to take the ground of is refused at
// /terrain/point_cloud.
void check_point_cloud_ground(const Config& config);

void check_across_keys(const nlohmann::json& document, const Config& config);

}  // namespace glaswave
