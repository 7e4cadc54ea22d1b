// Monte Carlo transport of one shot.
#include "pipeline/transport/shot_transport.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "core/random.hpp"

namespace glaswave {
namespace {

// Rays are tallied in a fixed number of contiguous groups, summed in order: the result is the
// same bits for any thread count, and memory does not grow with the rays.
constexpr std::int64_t ray_groups = 64;

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

enum class Vertex { leaf, ground, trunk };

struct Interaction {
  double distance_m;
  int material;
};

// Where the accumulated optical depth along the ray reaches `target`, within the spans
// (overlapping spans add their extinctions), and which foliage the ray met there, chosen in
// proportion to each one's extinction at that point; empty if the depth is never reached.
template <class Uniform>
std::optional<Interaction> free_path(const std::vector<VolumeSpan>& spans,
                                     const std::vector<double>& projection, double target,
                                     Uniform&& uniform) {
  if (spans.empty()) return std::nullopt;
  // One sweep over span ends: extinction added where a span starts, removed where it ends.
  thread_local std::vector<std::pair<double, double>> events;
  events.clear();
  for (const VolumeSpan& span : spans) {
    const double extinction = span.area_density_m2_m3 * projection[span.material];
    events.emplace_back(span.start_m, extinction);
    events.emplace_back(span.end_m, -extinction);
  }
  std::sort(events.begin(), events.end());
  double extinction = 0.0, depth = 0.0, t_previous = events.front().first;
  for (const auto& [t, change] : events) {
    if (extinction > 0.0 && t > t_previous) {
      const double step = extinction * (t - t_previous);
      if (depth + step >= target) {
        const double at = t_previous + (target - depth) / extinction;
        // The spans covering the point share the interaction by their extinction.
        double pick = uniform() * extinction;
        int material = spans.front().material;
        for (const VolumeSpan& span : spans) {
          if (span.start_m > at || span.end_m <= at) continue;
          material = span.material;
          pick -= span.area_density_m2_m3 * projection[span.material];
          if (pick < 0.0) break;
        }
        return Interaction{at, material};
      }
      depth += step;
    }
    t_previous = t;
    extinction += change;
  }
  return std::nullopt;
}

// Optical depth along a connection ray whose first `shared_m` metres run close to a path
// already sampled, at separation angle `separation_rad`: over a length l the two paths are
// l * separation apart, and where that is less than a leaf they see the same gaps, so only a
// fraction 1 - exp(-l separation / leaf_size) of the foliage there is new (Kuusk's hotspot).
double connection_depth(const std::vector<VolumeSpan>& spans, const std::vector<double>& projection,
                        const std::vector<Foliage>& foliage, double shared_m,
                        double separation_rad) {
  double depth = 0.0;
  for (const VolumeSpan& span : spans) {
    const double leaf_size_m = foliage[span.material].leaf_size_m;
    const double rate =
        leaf_size_m > 0.0 ? separation_rad / leaf_size_m : std::numeric_limits<double>::infinity();
    const double a = span.start_m, b = std::min(span.end_m, shared_m);
    double length =
        std::max(0.0, span.end_m - std::max(span.start_m, shared_m));  // beyond the shared part
    if (b > a) {
      if (std::isinf(rate))
        length += b - a;
      else if (rate > 0.0)
        length += (b - a) - (std::exp(-rate * a) - std::exp(-rate * b)) / rate;
    }
    depth += span.area_density_m2_m3 * projection[span.material] * length;
  }
  return depth;
}

// A direction about `normal`, cosine-weighted.
Vec3 cosine_direction(const Vec3& normal, double u1, double u2) {
  const Vec3 helper = std::abs(normal[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{1.0, 0.0, 0.0};
  const Vec3 across = normalized(cross(helper, normal));
  const Vec3 along = cross(normal, across);
  const double r = std::sqrt(u1), phi = 2.0 * std::numbers::pi * u2;
  return (r * std::cos(phi)) * across + (r * std::sin(phi)) * along +
         std::sqrt(std::max(0.0, 1.0 - u1)) * normal;
}

void trace_chunk(const Scene& scene, const LidarModel& lidar, const ShotGeometry& geometry,
                 const SceneOptics& optics, const TransportOptions& options,
                 std::int64_t shot_number, std::int64_t first_ray, std::int64_t last_ray,
                 Tally& tally) {
  const BeamSampler beam(lidar, geometry.axis);
  const std::size_t bands = lidar.band_count();
  const double two_sigma_sq = 2.0 * lidar.beam_sigma_rad() * lidar.beam_sigma_rad();
  const double range_m = geometry.range_m;
  // Rays start just above the scene, so Embree's float coordinates stay small.
  const double start_height_m = scene.top_m() + 1.0;
  const bool foliage = scene.has_volumes();
  constexpr double surface_offset_m = 1e-4;
  constexpr double far_m = 1.0e5;
  std::vector<VolumeSpan> spans;
  std::vector<double> throughput(bands), response(bands);
  std::vector<double> projection(optics.foliage.size());  // G of each foliage for one direction
  bool any_point_leaves = false;
  for (const Foliage& f : optics.foliage)
    any_point_leaves = any_point_leaves || f.leaf_size_m == 0.0;
  auto project = [&](const Vec3& d) {
    for (std::size_t m = 0; m < optics.foliage.size(); ++m)
      projection[m] = optics.foliage[m].leaf_angles->projection(d[2]);
  };
  auto angle_from_axis = [&](const Vec3& d) {
    return std::atan2(norm(cross(d, geometry.axis)), dot(d, geometry.axis));
  };
  // The beam's irradiance in a direction, as a density over the field of view (per sr):
  // exp(-theta^2 / 2 sigma^2) / (2 pi sigma^2 f_fov). The beam path's rays are drawn by it.
  auto beam_density = [&](const Vec3& d) {
    return std::exp(-std::pow(angle_from_axis(d), 2) / two_sigma_sq) /
           (std::numbers::pi * two_sigma_sq * lidar.fov_fraction());
  };
  const double uniform_density = 1.0 / lidar.fov_solid_angle_sr();

  // Each ray traces two paths. The first, drawn by the beam's irradiance, scores the single
  // scattering: the laser lights its first interaction down the very path sampled, so every ray
  // carries the same weight and a bare surface's energy comes out to round-off. The second
  // scores orders 2 and up: multiply scattered light reaches the detector from anywhere in its
  // view, so it is drawn half by the beam and half uniformly over the field of view. Drawn by
  // the beam alone, a ray in the beam's tail would weigh exp(theta^2 / 2 sigma^2), without
  // bound (e^23 at the edge of GLAS's view); the mixture bounds the weight by 2 Omega_fov.
  for (std::int64_t ray = first_ray; ray < last_ray; ++ray) {
    RayRandom random(options.seed, shot_number, ray);
    auto uniform = [&random] { return random.uniform(); };
    for (const bool beam_path : {true, false}) {
      if (!beam_path && options.max_order < 2) break;
      const bool by_beam = beam_path || random.uniform() < 0.5;
      const double u1 = random.uniform(), u2 = random.uniform();
      const Vec3 first_direction =
          by_beam ? beam.direction(u1, u2) : beam.uniform_direction(u1, u2);
      // Density the second path's first direction was drawn with (the mixture); the beam path
      // scores only its first interaction and never needs it.
      const double path_density =
          beam_path ? 0.0 : 0.5 * beam_density(first_direction) + 0.5 * uniform_density;
      const double start_m = (geometry.sensor_m[2] - start_height_m) / -first_direction[2];

      Vec3 position = geometry.sensor_m + start_m * first_direction;
      Vec3 direction = first_direction;
      double path_m = start_m;  // from the detector to `position` along the path
      double min_distance_m = 0.0;
      std::fill(throughput.begin(), throughput.end(), 1.0);
      bool canopy_return = false;

      for (int order = 1; order <= options.max_order; ++order) {
        // The next interaction: foliage by free-path sampling, but never beyond the nearest
        // surface.
        const SurfaceHit hit = scene.intersect(position, direction, far_m, min_distance_m);
        ++tally.ray_queries;
        std::optional<Interaction> leaf;
        if (foliage) {
          scene.volume_spans(position, direction,
                             hit.kind == SurfaceKind::none ? far_m : hit.distance_m, spans);
          ++tally.ray_queries;
          project(direction);
          leaf = free_path(spans, projection, -std::log1p(-random.uniform()), uniform);
        }
        if (!leaf && hit.kind == SurfaceKind::none) break;  // left the scene
        const Vertex vertex = leaf                              ? Vertex::leaf
                              : hit.kind == SurfaceKind::ground ? Vertex::ground
                                                                : Vertex::trunk;
        const double segment_m = leaf ? leaf->distance_m : hit.distance_m;
        const Foliage* material = leaf                      ? &optics.foliage[leaf->material]
                                  : vertex == Vertex::trunk ? &optics.foliage[hit.material]
                                                            : nullptr;
        const Vec3 point = position + segment_m * direction;
        path_m += segment_m;
        if (order == 1) canopy_return = vertex != Vertex::ground;

        // The element met: a leaf normal drawn for this direction, or the surface's.
        const Vec3 normal =
            leaf ? material->leaf_angles->sample_normal(direction, uniform) : hit.normal;

        // Direct laser light at the point, scored toward the detector. The laser sits with the
        // detector: at the first interaction its light comes down the very path sampled, and with
        // finite leaves it finds the same gaps (the hotspot, PHYSICS.md section 3).
        const Vec3 to_laser = geometry.sensor_m - point;
        const double laser_m = norm(to_laser);
        const Vec3 up_to_laser = (1.0 / laser_m) * to_laser;
        const Vec3 laser_light = -1.0 * up_to_laser;  // travel direction of the laser's light
        double transmission = 1.0, beam_ratio = 1.0;
        const bool scored = beam_path || order > 1;
        if (order > 1) {
          // Surfaces between the point and the laser block it.
          const double exit_m = (start_height_m - point[2]) / up_to_laser[2];
          if (scene.occluded(point, up_to_laser, exit_m, surface_offset_m)) transmission = 0.0;
          ++tally.ray_queries;
          // The laser's light at the point, over the density of the detector ray that found it.
          beam_ratio = beam_density(laser_light) / path_density;
        }
        // At the first interaction with finite leaves only, the way out needs no second look.
        if (scored && foliage && transmission > 0.0 && (order > 1 || any_point_leaves)) {
          const double exit_m = (start_height_m - point[2]) / up_to_laser[2];
          scene.volume_spans(point, up_to_laser, exit_m, spans);
          ++tally.ray_queries;
          // The connection runs beside the segment just sampled (traced back from the point).
          const double separation_rad =
              std::acos(std::clamp(dot(up_to_laser, -1.0 * direction), -1.0, 1.0));
          const double shared_m = order == 1 ? std::numeric_limits<double>::infinity() : segment_m;
          project(up_to_laser);
          transmission *= std::exp(-connection_depth(spans, projection, optics.foliage, shared_m,
                                                     order == 1 ? 0.0 : separation_rad));
        }
        if (scored && transmission > 0.0) {
          const double scale =
              transmission * beam_ratio * (range_m / laser_m) * (range_m / laser_m);
          const double time_ns = (laser_m + path_m - 2.0 * range_m) / speed_of_light_m_s * 1e9;
          const int bin = lidar.tally_index(time_ns);
          const Vec3 toward_detector = -1.0 * direction;
          for (std::size_t band = 0; band < bands; ++band) {
            double element = 0.0;
            if (vertex == Vertex::leaf) {
              element =
                  bilambertian_response(normal, laser_light, toward_detector,
                                        material->reflectance[band], material->transmittance[band]);
            } else {
              const double reflectance = vertex == Vertex::ground
                                             ? optics.soil_reflectance[band]
                                             : material->trunk_reflectance[band];
              element = reflectance * std::max(0.0, dot(normal, up_to_laser));
            }
            response[band] = throughput[band] * element * scale;
          }
          if (bin >= 0) {
            for (std::size_t band = 0; band < bands; ++band) {
              const std::size_t at = band * tally.size + bin;
              tally.total[at] += response[band];
              (canopy_return ? tally.canopy : tally.ground)[at] += response[band];
              if (order <= tally.orders)
                tally.order[(band * tally.orders + order - 1) * tally.size + bin] += response[band];
            }
          }
        }
        if (beam_path || order == options.max_order) break;

        // The diffuse light: where the light scattered here toward the detector came from.
        const Vec3 back = -1.0 * direction;  // the side the path arrived from
        if (vertex == Vertex::leaf) {
          // Reflection sends the path back to the side it came from, transmission through.
          double reflected = 0.0, transmitted = 0.0;
          for (std::size_t band = 0; band < bands; ++band) {
            reflected += throughput[band] * material->reflectance[band];
            transmitted += throughput[band] * material->transmittance[band];
          }
          if (reflected + transmitted <= 0.0) break;
          const double p_reflect = reflected / (reflected + transmitted);
          const bool reflect = random.uniform() < p_reflect;
          const Vec3 facing = dot(normal, back) >= 0.0 ? normal : -1.0 * normal;
          const double v1 = random.uniform(), v2 = random.uniform();
          direction = cosine_direction(reflect ? facing : -1.0 * facing, v1, v2);
          for (std::size_t band = 0; band < bands; ++band)
            throughput[band] *= reflect ? material->reflectance[band] / p_reflect
                                        : material->transmittance[band] / (1.0 - p_reflect);
          position = point;
          min_distance_m = 0.0;
        } else {
          const double v1 = random.uniform(), v2 = random.uniform();
          direction = cosine_direction(normal, v1, v2);
          for (std::size_t band = 0; band < bands; ++band)
            throughput[band] *= vertex == Vertex::ground ? optics.soil_reflectance[band]
                                                         : material->trunk_reflectance[band];
          position = point;
          min_distance_m = surface_offset_m;
        }
        // Russian roulette on faint paths keeps the estimate unbiased and the work bounded.
        const double strongest = *std::max_element(throughput.begin(), throughput.end());
        if (strongest <= 0.0) break;
        if (strongest < 0.05) {
          if (random.uniform() >= 0.5) break;
          for (double& weight : throughput) weight *= 2.0;
        }
      }
    }
  }
}

}  // namespace

ShotWaveforms simulate_shot(const Scene& scene, const LidarModel& lidar,
                            const ShotGeometry& geometry, const SceneOptics& optics,
                            const TransportOptions& options, std::int64_t shot_number) {
  const std::size_t bands = lidar.band_count();
  const int orders = options.per_order ? options.max_order : 0;
  const std::int64_t groups = std::min(ray_groups, options.rays);
  std::vector<Tally> chunk_tallies(groups, Tally(bands, lidar.tally_size(), orders));
  tbb::parallel_for(std::int64_t{0}, groups, [&](std::int64_t group) {
    trace_chunk(scene, lidar, geometry, optics, options, shot_number, group * options.rays / groups,
                (group + 1) * options.rays / groups, chunk_tallies[group]);
  });
  Tally tally(bands, lidar.tally_size(), orders);
  for (const Tally& chunk : chunk_tallies) tally += chunk;

  ShotWaveforms waveforms;
  waveforms.ray_queries = tally.ray_queries;
  const double bin_s = lidar.sensor().bin_ns * 1e-9;
  const double range_m = geometry.range_m;
  auto slice = [&](const std::vector<double>& flat, std::size_t row, double scale) {
    std::vector<double> energy_J(flat.begin() + row * tally.size,
                                 flat.begin() + (row + 1) * tally.size);
    for (double& value : energy_J) value *= scale;
    return lidar.power_W(energy_J);
  };
  auto integral_J = [&](const std::vector<double>& power_W) {
    double sum = 0.0;
    for (double value : power_W) sum += value * bin_s;
    return sum;
  };
  for (std::size_t band = 0; band < bands; ++band) {
    const LidarBand& b = lidar.sensor().bands[band];
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
      for (int k = 0; k < orders; ++k)
        waveforms.order_W.back().push_back(slice(tally.order, band * orders + k, scale));
    }
  }
  return waveforms;
}

}  // namespace glaswave
