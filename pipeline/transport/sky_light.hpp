// The sky's light in a photon-counting receiver's field of view (issue 40): what a horizontally
// uniform Lambertian scene of reflectance rho under the atmosphere's layers, and the layers
// themselves, send toward a receiver above them looking down at nadir, per unit of the sunlight:
//   R(mu0, rho) = R_path(mu0) + rho T_down(mu0) T_up / (1 - rho S),      R = pi L / (E mu0),
// R_path the layers' own light toward nadir (the sky's radiance seen from above), T_down the
// sunlight reaching the scene, direct and diffuse, T_up the scene's light reaching the top
// toward nadir, direct and diffuse (T_down at the zenith, by reciprocity), S the layers' albedo
// from below (what of the scene's Lambertian light they send back down). Traced by the lidar's
// and brf's own code (AtmosphereModel::cross) over a black ground at sea level, at sun cosines
// 0.05, 0.10, ..., 1, linear in between.
#pragma once

#include <cstdint>
#include <vector>

#include "footprints/atmosphere_settings.hpp"

namespace glaswave {

struct SkyLight {
  std::vector<double> mu_sun, path_reflectance, down_transmission;  // per sun cosine
  double up_transmission = 1.0, spherical_albedo = 0.0;

  // R(mu0, rho) above; 0 with the sun at or below the horizon.
  double reflectance(double mu_sun, double rho) const;
};

// The table for one band of the layers (expanded for `bands` bands), `photons` photons a sun
// cosine (and for S), photon p of node k drawing from RandomStream(seed, k, p, sky); node 20 is
// S's.
SkyLight sky_light(const AtmosphereSettings& settings, std::size_t bands, std::size_t band,
                   std::uint64_t seed, int photons = 10000);

}  // namespace glaswave
