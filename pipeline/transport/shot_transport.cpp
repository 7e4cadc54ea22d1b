// Monte Carlo transport of one shot.
#include "pipeline/transport/shot_transport.hpp"

#include <cmath>
#include <numbers>

#include <tbb/parallel_for.h>

#include "pipeline/transport/random.hpp"

namespace glaswave {
namespace {

constexpr std::int64_t rays_per_chunk = 4096;

// Normalised returns of a group of rays, per band and tally bin. A return's weight is its
// part of E_t T A_T f_fov / (pi R^2) per ray: a Lambertian surface of reflectance rho seen
// square-on at the reference range weighs rho.
struct Tally {
  Tally(std::size_t bands, int size, int orders)
      : size(size),
        orders(orders),
        total(bands * size, 0.0),
        canopy(bands * size, 0.0),
        ground(bands * size, 0.0),
        order(bands * orders * size, 0.0) {}

  Tally& operator+=(const Tally& other) {
    for (std::size_t i = 0; i < total.size(); ++i) total[i] += other.total[i];
    for (std::size_t i = 0; i < canopy.size(); ++i) canopy[i] += other.canopy[i];
    for (std::size_t i = 0; i < ground.size(); ++i) ground[i] += other.ground[i];
    for (std::size_t i = 0; i < order.size(); ++i) order[i] += other.order[i];
    ray_queries += other.ray_queries;
    return *this;
  }

  int size, orders;
  std::vector<double> total, canopy, ground, order;
  std::int64_t ray_queries = 0;
};

void trace_chunk(const Scene& scene, const LidarModel& lidar, const ShotGeometry& geometry,
                 const SceneOptics& optics, const TransportOptions& options, std::int64_t shot_number,
                 std::int64_t first_ray, std::int64_t last_ray, Tally& tally) {
  const BeamSampler beam(lidar, geometry.axis);
  const std::size_t bands = lidar.band_count();
  // Rays start just above the scene, so Embree's float coordinates stay small.
  const double start_height_m = scene.top_m() + 1.0;
  for (std::int64_t ray = first_ray; ray < last_ray; ++ray) {
    RayRandom random(options.seed, shot_number, ray);
    const double u1 = random.uniform(), u2 = random.uniform();
    const Vec3 direction = beam.direction(u1, u2);
    const double start_m = (geometry.sensor_m[2] - start_height_m) / -direction[2];
    const Vec3 origin = geometry.sensor_m + start_m * direction;
    const SurfaceHit hit = scene.intersect(origin, direction, 1.0e5);
    ++tally.ray_queries;
    if (hit.kind == SurfaceKind::none) continue;

    // The way back to the detector is the way in (a monostatic lidar): the return leaves the
    // surface at the same angle the light arrived, and travels the same path.
    const double path_m = start_m + hit.distance_m;
    const double cos_exit = dot(hit.normal, -1.0 * direction);
    const double spread = (geometry.range_m / path_m) * (geometry.range_m / path_m);
    const double time_ns = 2.0 * (path_m - geometry.range_m) / speed_of_light_m_s * 1e9;
    const int bin = lidar.tally_index(time_ns);
    if (bin < 0) continue;
    for (std::size_t band = 0; band < bands; ++band) {
      const double weight = optics.soil_reflectance[band] * cos_exit * spread;
      const std::size_t at = band * tally.size + bin;
      tally.total[at] += weight;
      tally.ground[at] += weight;
      if (tally.orders > 0) tally.order[(band * tally.orders + 0) * tally.size + bin] += weight;
    }
  }
}

}  // namespace

ShotWaveforms simulate_shot(const Scene& scene, const LidarModel& lidar, const ShotGeometry& geometry,
                            const SceneOptics& optics, const TransportOptions& options,
                            std::int64_t shot_number) {
  const std::size_t bands = lidar.band_count();
  const int orders = options.per_order ? options.max_order : 0;
  const std::int64_t chunks = (options.rays + rays_per_chunk - 1) / rays_per_chunk;
  std::vector<Tally> chunk_tallies(chunks, Tally(bands, lidar.tally_size(), orders));
  tbb::parallel_for(std::int64_t{0}, chunks, [&](std::int64_t chunk) {
    const std::int64_t first = chunk * rays_per_chunk;
    trace_chunk(scene, lidar, geometry, optics, options, shot_number, first,
                std::min(first + rays_per_chunk, options.rays), chunk_tallies[chunk]);
  });
  Tally tally(bands, lidar.tally_size(), orders);
  for (const Tally& chunk : chunk_tallies) tally += chunk;

  ShotWaveforms waveforms;
  waveforms.ray_queries = tally.ray_queries;
  const double bin_s = lidar.sensor().bin_ns * 1e-9;
  const double range_m = geometry.range_m;
  auto slice = [&](const std::vector<double>& flat, std::size_t row, double scale) {
    std::vector<double> energy_J(flat.begin() + row * tally.size, flat.begin() + (row + 1) * tally.size);
    for (double& value : energy_J) value *= scale;
    return lidar.power_W(energy_J);
  };
  auto integral_J = [&](const std::vector<double>& power_W) {
    double sum = 0.0;
    for (double value : power_W) sum += value * bin_s;
    return sum;
  };
  for (std::size_t band = 0; band < bands; ++band) {
    const Band& b = lidar.sensor().bands[band];
    // Section 1 of PHYSICS.md: E_t T A_T f_fov / (pi R^2), shared by the rays.
    const double scale = b.pulse_energy_mJ * 1e-3 * b.atmos_transmission_roundtrip *
                         lidar.sensor().telescope_area_m2 * lidar.fov_fraction() /
                         (std::numbers::pi * range_m * range_m) / static_cast<double>(options.rays);
    waveforms.total_W.push_back(slice(tally.total, band, scale));
    waveforms.canopy_W.push_back(slice(tally.canopy, band, scale));
    waveforms.ground_W.push_back(slice(tally.ground, band, scale));
    waveforms.energy_J.push_back(integral_J(waveforms.total_W.back()));
    waveforms.canopy_energy_J.push_back(integral_J(waveforms.canopy_W.back()));
    waveforms.ground_energy_J.push_back(integral_J(waveforms.ground_W.back()));
    if (orders > 0) {
      waveforms.order_W.emplace_back();
      for (int k = 0; k < orders; ++k) waveforms.order_W.back().push_back(slice(tally.order, band * orders + k, scale));
    }
  }
  return waveforms;
}

}  // namespace glaswave
