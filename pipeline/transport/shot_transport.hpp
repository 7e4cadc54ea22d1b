// The seed's backward Monte Carlo for one shot (section 2.3): rays sampled over the field of
// view; at each interaction along a ray (a leaf or bark element met by free-path sampling in
// turbid foliage, or a surface found by Embree) the direct laser illumination is scored toward
// the detector with the path's total length, and the diffuse light is followed by sampling the
// next scattering, up to max_order. Scores are binned in time, converted to power and
// convolved with the pulse. All bands in one pass, one weight per band.
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "footprints/atmosphere_settings.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/ray_event.hpp"
#include "pipeline/transport/scattering.hpp"

namespace glaswave {

// Rays are tallied in this many contiguous groups, summed in order (the same bits for any thread
// count), each group in a copy of the shot's waveforms, and the sum in one more: what a shot's
// tallies take, for the memory estimate.
inline constexpr std::int64_t transport_ray_groups = 64;
inline constexpr double transport_waveform_copies = transport_ray_groups + 1;

// One shot in its local frame (the footprint's east-north-up frame), double precision.
struct ShotGeometry {
  Vec3 sensor_m{};       // spacecraft position
  Vec3 axis{};           // beam axis, unit, spacecraft -> ground
  double range_m = 0.0;  // to the footprint centre: times are relative to 2 * range_m / c
  // The ground under the footprint centre: its z in the frame and its height above the ellipsoid,
  // where the atmosphere's layers are placed from.
  double ground_z_m = 0.0;
  double ground_height_m = 0.0;
};

// A shot's returns before the pulse shapes them: the energy (J) scored in each tally bin
// (LidarModel::tally_index) that was scored into, those bins in increasing order. A photon-
// counting receiver draws its photons from these and spreads each by the pulse, which is the same
// Poisson process as drawing from the pulse-shaped power.
struct ScoredReturns {
  std::vector<std::uint32_t> bins;
  std::vector<std::vector<double>> total_J, canopy_J, ground_J;  // [band][entry]
  std::vector<std::vector<std::vector<double>>> order_J;         // [band][order - 1][entry]
  std::size_t size() const { return bins.size(); }
};

// The received signal of one shot: [band][bin] power (W) and [band] energy (J).
struct ShotWaveforms {
  std::vector<std::vector<double>> total_W, canopy_W, ground_W;
  // [band][bin] W^2: the Monte Carlo variance of total_W, from the spread of the rays' scores
  // (bins taken as independent: a ray's scores in different bins are not correlated with it).
  std::vector<std::vector<double>> total_variance_W2;
  std::vector<std::vector<std::vector<double>>> order_W;  // [band][order - 1][bin] when asked for
  // The integrals of the power; without power waveforms, the scored energies' sums (the same
  // but for the pulse's tails beyond the window).
  std::vector<double> energy_J, canopy_energy_J, ground_energy_J;
  ScoredReturns scored;  // when TransportOptions::scored_energies
  // [band], with an atmosphere only (else empty): the layers' direct two-way transmission along
  // the beam's axis, exp(-2 tau / mu) of their column above the scene; of the energy returned in
  // the window, the part whose light the layers scattered, and its energy-weighted extra path
  // over the straight one (m, the unscattered light counting 0). NaN where nothing returned.
  std::vector<double> atmosphere_transmission, atmosphere_scattered_fraction, atmosphere_delay_m;
  std::int64_t ray_queries = 0;
};

struct TransportOptions {
  std::int64_t rays = 10000;
  int max_order = 8;
  bool per_order = false;
  std::uint64_t seed = 1;
  // Rays take their beam direction and first free path from the shot's scrambled Sobol' points
  // (sobol_points.hpp) instead of their own streams (simulation.sampling "sobol"). Unbiased, and
  // on the seed's base case the mean waveform's RMS error at equal CPU time is that of 1.9 times
  // the rays; off by default, as plain Monte Carlo's n^-1/2 law (PHYSICS.md section 6) and the
  // per-ray variance the processing weighs its fits with hold only for independent rays.
  bool quasi_random = false;
  // What the shot's returns are given as: the power in the window's bins, pulse-shaped (the
  // waveform receiver's, and every product's but the ICESat-2 granules'), and the energies
  // scored before the pulse (ShotWaveforms::scored, the photon-counting receiver's).
  bool power_waveforms = true;
  bool scored_energies = false;
  // The layers the light crosses above the scene (atmosphere.hpp); absent: none, and each band's
  // fixed atmos_transmission_roundtrip scales the returns instead.
  std::optional<AtmosphereSettings> atmosphere;
};

// Simulates shot `shot_number`. The result depends only on the inputs, never on how many
// threads run it: rays are tallied in fixed chunks that are summed in order.
ShotWaveforms simulate_shot(const Scene& scene, const LidarModel& lidar,
                            const ShotGeometry& geometry, const SceneOptics& optics,
                            const TransportOptions& options, std::int64_t shot_number);

// Ray `ray` of shot `shot_number` alone, exactly as it runs inside the shot of options.rays
// rays (a ray's random numbers depend only on (seed, shot, ray)): the waveforms are that ray's
// part of the shot's, which the shot's are the sum of. `observer`, when set, is told each event
// of the ray's paths, in order (pbrt's flag that re-runs one failing sample).
ShotWaveforms simulate_ray(const Scene& scene, const LidarModel& lidar,
                           const ShotGeometry& geometry, const SceneOptics& optics,
                           const TransportOptions& options, std::int64_t shot_number,
                           std::int64_t ray, const RayObserver& observer = {});

}  // namespace glaswave
