// FLIGHT's solar mode (`glaswave brf`): photons traced forward from the sun into a scene, each
// followed through every scattering until it leaves or is absorbed (or up to max_order), and each
// interaction scored toward every view direction by a local estimate (the element's scattering
// toward the view times the transmittance along it). The connection toward the view shares the gaps
// of the path that brought the photon (the leaf-size correlation of the lidar transport, PHYSICS.md
// section 3), so the hotspot is kept. Over a periodic tile of a plane a path leaving one side comes
// back in at the opposite one, so that nothing leaks out of the scene's sides.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <vector>

#include "footprints/atmosphere_settings.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/scattering.hpp"

namespace glaswave {

// The square tile [-half_size_m, half_size_m]^2 of the scene's local frame the sun lights.
struct BrfTile {
  double half_size_m = 50.0;
  // Paths leaving a side come back in at the opposite one (a synthetic plane). Otherwise they
  // go on through the scene built around the tile and are scored wherever they are.
  bool periodic = true;
  // The ground's gradient (dz/dx, dz/dy): a path wrapped across the tile keeps its height above
  // the ground.
  double ground_slope_x = 0.0, ground_slope_y = 0.0;
};

// Every order: a photon is followed until it leaves the scene or Russian roulette ends it (which
// keeps the estimate unbiased), as FLIGHT does. A cut at the lidar's 8 orders lost 29 % of a
// conservative scene's light (issue 28).
inline constexpr int brf_every_order = std::numeric_limits<int>::max();

struct BrfOptions {
  Vec3 sun_direction{0.0, 0.0, -1.0};  // travel direction of the sunlight, unit
  std::vector<Vec3> views;             // unit, toward the viewer
  std::int64_t photons = 1000000;
  int max_order = brf_every_order;  // the scatterings scored; a smaller number cuts the light
  std::uint64_t seed = 1;
  int image_pixels = 100;  // nadir image: pixels along each side of the tile
  // The layers above the scene's top that the sunlight crosses on its way down and the scene's
  // light on its way up (issue 40), placed as the lidar's are: the frame's origin is on the
  // ground, `ground_height_m` above the ellipsoid. None: the sun lights the scene's top directly,
  // as before (and the same bits). A periodic tile must then be level (the layers are).
  std::optional<AtmosphereSettings> atmosphere;
  double ground_height_m = 0.0;
};

// Per band: the albedo (energy leaving the top after up to max_order scatterings, every one by
// default, over energy entering), each view's bidirectional reflectance factor (the radiance over
// that of a white Lambertian plane under the same sun) and its standard error (from the spread of
// the photons' scores), and the nadir BRF of each pixel of the tile (row 0 to the north, column 0
// to the west).
//
// RAMI's split and fluxes, per incident photon: each view's BRF in its parts (light scattered once
// by the canopy, once by the soil alone, and two or more times: RAMI's co_sgl, uc_sgl and mlt,
// which sum to the BRF), the canopy's absorption (every element but the ground) and the
// transmission to the ground (every arrival there, direct and diffuse, before the soil reflects
// it), each with its standard error. Energy closes: albedo + absorption + transmission times the
// soil's absorptance = 1, within the Monte Carlo error (Russian roulette keeps it in expectation).
//
// With the layers (BrfOptions::atmosphere), every one of those is of the scene's top under the
// light that reaches it there, direct and diffuse, all of it over all of it: the albedo is the
// energy leaving the top over the energy entering it, the BRF the radiance over that of a white
// Lambertian plane under the same light (the hemispherical-directional reflectance factor), the
// fluxes per energy entering, the image the same; each photon's share entering weights its
// scores (ratio estimates, their standard errors by the delta method). Beside them, per unit of
// the sunlight at the top of the layers (BrfSky): what reaches the scene's top the first time,
// unscattered (exp(-tau / mu_sun)) and scattered by the layers, and all that reaches it (the
// light the layers send back down included); the reflectance at the top of the layers (its
// albedo, and per view the radiance over that of a white plane under the sun without them,
// pi L / (E mu_sun)); the layers' absorption, and the closure (that albedo plus every
// absorption: the layers', the canopy's, the soil's), 1 within the Monte Carlo error.
enum BrfPart { brf_canopy_once = 0, brf_soil_once = 1, brf_many_times = 2, brf_parts = 3 };

struct BrfSky {
  std::vector<double> direct, direct_stderr;         // [band]: at the scene's top, unscattered
  std::vector<double> diffuse, diffuse_stderr;       // [band]: at the scene's top, scattered
  std::vector<double> downward, downward_stderr;     // [band]: every arrival at the scene's top
  std::vector<double> albedo, albedo_stderr;         // [band]: at the top of the layers
  std::vector<std::vector<double>> brf, brf_stderr;  // [band][view]: at the top of the layers
  std::vector<double> absorbed, absorbed_stderr;     // [band]: by the layers
  std::vector<double> closure, closure_stderr;       // [band]
};

struct BrfResult {
  std::vector<double> albedo, albedo_stderr;
  std::vector<double> absorbed, absorbed_stderr;        // [band]: the canopy's absorption
  std::vector<double> transmitted, transmitted_stderr;  // [band]: reaching the ground
  // [band]: albedo + absorption + transmission (1 - soil reflectance), photon by photon
  std::vector<double> closure, closure_stderr;
  std::vector<std::vector<double>> brf, brf_stderr;                              // [band][view]
  std::vector<std::vector<double>> part_brf[brf_parts], part_stderr[brf_parts];  // [band][view]
  std::vector<std::vector<double>> image;  // [band][row * image_pixels + column]
  std::optional<BrfSky> sky;               // with the layers
  std::int64_t ray_queries = 0;
};

// Photons are traced in batches of this many; photon p of the run draws from
// RandomStream(seed, p / batch, p % batch, RandomPurpose::sun).
inline constexpr std::int64_t brf_batch_photons = 1024;

// Called after each group of batches with (photons done, photons in all).
using BrfProgress = std::function<void(std::int64_t, std::int64_t)>;

// Traces options.photons photons through the scene on the current TBB arena. The result is the
// same bits for any thread count: batches are tallied apart and summed in order.
BrfResult simulate_brf(const Scene& scene, const SceneOptics& optics, const BrfTile& tile,
                       const BrfOptions& options, const BrfProgress& progress = {});

}  // namespace glaswave
