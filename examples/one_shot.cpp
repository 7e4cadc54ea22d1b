// One shot over a plane through glaswave's public API, its received energy per band beside the
// closed form for bare Lambertian ground (PHYSICS.md section 1):
//   E_rec = E_t T A_T rho_s cos(alpha) f_fov / (pi R^2),  f_fov = 1 - exp(-ifov^2 / (8 sigma^2)).
// Build it against an installed glaswave (see CMakeLists.txt here); it exits with status 1 when a
// band is more than 0.5 % off.
#include <cmath>
#include <cstdio>
#include <glaswave/glaswave.hpp>
#include <numbers>

int main() try {
  const double slope_deg = 5.0, soil_reflectance = 0.15;
  // The configuration as the JSON document a file would hold: the seed's sensor (Table 2), one
  // shot aimed from 600 km at a plane tilted toward the east, bare soil, no vegetation.
  const nlohmann::json document = {
      {"sensor", {{"preset", "north2010"}}},
      {"simulation", {{"rays_per_shot", 20000}}},
      {"terrain",
       {{"plane",
         {{"origin_lat_deg", 0.0},
          {"origin_lon_deg", 0.0},
          {"slope_deg", slope_deg},
          {"aspect_deg", 90.0}}},
        {"soil_reflectance", soil_reflectance}}},
      {"canopy", nullptr},
      {"track",
       {{"type", "points"},
        {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}},
        {"altitude_m", 600000.0}}},
  };
  const glaswave::Config config = glaswave::parse_config(document);

  // The terrain, the track planned on it, and the shot simulated where its beam meets the ground.
  const std::unique_ptr<glaswave::Terrain> terrain = glaswave::open_terrain(config);
  const std::unique_ptr<glaswave::Track> track = glaswave::plan_track(config, *terrain);
  const std::unique_ptr<glaswave::ShotSimulator> simulator =
      glaswave::make_shot_simulator(config, *terrain);
  const glaswave::ShotRecord shot = simulator->simulate(track->footprint(0));

  const glaswave::SensorSettings& sensor = config.sensor;
  const double f_fov =
      1.0 - std::exp(-sensor.ifov_rad * sensor.ifov_rad /
                     (8.0 * sensor.divergence_sigma_rad * sensor.divergence_sigma_rad));
  const double cos_alpha = std::cos(slope_deg * std::numbers::pi / 180.0);  // at nadir, alpha = S
  std::printf("one shot at nadir over a %.0f degree slope, range %.1f m\n", slope_deg,
              shot.range_m);
  std::printf("band  simulated (J)  closed form (J)  ratio\n");
  bool agree = true;
  for (std::size_t b = 0; b < sensor.bands.size(); ++b) {
    const glaswave::LidarBand& band = sensor.bands[b];
    const double expected_J = band.pulse_energy_mJ * 1e-3 * band.atmos_transmission_roundtrip *
                              sensor.telescope_area_m2 * soil_reflectance * cos_alpha * f_fov /
                              (std::numbers::pi * shot.range_m * shot.range_m);
    const double ratio = shot.rx_energy_J[b] / expected_J;
    std::printf("%-5s %13.6e  %15.6e  %.4f\n", band.name.c_str(), shot.rx_energy_J[b], expected_J,
                ratio);
    agree = agree && std::abs(ratio - 1.0) < 0.005;
  }
  return agree ? 0 : 1;
} catch (const glaswave::Error& e) {
  std::fprintf(stderr, "one_shot: error: %s\n", e.what());
  return e.exit_status();
}
