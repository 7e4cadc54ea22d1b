// One photon of the BRF from the sun (brf_sun_tracer.hpp): its next element found (across a
// periodic tile's sides), the local estimates toward the views and the nadir image, the fluxes
// RAMI asks for, and, with an atmosphere, its passes down through the layers and back up.
#include "pipeline/transport/brf_sun_tracer.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numbers>

namespace glaswave::brf_paths {
namespace {

// A path that wraps around the tile this many times without meeting anything runs almost
// level through empty space: it is dropped (its energy is lost, a negligible part).
constexpr int max_wraps = 1000;
// A photon that has gone down through the layers this often (the sky's light bouncing between a
// white scene and a thick cloud) is given up: its energy is lost, a negligible part.
constexpr int most_passes = 10000;

}  // namespace

// Distance along d to the tile's side; infinite when the tile is not periodic.
double SunTracer::to_side_m(const Vec3& p, const Vec3& d) const {
  if (!tile_.periodic) return std::numeric_limits<double>::infinity();
  const double h = tile_.half_size_m;
  double t = std::numeric_limits<double>::infinity();
  for (int axis = 0; axis < 2; ++axis) {
    if (d[axis] > 0.0) t = std::min(t, (h - p[axis]) / d[axis]);
    if (d[axis] < 0.0) t = std::min(t, (-h - p[axis]) / d[axis]);
  }
  return std::max(0.0, t);
}

// Moves p by step_m along d to the side it reaches and brings it in at the opposite side,
// shifted along the ground so that its height above the ground is kept.
void SunTracer::wrap(Vec3& p, const Vec3& d, double step_m) const {
  const double h = tile_.half_size_m;
  const double slopes[2] = {tile_.ground_slope_x, tile_.ground_slope_y};
  p = p + step_m * d;
  for (int axis = 0; axis < 2; ++axis) {
    if (d[axis] > 0.0 && p[axis] >= h - 1e-9) {
      p[axis] -= 2.0 * h;
      p[2] -= 2.0 * h * slopes[axis];
    } else if (d[axis] < 0.0 && p[axis] <= -h + 1e-9) {
      p[axis] += 2.0 * h;
      p[2] += 2.0 * h * slopes[axis];
    }
  }
}

// The next element along the photon's path: a leaf by free-path sampling, never beyond the
// nearest surface; across the tile's sides when it is periodic (the exponential free path has no
// memory, so a fresh depth is drawn on each stretch).
Event SunTracer::next_event(Photon& photon, RandomStream& random, BatchTally& tally) {
  auto uniform = [&random] { return random.uniform(); };
  Event event;
  Vec3 origin = photon.position;
  double min_distance_m = photon.min_distance_m;
  for (int stretch = 0; stretch <= max_wraps; ++stretch) {
    const Vec3& d = photon.direction;
    const double side_m = to_side_m(origin, d);
    const double limit_m = std::min(side_m, far_m);
    std::optional<double> target;
    if (scene_.has_volumes()) {
      project(d);
      target = -std::log1p(-random.uniform());
    }
    const ElementMet met = element_met(scene_, origin, d, limit_m, min_distance_m, target, spans_,
                                       projection_, uniform);
    tally.ray_queries += met.ray_queries;
    const SurfaceHit& hit = met.surface;
    const std::optional<Interaction>& leaf = met.leaf;
    if (leaf) {
      event.element = RayElement::leaf;
      event.material = &optics_.foliage[leaf->material];
      event.point = origin + leaf->distance_m * d;
      event.segment_m += leaf->distance_m;
      event.normal = event.material->leaf_angles->sample_normal(d, uniform);
      return event;
    }
    if (hit.kind != SurfaceKind::none) {
      event.element = surface_element(hit.kind);
      if (event.element != RayElement::ground) event.material = &optics_.foliage[hit.material];
      event.point = origin + hit.distance_m * d;
      event.segment_m += hit.distance_m;
      event.normal = hit.normal;
      return event;
    }
    // Through a side: out of the top, or below the ground, the photon is gone.
    const double rise = rise_rate(d);
    const double height_m = height_above_plane(origin) + rise * side_m;
    if (!tile_.periodic || side_m >= far_m || (rise > 0.0 && height_m > top_m_) ||
        (rise < 0.0 && height_m < -top_m_)) {
      event.escaped_up = rise > 0.0;
      // Where it leaves through the top, for the layers above (level then: rise is d[2]).
      if (layers_ && event.escaped_up)
        event.point = origin + ((top_m_ - height_above_plane(origin)) / rise) * d;
      return event;
    }
    wrap(origin, d, side_m);
    event.segment_m += side_m;
    min_distance_m = 0.0;
  }
  return event;  // lost, wandering level
}

// Transmittance from the event toward the viewer, across the tile's sides when it is periodic.
// Its first stretch runs back beside the path that brought the photon (`arriving` reversed, over
// event.segment_m): where the two are within a leaf of each other they see the same gaps.
double SunTracer::view_transmission(const Event& event, const Vec3& arriving, const Vec3& view,
                                    BatchTally& tally) {
  const double rise = rise_rate(view);
  if (!(rise > 0.0)) return 0.0;
  const double separation_rad = std::acos(std::clamp(dot(view, -1.0 * arriving), -1.0, 1.0));
  const bool foliage = scene_.has_volumes();
  if (foliage) project(view);
  Vec3 origin = event.point;
  double travelled_m = 0.0, depth = 0.0;
  for (int stretch = 0; stretch <= max_wraps; ++stretch) {
    const double top_m = (top_m_ - height_above_plane(origin)) / rise;
    const double side_m = to_side_m(origin, view);
    const double step_m = std::max(0.0, std::min(top_m, side_m));
    if (scene_.occluded(origin, view, step_m, stretch == 0 ? surface_offset_m : 0.0)) {
      ++tally.ray_queries;
      return 0.0;
    }
    ++tally.ray_queries;
    if (foliage) {
      scene_.volume_spans(origin, view, step_m, spans_);
      ++tally.ray_queries;
      for (VolumeSpan& span : spans_) {  // distances from the event, for the correlation
        span.start_m += travelled_m;
        span.end_m += travelled_m;
      }
      depth +=
          connection_depth(spans_, projection_, optics_.foliage, event.segment_m, separation_rad);
    }
    if (top_m <= side_m) return std::exp(-depth);
    wrap(origin, view, step_m);
    travelled_m += step_m;
  }
  return 0.0;
}

// The local estimate: what the element sends toward each view (and nadir, for the image) per
// photon, over the tile's area seen from the view (per unit area across: v.N, N = (-dz/dx,
// -dz/dy, 1) the tile's upward normal scaled to unit horizontal area).
void SunTracer::score(const Event& event, const Vec3& arriving, int part, BatchTally& tally) {
  const Vec3 toward_sun = -1.0 * arriving;
  auto response = [&](std::size_t band, const Vec3& view) {
    return element_response(event.element, event.material, optics_, band, event.normal, -1.0 * view,
                            toward_sun);
  };
  for (std::size_t v = 0; v < views_; ++v) {
    const Vec3& view = options_.views[v];
    const double transmission = view_transmission(event, arriving, view, tally);
    if (!(transmission > 0.0)) continue;
    for (std::size_t band = 0; band < bands_; ++band) {
      const double value =
          throughput_[band] * response(band, view) * transmission / rise_rate(view);
      scores_[band * views_ + v] += value;
      part_scores_[(part * bands_ + band) * views_ + v] += value;
      if (layers_) toa_scores_[band * views_ + v] += value * view_above_[band * views_ + v];
    }
  }
  // The image: nadir, at the pixel under the event.
  const double h = tile_.half_size_m, pixel_m = 2.0 * h / options_.image_pixels;
  const auto column = static_cast<std::int64_t>(std::floor((event.point[0] + h) / pixel_m));
  const auto row = static_cast<std::int64_t>(std::floor((h - event.point[1]) / pixel_m));
  if (column < 0 || row < 0 || column >= options_.image_pixels || row >= options_.image_pixels)
    return;
  const Vec3 nadir{0.0, 0.0, 1.0};
  const double transmission = view_transmission(event, arriving, nadir, tally);
  if (!(transmission > 0.0)) return;
  tally.pixels.push_back(row * options_.image_pixels + column);
  for (std::size_t band = 0; band < bands_; ++band)
    tally.pixel_scores.push_back(throughput_[band] * response(band, nadir) * transmission);
}

// What the event took: the ground is reached by the whole throughput before it (RAMI's ftran),
// the canopy keeps what its scattering did not pass on (all of it when nothing scatters).
void SunTracer::tally_fluxes(const Event& event, const std::vector<double>& before,
                             bool scattered) {
  for (std::size_t band = 0; band < bands_; ++band) {
    if (event.element == RayElement::ground)
      transmitted_[band] += before[band];
    else
      absorbed_[band] += scattered ? before[band] - throughput_[band] : before[band];
  }
}

// Follows the photon through the scene from where `path` is until it is absorbed, ended by
// Russian roulette or cut at max_order (false), or leaves through the top (true: `exit_point`
// there, with the layers). `order` counts the scene's scatterings over the photon's life.
bool SunTracer::through_scene(Photon& path, RandomStream& random, BatchTally& tally,
                              std::int64_t& order, Vec3& exit_point) {
  // Scored up to max_order (every order by default); the light scattered there is followed once
  // more to see whether it leaves, so that the albedo counts the same orders as the BRF.
  const std::int64_t last_order = std::int64_t{options_.max_order} + 1;
  while (++order <= last_order) {
    const Event event = next_event(path, random, tally);
    if (event.element == RayElement::none) {
      if (!event.escaped_up) return false;
      for (std::size_t band = 0; band < bands_; ++band) escaped_[band] += throughput_[band];
      exit_point = event.point;
      return true;
    }
    if (order > options_.max_order) return false;
    const int part = order > 1                             ? brf_many_times
                     : event.element == RayElement::ground ? brf_soil_once
                                                           : brf_canopy_once;
    score(event, path.direction, part, tally);
    before_ = throughput_;
    const bool scattered = sample_scattering(event.element, event.material, optics_, event.normal,
                                             random, path.direction, throughput_);
    tally_fluxes(event, before_, scattered);
    if (!scattered) return false;
    path.position = event.point;
    path.min_distance_m = event.element == RayElement::leaf ? 0.0 : surface_offset_m;
    // Russian roulette on faint photons keeps the estimate unbiased and the work bounded.
    const double strongest = *std::max_element(throughput_.begin(), throughput_.end());
    if (!(strongest > 0.0)) return false;
    if (strongest < 0.05) {
      if (random.uniform() >= 0.5) return false;
      for (double& weight : throughput_) weight *= 2.0;
    }
  }
  return false;
}

// A scattering in the layers, scored toward each view at their top: the phase function toward it
// (per sr) times the transmission above the point, over the view's cosine, times pi (a white
// Lambertian plane's radiance being E mu / pi).
void SunTracer::score_layers(const Vec3& point, const Vec3& arriving, const AtmospherePhase& phase,
                             std::span<const double> weight) {
  constexpr double inf = std::numeric_limits<double>::infinity();
  for (std::size_t v = 0; v < views_; ++v) {
    const Vec3& view = options_.views[v];
    if (!(view[2] > 0.0)) continue;
    const double response = std::numbers::pi * phase_function(phase, dot(arriving, view)) / view[2];
    for (std::size_t band = 0; band < bands_; ++band)
      toa_scores_[band * views_ + v] +=
          weight[band] * response *
          std::exp(-layers_->optical_depth(band, point[2], inf) / view[2]);
  }
}

// The photon from the top of the layers: down through them to the scene's top (where, the layers
// being uniform across, it comes in at its place brought back into the tile), through the scene,
// up into the layers, and down again or out through their top.
void SunTracer::through_layers(Photon& path, RandomStream& random, BatchTally& tally) {
  const std::function<double()> uniform = [&random] { return random.uniform(); };
  const double h = tile_.half_size_m;
  auto into_tile = [h](double x) { return x - 2.0 * h * std::floor((x + h) / (2.0 * h)); };
  std::int64_t order = 0;
  for (int pass = 0; pass < most_passes; ++pass) {
    double path_m = 0.0;
    int scatterings = 0;
    before_ = throughput_;
    const bool down = layers_->cross(path.position, path.direction, path_m, throughput_, uniform,
                                     &scatterings, &seen_);
    for (std::size_t band = 0; band < bands_; ++band)
      layers_absorbed_[band] += before_[band] - throughput_[band];
    if (!down) break;
    for (std::size_t band = 0; band < bands_; ++band) {
      down_[band] += throughput_[band];
      if (pass == 0) (scatterings == 0 ? direct_ : diffuse_)[band] += throughput_[band];
    }
    path.position = {into_tile(path.position[0]), into_tile(path.position[1]), top_m_};
    path.min_distance_m = 0.0;
    Vec3 exit_point{};
    if (!through_scene(path, random, tally, order, exit_point)) return;
    path.position = {exit_point[0], exit_point[1], layers_->floor_z_m()};
    before_ = throughput_;
    const bool back = layers_->cross(path.position, path.direction, path_m, throughput_, uniform,
                                     &scatterings, &seen_);
    for (std::size_t band = 0; band < bands_; ++band)
      layers_absorbed_[band] += before_[band] - throughput_[band];
    // Without a layer above the floor the crossing changes nothing and the light has left.
    if (!back || !(path.direction[2] < 0.0)) break;
  }
  // Out through the top of the layers, or lost in them (scattered too often, or level).
  if (path.position[2] >= layers_->top_z_m() && path.direction[2] > 0.0)
    for (std::size_t band = 0; band < bands_; ++band) toa_escaped_[band] += throughput_[band];
}

void SunTracer::trace_photon(std::int64_t batch, std::int64_t photon, BatchTally& tally) {
  RandomStream random(options_.seed, batch, photon, RandomPurpose::sun);
  std::fill(throughput_.begin(), throughput_.end(), 1.0);
  std::fill(scores_.begin(), scores_.end(), 0.0);
  std::fill(part_scores_.begin(), part_scores_.end(), 0.0);
  std::fill(absorbed_.begin(), absorbed_.end(), 0.0);
  std::fill(transmitted_.begin(), transmitted_.end(), 0.0);
  std::fill(escaped_.begin(), escaped_.end(), 0.0);
  // Uniform over the tile, entering at the top of the scene (or of the layers).
  const double h = tile_.half_size_m;
  const double x = (2.0 * random.uniform() - 1.0) * h, y = (2.0 * random.uniform() - 1.0) * h;
  Photon path;
  path.direction = options_.sun_direction;
  if (layers_) {
    for (std::vector<double>* v :
         {&toa_scores_, &down_, &direct_, &diffuse_, &toa_escaped_, &layers_absorbed_})
      std::fill(v->begin(), v->end(), 0.0);
    path.position = {x, y, layers_->top_z_m()};
    through_layers(path, random, tally);
    tally_through_layers(tally);
    return;
  }
  path.position = {x, y, top_m_ + tile_.ground_slope_x * x + tile_.ground_slope_y * y};
  std::int64_t order = 0;
  Vec3 exit_point{};
  through_scene(path, random, tally, order, exit_point);
  for (std::size_t band = 0; band < bands_; ++band) {
    tally.escaped[band] += escaped_[band];
    tally.escaped_sq[band] += escaped_[band] * escaped_[band];
  }
  for (std::size_t i = 0; i < scores_.size(); ++i) {
    tally.sum[i] += scores_[i];
    tally.sum_sq[i] += scores_[i] * scores_[i];
  }
  for (std::size_t i = 0; i < part_scores_.size(); ++i) {
    tally.part_sum[i] += part_scores_[i];
    tally.part_sum_sq[i] += part_scores_[i] * part_scores_[i];
  }
  for (std::size_t band = 0; band < bands_; ++band) {
    tally.absorbed[band] += absorbed_[band];
    tally.absorbed_sq[band] += absorbed_[band] * absorbed_[band];
    tally.transmitted[band] += transmitted_[band];
    tally.transmitted_sq[band] += transmitted_[band] * transmitted_[band];
    // Where this photon's energy went; 1 but for Russian roulette's draws.
    const double closure = escaped_[band] + absorbed_[band] +
                           transmitted_[band] * (1.0 - optics_.soil_reflectance[band]);
    tally.closure[band] += closure;
    tally.closure_sq[band] += closure * closure;
  }
}

// A photon through the layers: its scene's quantities beside the energy it brought into the
// scene's top (their ratios are taken over all photons), and the sky's per photon.
void SunTracer::tally_through_layers(BatchTally& tally) {
  for (std::size_t band = 0; band < bands_; ++band) {
    const double d = down_[band];
    tally.down.add(band, d, d);
    tally.escaped_ratio.add(band, escaped_[band], d);
    tally.absorbed_ratio.add(band, absorbed_[band], d);
    tally.transmitted_ratio.add(band, transmitted_[band], d);
    const double soil_absorbed = transmitted_[band] * (1.0 - optics_.soil_reflectance[band]);
    tally.closure_ratio.add(band, escaped_[band] + absorbed_[band] + soil_absorbed, d);
    tally.direct.add(band, direct_[band], d);
    tally.diffuse.add(band, diffuse_[band], d);
    tally.toa_escaped.add(band, toa_escaped_[band], d);
    tally.layers_absorbed.add(band, layers_absorbed_[band], d);
    tally.toa_closure.add(
        band, toa_escaped_[band] + layers_absorbed_[band] + absorbed_[band] + soil_absorbed, d);
    for (std::size_t v = 0; v < views_; ++v) {
      const std::size_t i = band * views_ + v;
      tally.view_ratio.add(i, scores_[i], d);
      tally.toa_view.add(i, toa_scores_[i], d);
      for (int part = 0; part < brf_parts; ++part) {
        const std::size_t j = (part * bands_ + band) * views_ + v;
        tally.part_ratio.add(j, part_scores_[j], d);
      }
    }
  }
}

}  // namespace glaswave::brf_paths
