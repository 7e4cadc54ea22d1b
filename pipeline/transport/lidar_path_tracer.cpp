// One lidar ray's paths through the scene (lidar_path_tracer.hpp): the beam sampled, the next
// element found, the direct return scored toward the detector (through the atmosphere's layers
// where the shot has them) and binned, the diffuse light scattered, faint paths rouletted.
#include "pipeline/transport/lidar_path_tracer.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

namespace glaswave::lidar_paths {

PathTracer::PathTracer(const Scene& scene, const LidarModel& lidar, const ShotGeometry& geometry,
                       const SceneOptics& optics, const TransportOptions& options,
                       std::int64_t shot_number, const RayObserver* observer)
    : scene_(scene),
      lidar_(lidar),
      geometry_(geometry),
      optics_(optics),
      options_(options),
      shot_number_(shot_number),
      observer_(observer),
      beam_(lidar, geometry.axis),
      bands_(lidar.band_count()),
      two_sigma_sq_(2.0 * lidar.beam_sigma_rad() * lidar.beam_sigma_rad()),
      uniform_density_(1.0 / lidar.fov_solid_angle_sr()),
      start_height_m_(scene.top_m() + 1.0),
      foliage_(scene.has_volumes()),
      throughput_(bands_),
      response_(bands_),
      factor_(bands_),
      projection_(optics.foliage.size()),
      points_(options.seed, static_cast<std::uint64_t>(shot_number)) {
  for (const Foliage& f : optics.foliage)
    any_point_leaves_ = any_point_leaves_ || f.leaf_size_m == 0.0;
  if (options.atmosphere)
    atmosphere_.emplace(*options.atmosphere, bands_, geometry.ground_z_m, geometry.ground_height_m,
                        start_height_m_);
}

// Each ray traces two paths. The first, drawn by the beam's irradiance, scores the single
// scattering: the laser lights its first interaction down the very path sampled, so every ray
// carries the same weight and a bare surface's energy comes out to round-off. The second
// scores orders 2 and up: multiply scattered light reaches the detector from anywhere in its
// view, so it is drawn half by the beam and half uniformly over the field of view. Drawn by
// the beam alone, a ray in the beam's tail would weigh exp(theta^2 / 2 sigma^2), without
// bound (e^23 at the edge of GLAS's view); the mixture bounds the weight by 2 Omega_fov.
void PathTracer::trace_ray(std::int64_t ray, Tally& tally) {
  RayRandom random(options_.seed, shot_number_, ray);
  ray_ = ray;
  trace_path(true, random, tally);
  if (options_.max_order >= 2) trace_path(false, random, tally);
  tally_squares(tally);
}

// The ray's score in each bin it reached, squared, into the tally; the ray's list emptied.
void PathTracer::tally_squares(Tally& tally) {
  for (std::size_t entry = 0; entry < ray_bins_.size(); ++entry)
    for (std::size_t band = 0; band < bands_; ++band) {
      const double score = ray_scores_[entry * bands_ + band];
      tally.squares[band * tally.size + ray_bins_[entry]] += score * score;
    }
  ray_bins_.clear();
  ray_scores_.clear();
}

void PathTracer::trace_path(bool beam_path, RayRandom& random, Tally& tally) {
  Path path = sample_beam(beam_path, random);
  if (path.lost) {
    emit(RayEventKind::leave, path, path.position, nullptr);
    return;
  }
  emit(RayEventKind::enter, path, path.position, nullptr);
  for (int order = 1; order <= options_.max_order; ++order) {
    const std::optional<Vertex> vertex = find_vertex(path, random, tally);
    if (!vertex) {
      emit(RayEventKind::leave, path, path.position, nullptr);
      return;
    }
    path.path_m += vertex->segment_m;
    path.order = order;
    if (order == 1) path.canopy_return = vertex->element != RayElement::ground;
    emit(RayEventKind::interaction, path, vertex->point, &*vertex);
    // The second path's first interaction is the beam path's to score.
    if (beam_path || order > 1) score_direct(path, *vertex, order, tally, random);
    if (beam_path || order == options_.max_order) {
      emit(RayEventKind::end, path, vertex->point, &*vertex);
      return;
    }
    if (!scatter(path, *vertex, random) || !survives_roulette(path, random)) {
      emit(RayEventKind::absorbed, path, vertex->point, &*vertex);
      return;
    }
  }
}

// The path's first direction, and where it crosses the top of the scene.
Path PathTracer::sample_beam(bool beam_path, RayRandom& random) {
  const bool by_beam = beam_path || random.uniform() < 0.5;
  // Where in the footprint and the field of view: the ray's own draws or its quasi-random point.
  double u1 = 0.0, u2 = 0.0;
  if (options_.quasi_random) {
    u1 = quasi_random(beam_path ? SobolPoints::beam_u1 : SobolPoints::second_u1, random);
    u2 = quasi_random(beam_path ? SobolPoints::beam_u2 : SobolPoints::second_u2, random);
  } else {
    u1 = random.uniform();
    u2 = random.uniform();
  }
  const Vec3 first_direction = by_beam ? beam_.direction(u1, u2) : beam_.uniform_direction(u1, u2);
  Path path;
  path.beam_path = beam_path;
  // The beam path scores only its first interaction and never needs the density.
  path.density = beam_path ? 0.0 : 0.5 * beam_density(first_direction) + 0.5 * uniform_density_;
  std::fill(throughput_.begin(), throughput_.end(), 1.0);
  if (atmosphere_) {
    // Down through the layers: the beam path is the laser's light, scattered on its way to the
    // scene; the second path the detector's view, scattered on the way back (reciprocity).
    path.position = geometry_.sensor_m;
    path.direction = first_direction;
    int scatterings = 0;
    path.lost = !atmosphere_->cross(
        path.position, path.direction, path.path_m, throughput_,
        [&random] { return random.uniform(); }, &scatterings);
    path.atmosphere_scattered = scatterings > 0;
    if (path.atmosphere_scattered)
      path.atmosphere_extra_m = path.path_m - norm(path.position - geometry_.sensor_m);
    return path;
  }
  const double start_m = (geometry_.sensor_m[2] - start_height_m_) / -first_direction[2];
  path.position = geometry_.sensor_m + start_m * first_direction;
  path.direction = first_direction;
  path.path_m = start_m;
  return path;
}

// The next element along the path: a leaf by free-path sampling through the foliage, but never
// beyond the nearest surface; empty when the path leaves the scene.
std::optional<Vertex> PathTracer::find_vertex(const Path& path, RayRandom& random, Tally& tally) {
  auto uniform = [&random] { return random.uniform(); };
  std::optional<double> target;
  if (foliage_) {
    project(path.direction);
    // The beam path's one free path: the third coordinate of the ray's point, if quasi-random.
    const double u = options_.quasi_random && path.beam_path
                         ? quasi_random(SobolPoints::beam_free_path, random)
                         : random.uniform();
    target = -std::log1p(-u);
  }
  const ElementMet met = element_met(scene_, path.position, path.direction, far_m,
                                     path.min_distance_m, target, spans_, projection_, uniform);
  tally.ray_queries += met.ray_queries;
  const SurfaceHit& hit = met.surface;
  const std::optional<Interaction>& leaf = met.leaf;
  if (!leaf && hit.kind == SurfaceKind::none) return std::nullopt;
  Vertex vertex;
  if (leaf) {
    vertex.element = RayElement::leaf;
    vertex.foliage = leaf->material;
    vertex.crown = leaf->crown;
    vertex.segment_m = leaf->distance_m;
  } else {
    vertex.element = surface_element(hit.kind);
    vertex.foliage = vertex.element == RayElement::ground ? -1 : hit.material;
    vertex.segment_m = hit.distance_m;
  }
  if (vertex.foliage >= 0) vertex.material = &optics_.foliage[vertex.foliage];
  vertex.point = path.position + vertex.segment_m * path.direction;
  vertex.normal =
      leaf ? vertex.material->leaf_angles->sample_normal(path.direction, uniform) : hit.normal;
  return vertex;
}

// Direct laser light at the element, scored toward the detector. The laser sits with the
// detector: at the first interaction its light comes down the very path sampled, and with
// finite leaves it finds the same gaps (the hotspot, PHYSICS.md section 3).
void PathTracer::score_direct(const Path& path, const Vertex& vertex, int order, Tally& tally,
                              RayRandom& random) {
  const Vec3 to_laser = geometry_.sensor_m - vertex.point;
  const double laser_m = norm(to_laser);
  const Vec3 up_to_laser = (1.0 / laser_m) * to_laser;
  const Vec3 laser_light = -1.0 * up_to_laser;  // travel direction of the laser's light
  const double transmission = laser_transmission(path, vertex, order, up_to_laser, tally);
  if (!(transmission > 0.0)) {
    emit(RayEventKind::blocked, path, vertex.point, &vertex);
    return;
  }
  // Beyond the first order, the laser's light at the point over the density of the detector
  // ray that found it.
  const double beam_ratio = order > 1 ? beam_density(laser_light) / path.density : 1.0;
  if (atmosphere_) {
    score_through_atmosphere(path, vertex, order, transmission, beam_ratio, laser_m, up_to_laser,
                             tally, random);
    return;
  }
  const double range_m = geometry_.range_m;
  const double scale = transmission * beam_ratio * (range_m / laser_m) * (range_m / laser_m);
  const double time_ns = (laser_m + path.path_m - 2.0 * range_m) / speed_of_light_m_s * 1e9;
  const int tally_bin = lidar_.tally_index(time_ns);
  const Vec3 toward_detector = -1.0 * path.direction;
  for (std::size_t band = 0; band < bands_; ++band)
    response_[band] = throughput_[band] *
                      element_response(vertex.element, vertex.material, optics_, band,
                                       vertex.normal, laser_light, toward_detector) *
                      scale;
  if (tally_bin >= 0) bin(path, order, tally_bin, tally);
  if (observer_) {
    RayEvent event = event_at(RayEventKind::score, path, vertex.point, &vertex);
    event.weight = response_;
    event.path_m = laser_m + path.path_m;
    event.time_ns = time_ns;
    event.tally_bin = tally_bin;
    event.bin = tally_bin - lidar_.margin_bins();
    (*observer_)(event);
  }
}

// The direct return with the atmosphere's layers above the scene. Beyond the first order the path
// is the detector's view (its scatterings in the layers drawn already) and the laser lights the
// element straight through them. At the first order the path is the laser's light, which may have
// scattered in the layers: the element sends it back straight, seen when it lies in the field of
// view, and once scattered in the layers into the field of view (a point drawn on a detector ray
// uniform over the field of view, at a height drawn by the layers' scattering). The scene is
// crossed on the way back as by the straight return (the scattering angles are small).
void PathTracer::score_through_atmosphere(const Path& path, const Vertex& vertex, int order,
                                          double transmission, double beam_ratio, double laser_m,
                                          const Vec3& up_to_laser, Tally& tally,
                                          RayRandom& random) {
  const AtmosphereModel& atmosphere = *atmosphere_;
  const double range_m = geometry_.range_m;
  const Vec3 laser_light = -1.0 * up_to_laser;
  // A return scored, its light scattered by the layers or not, `extra_m` longer for it.
  auto score = [&](double path_m, bool scattered, double extra_m) {
    const double time_ns = (path_m - 2.0 * range_m) / speed_of_light_m_s * 1e9;
    const int tally_bin = lidar_.tally_index(time_ns);
    if (tally_bin >= 0) {
      bin(path, order, tally_bin, tally);
      for (std::size_t band = 0; band < bands_; ++band) {
        double* sums = &tally.atmosphere[band * Tally::atmosphere_sums];
        sums[0] += response_[band];
        if (!scattered) continue;
        sums[1] += response_[band];
        sums[2] += response_[band] * extra_m;
      }
    }
    if (observer_) {
      RayEvent event = event_at(RayEventKind::score, path, vertex.point, &vertex);
      event.weight = response_;
      event.path_m = path_m;
      event.time_ns = time_ns;
      event.tally_bin = tally_bin;
      event.bin = tally_bin - lidar_.margin_bins();
      (*observer_)(event);
    }
  };
  const double direct_scale = transmission * beam_ratio * (range_m / laser_m) * (range_m / laser_m);
  if (order > 1) {
    const Vec3 toward_detector = -1.0 * path.direction;
    for (std::size_t band = 0; band < bands_; ++band)
      response_[band] = throughput_[band] *
                        element_response(vertex.element, vertex.material, optics_, band,
                                         vertex.normal, laser_light, toward_detector) *
                        direct_scale *
                        std::exp(-atmosphere.column_optical_depth(band) / up_to_laser[2]);
    score(laser_m + path.path_m, path.atmosphere_scattered, path.atmosphere_extra_m);
    return;
  }
  // The element's response is per unit irradiance across the light's path; the light sent
  // toward a direction other than the one it came from is that times cos(out) / cos(in).
  const Vec3& incoming = path.direction;
  const double cos_in = std::abs(dot(vertex.normal, incoming));
  if (!(cos_in > 0.0)) return;
  const Vec3 from_sensor = vertex.point - geometry_.sensor_m;
  const double off_axis_rad =
      std::atan2(norm(cross(from_sensor, geometry_.axis)), dot(from_sensor, geometry_.axis));
  if (off_axis_rad <= lidar_.max_angle_rad() * (1.0 + 1e-9) && up_to_laser[2] > 0.0) {
    const double cos_out = std::abs(dot(vertex.normal, up_to_laser));
    for (std::size_t band = 0; band < bands_; ++band)
      response_[band] = throughput_[band] *
                        element_response(vertex.element, vertex.material, optics_, band,
                                         vertex.normal, incoming, up_to_laser) *
                        (cos_out / cos_in) * direct_scale *
                        std::exp(-atmosphere.column_optical_depth(band) / up_to_laser[2]);
    score(path.path_m + laser_m, path.atmosphere_scattered, path.path_m - laser_m);
  }
  if (!atmosphere.scatters()) return;
  const double u1 = random.uniform(), u2 = random.uniform(), u3 = random.uniform();
  const Vec3 down = beam_.uniform_direction(u1, u2);
  AtmosphereModel::ScatterPoint at;
  if (!atmosphere.scatter_point(geometry_.sensor_m, down, u3, at)) return;
  const Vec3 to_point = at.point - vertex.point;
  const double rise_m = norm(to_point);
  const Vec3 up = (1.0 / rise_m) * to_point;
  if (!(up[2] > 0.0)) return;
  atmosphere.scattering_factor(at, down, dot(up, -1.0 * down), factor_);
  const double cos_out = std::abs(dot(vertex.normal, up));
  const double scale = transmission * (cos_out / cos_in) * range_m * range_m *
                       lidar_.fov_solid_angle_sr() / (rise_m * rise_m);
  const double floor_z = atmosphere.floor_z_m();
  for (std::size_t band = 0; band < bands_; ++band)
    response_[band] =
        throughput_[band] *
        element_response(vertex.element, vertex.material, optics_, band, vertex.normal, incoming,
                         up) *
        scale * factor_[band] *
        std::exp(-atmosphere.optical_depth(band, floor_z, at.z_m) / up[2] -
                 atmosphere.optical_depth(band, at.z_m, std::numeric_limits<double>::infinity()) /
                     -down[2]);
  const double scattered_path_m = path.path_m + rise_m + norm(geometry_.sensor_m - at.point);
  score(scattered_path_m, true, scattered_path_m - 2.0 * laser_m);
}

// Part of the laser's light that reaches the element: surfaces block it (beyond the first
// order: the first interaction is lit down the path that found it), foliage attenuates it.
double PathTracer::laser_transmission(const Path& path, const Vertex& vertex, int order,
                                      const Vec3& up_to_laser, Tally& tally) {
  const double exit_m = (start_height_m_ - vertex.point[2]) / up_to_laser[2];
  double transmission = 1.0;
  if (order > 1) {
    if (scene_.occluded(vertex.point, up_to_laser, exit_m, surface_offset_m)) transmission = 0.0;
    ++tally.ray_queries;
  }
  // At the first interaction with finite leaves only, the way out needs no second look: the
  // light returns through the very gaps it came down.
  if (!foliage_ || !(transmission > 0.0) || (order == 1 && !any_point_leaves_)) return transmission;
  scene_.volume_spans(vertex.point, up_to_laser, exit_m, spans_);
  ++tally.ray_queries;
  // The connection runs beside the segment just sampled (traced back from the point); at the
  // first order all the way, at no angle.
  const double separation_rad =
      order == 1 ? 0.0 : std::acos(std::clamp(dot(up_to_laser, -1.0 * path.direction), -1.0, 1.0));
  const double shared_m = order == 1 ? std::numeric_limits<double>::infinity() : vertex.segment_m;
  project(up_to_laser);
  return transmission * std::exp(-connection_depth(spans_, projection_, optics_.foliage, shared_m,
                                                   separation_rad));
}

// The scored return into its time bin: the total, the canopy or ground part (by the first
// element the path met), and its scattering order when orders are kept apart.
void PathTracer::bin(const Path& path, int order, int bin, Tally& tally) {
  tally.mark(bin);
  // A ray scores a few times at most, mostly into later bins: the list is short.
  std::size_t entry = ray_bins_.size();
  while (entry > 0 && ray_bins_[entry - 1] != bin) --entry;
  if (entry == 0) {
    ray_bins_.push_back(bin);
    ray_scores_.resize(ray_scores_.size() + bands_, 0.0);
    entry = ray_bins_.size();
  }
  for (std::size_t band = 0; band < bands_; ++band)
    ray_scores_[(entry - 1) * bands_ + band] += response_[band];
  for (std::size_t band = 0; band < bands_; ++band) {
    const std::size_t at = band * tally.size + bin;
    tally.total[at] += response_[band];
    (path.canopy_return ? tally.canopy : tally.ground)[at] += response_[band];
    if (order <= tally.orders)
      tally.order[(band * tally.orders + order - 1) * tally.size + bin] += response_[band];
  }
}

// The diffuse light: where the light scattered here toward the detector came from. The next
// direction is drawn by the element's scattering, the throughput carrying the rest; false when
// the element scatters nothing.
bool PathTracer::scatter(Path& path, const Vertex& vertex, RayRandom& random) {
  if (!sample_scattering(vertex.element, vertex.material, optics_, vertex.normal, random,
                         path.direction, throughput_))
    return false;
  // A leaf is no surface; a path leaving a surface starts off it.
  path.min_distance_m = vertex.element == RayElement::leaf ? 0.0 : surface_offset_m;
  path.position = vertex.point;
  emit(RayEventKind::scatter, path, path.position, &vertex);
  return true;
}

// Russian roulette on faint paths keeps the estimate unbiased and the work bounded.
bool PathTracer::survives_roulette(const Path& path, RayRandom& random) {
  const double strongest = *std::max_element(throughput_.begin(), throughput_.end());
  if (strongest <= 0.0) return false;
  if (strongest < 0.05) {
    if (random.uniform() >= 0.5) return false;
    for (double& weight : throughput_) weight *= 2.0;
    emit(RayEventKind::roulette, path, path.position, nullptr);
  }
  return true;
}

void PathTracer::project(const Vec3& direction) {
  project_foliage(optics_, direction[2], projection_);
}

// The beam's irradiance in a direction, as a density over the field of view (per sr): for a
// Gaussian beam exp(-theta^2 / 2 sigma^2) / (2 pi sigma^2 f_fov). The beam path's rays are drawn
// by it.
double PathTracer::beam_density(const Vec3& direction) const {
  const double angle_from_axis =
      std::atan2(norm(cross(direction, geometry_.axis)), dot(direction, geometry_.axis));
  if (lidar_.uniform_beam()) return lidar_.beam_density_sr(angle_from_axis);
  return std::exp(-std::pow(angle_from_axis, 2) / two_sigma_sq_) /
         (std::numbers::pi * two_sigma_sq_ * lidar_.fov_fraction());
}

// An event at `position` that carries the path's throughput.
RayEvent PathTracer::event_at(RayEventKind kind, const Path& path, const Vec3& position,
                              const Vertex* vertex) const {
  RayEvent event;
  event.kind = kind;
  event.single_scattering_path = path.beam_path;
  event.order = path.order;
  event.position_m = position;
  event.direction = path.direction;
  if (vertex) {
    event.element = vertex->element;
    event.foliage = vertex->foliage;
    event.crown = vertex->crown;
  }
  event.weight = throughput_;
  event.path_m = path.path_m;
  return event;
}

// Tells the observer, if any: without one no event is built.
void PathTracer::emit(RayEventKind kind, const Path& path, const Vec3& position,
                      const Vertex* vertex) const {
  if (observer_) (*observer_)(event_at(kind, path, position, vertex));
}

}  // namespace glaswave::lidar_paths
