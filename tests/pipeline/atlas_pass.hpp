// The ICESat-2 tests' and benchmark's pass: one ATLAS beam 0.7 m a shot northward from (10 N,
// 0 E) at 496 km over a level plane at 100 m (soil reflectance 0.15) with the seed's Table 1
// forest on it, at noon of the 2019 March equinox (the sun 10 degrees from the zenith), 3
// scattering orders, the granules written alone. Each test changes what it needs.
#pragma once

#include <cstdint>
#include <nlohmann/json.hpp>

namespace glaswave::test_support {

inline nlohmann::json atlas_pass(int shots, int rays, std::uint64_t seed) {
  return {
      {"seed", seed},
      {"sensor", {{"preset", "atlas"}}},
      {"simulation", {{"rays_per_shot", rays}, {"max_order", 3}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 10.0}, {"origin_lon_deg", 0.0}, {"elevation_m", 100.0}}},
        {"soil_reflectance", 0.15}}},
      {"canopy", nlohmann::json::object()},  // {}: Table 1
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", 10.0},
        {"start_lon_deg", 0.0},
        {"heading_deg", 0.0},
        {"shots", shots},
        {"spacing_m", 0.7},
        {"altitude_m", 496000.0},
        {"start_time", "2019-03-20T12:00:00Z"}}},
      {"output", {{"netcdf", false}, {"footprints", false}}},
  };
}

}  // namespace glaswave::test_support
