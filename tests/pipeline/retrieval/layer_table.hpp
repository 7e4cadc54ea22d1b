// The turbid-layer table the retrieval tests and benchmark share (PHYSICS.md section 3): a layer
// from 5 to 15 m (crown_shape "layer", spherical leaves) over a plane of soil 0.3, each entry's
// two shots on two points, its PAI varied over [0, 5]; the sensor, its altitude, the rays and the
// entries given.
#pragma once

#include <nlohmann/json.hpp>

namespace glaswave::test_support {

inline nlohmann::json layer_table_configuration(const nlohmann::json& sensor, double altitude_m,
                                                int rays, int entries) {
  return {
      {"sensor", sensor},
      {"simulation", {{"rays_per_shot", rays}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 0.0}, {"origin_lon_deg", 0.0}}}, {"soil_reflectance", 0.3}}},
      {"canopy",
       {{"crown_shape", "layer"},
        {"crown_base_m", {5.0, 5.0}},
        {"crown_half_height_m", 5.0},
        {"dbh_m", 0.0},
        {"pai", 2.0},
        {"cover", 1.0}}},
      {"track",
       {{"type", "points"},
        {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}, {{"lat_deg", 0.001}, {"lon_deg", 0.0}}}},
        {"altitude_m", altitude_m}}},
      {"table",
       {{"vary", {{"canopy.pai", {0.0, 5.0}}}}, {"entries", entries}, {"shots_per_entry", 2}}},
  };
}

}  // namespace glaswave::test_support
