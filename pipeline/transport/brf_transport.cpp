// Forward Monte Carlo from the sun with local estimates toward the views (FLIGHT's BRF mode).
#include "pipeline/transport/brf_transport.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/random.hpp"

namespace glaswave {
namespace {

// A path that wraps around the tile this many times without meeting anything runs almost
// level through empty space: it is dropped (its energy is lost, a negligible part).
constexpr int max_wraps = 1000;
// Batches traced at once between progress reports, and summed in order.
constexpr std::int64_t batches_per_group = 64;

// The tally of one batch of photons: scores summed per band and view, with their squares for
// the standard error; the nadir image as a list of (pixel, per-band score) entries, which stays
// small where a dense image per batch would not.
struct BatchTally {
  BatchTally(std::size_t bands, std::size_t views)
      : escaped(bands, 0.0),
        sum(bands * views, 0.0),
        sum_sq(bands * views, 0.0),
        escaped_sq(bands, 0.0),
        absorbed(bands, 0.0),
        absorbed_sq(bands, 0.0),
        transmitted(bands, 0.0),
        transmitted_sq(bands, 0.0),
        closure(bands, 0.0),
        closure_sq(bands, 0.0),
        part_sum(brf_parts * bands * views, 0.0),
        part_sum_sq(brf_parts * bands * views, 0.0) {}
  std::vector<double> escaped, sum, sum_sq;
  // RAMI's fluxes and parts (brf_transport.hpp), with their squares.
  std::vector<double> escaped_sq, absorbed, absorbed_sq, transmitted, transmitted_sq;
  std::vector<double> closure, closure_sq;
  std::vector<double> part_sum, part_sum_sq;  // [(part * bands + band) * views + view]
  std::vector<std::int64_t> pixels;
  std::vector<double> pixel_scores;  // [entry * bands + band]
  std::int64_t ray_queries = 0;
};

// A photon's place: where it is, where it goes, and how far it has come since its last event.
struct Photon {
  Vec3 position{}, direction{};
  double min_distance_m = 0.0;  // off the surface it leaves
};

// What a photon meets next.
struct Event {
  RayElement element = RayElement::none;
  const Foliage* material = nullptr;
  Vec3 point{}, normal{};
  double segment_m = 0.0;   // along the path from the previous event (or the top of the scene)
  bool escaped_up = false;  // when nothing is met: whether the photon left through the top
};

class SunTracer {
 public:
  SunTracer(const Scene& scene, const SceneOptics& optics, const BrfTile& tile,
            const BrfOptions& options)
      : scene_(scene),
        optics_(optics),
        tile_(tile),
        options_(options),
        bands_(optics.soil_reflectance.size()),
        views_(options.views.size()),
        top_m_(scene.top_m() + 1.0 +
               tile.half_size_m * (std::abs(tile.ground_slope_x) + std::abs(tile.ground_slope_y))),
        throughput_(bands_),
        scores_(bands_ * views_),
        part_scores_(brf_parts * bands_ * views_),
        absorbed_(bands_),
        transmitted_(bands_),
        escaped_(bands_),
        projection_(optics.foliage.size()) {}

  void trace_photon(std::int64_t batch, std::int64_t photon, BatchTally& tally);

 private:
  double height_above_plane(const Vec3& p) const {
    return p[2] - tile_.ground_slope_x * p[0] - tile_.ground_slope_y * p[1];
  }
  double rise_rate(const Vec3& d) const {
    return d[2] - tile_.ground_slope_x * d[0] - tile_.ground_slope_y * d[1];
  }
  double to_side_m(const Vec3& p, const Vec3& d) const;
  void wrap(Vec3& p, const Vec3& d, double step_m) const;
  Event next_event(Photon& photon, RandomStream& random, BatchTally& tally);
  double view_transmission(const Event& event, const Vec3& arriving, const Vec3& view,
                           BatchTally& tally);
  void score(const Event& event, const Vec3& arriving, int part, BatchTally& tally);
  void tally_fluxes(const Event& event, const std::vector<double>& before, bool scattered);
  void project(const Vec3& direction) { project_foliage(optics_, direction[2], projection_); }

  const Scene& scene_;
  const SceneOptics& optics_;
  const BrfTile& tile_;
  const BrfOptions& options_;
  const std::size_t bands_, views_;
  const double top_m_;  // above the plane of the ground: the top of the scene
  std::vector<double> throughput_, scores_;
  std::vector<double> part_scores_;                       // [(part * bands + band) * views + view]
  std::vector<double> absorbed_, transmitted_, escaped_;  // this photon's, per band
  std::vector<double> before_;                            // the throughput before an event
  std::vector<double> projection_;
  std::vector<VolumeSpan> spans_;
};

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

void SunTracer::trace_photon(std::int64_t batch, std::int64_t photon, BatchTally& tally) {
  RandomStream random(options_.seed, batch, photon, RandomPurpose::sun);
  std::fill(throughput_.begin(), throughput_.end(), 1.0);
  std::fill(scores_.begin(), scores_.end(), 0.0);
  std::fill(part_scores_.begin(), part_scores_.end(), 0.0);
  std::fill(absorbed_.begin(), absorbed_.end(), 0.0);
  std::fill(transmitted_.begin(), transmitted_.end(), 0.0);
  std::fill(escaped_.begin(), escaped_.end(), 0.0);
  // Uniform over the tile, entering at the top of the scene.
  const double h = tile_.half_size_m;
  const double x = (2.0 * random.uniform() - 1.0) * h, y = (2.0 * random.uniform() - 1.0) * h;
  Photon path;
  path.direction = options_.sun_direction;
  path.position = {x, y, top_m_ + tile_.ground_slope_x * x + tile_.ground_slope_y * y};
  // Scored up to max_order (every order by default); the light scattered there is followed once
  // more to see whether it leaves, so that the albedo counts the same orders as the BRF.
  const std::int64_t last_order = std::int64_t{options_.max_order} + 1;
  for (std::int64_t order = 1; order <= last_order; ++order) {
    const Event event = next_event(path, random, tally);
    if (event.element == RayElement::none) {
      if (event.escaped_up)
        for (std::size_t band = 0; band < bands_; ++band) {
          tally.escaped[band] += throughput_[band];
          tally.escaped_sq[band] += throughput_[band] * throughput_[band];
          escaped_[band] = throughput_[band];
        }
      break;
    }
    if (order > options_.max_order) break;
    const int part = order > 1                             ? brf_many_times
                     : event.element == RayElement::ground ? brf_soil_once
                                                           : brf_canopy_once;
    score(event, path.direction, part, tally);
    before_ = throughput_;
    const bool scattered = sample_scattering(event.element, event.material, optics_, event.normal,
                                             random, path.direction, throughput_);
    tally_fluxes(event, before_, scattered);
    if (!scattered) break;
    path.position = event.point;
    path.min_distance_m = event.element == RayElement::leaf ? 0.0 : surface_offset_m;
    // Russian roulette on faint photons keeps the estimate unbiased and the work bounded.
    const double strongest = *std::max_element(throughput_.begin(), throughput_.end());
    if (!(strongest > 0.0)) break;
    if (strongest < 0.05) {
      if (random.uniform() >= 0.5) break;
      for (double& weight : throughput_) weight *= 2.0;
    }
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

// The mean of n scores from their sum and sum of squares, and its standard error.
std::pair<double, double> mean_and_stderr(double sum, double sum_sq, double n) {
  const double mean = sum / n;
  const double variance = n > 1.0 ? std::max(0.0, sum_sq / n - mean * mean) * n / (n - 1.0) : 0.0;
  return {mean, std::sqrt(variance / n)};
}

}  // namespace

BrfResult simulate_brf(const Scene& scene, const SceneOptics& optics, const BrfTile& tile,
                       const BrfOptions& options, const BrfProgress& progress) {
  const std::size_t bands = optics.soil_reflectance.size(), views = options.views.size();
  const std::int64_t pixels =
      static_cast<std::int64_t>(options.image_pixels) * options.image_pixels;
  BatchTally total(bands, views);
  std::vector<std::vector<double>> image(bands, std::vector<double>(pixels, 0.0));
  const std::int64_t batches = (options.photons + brf_batch_photons - 1) / brf_batch_photons;
  for (std::int64_t first = 0; first < batches; first += batches_per_group) {
    const std::int64_t last = std::min(batches, first + batches_per_group);
    std::vector<BatchTally> tallies(last - first, BatchTally(bands, views));
    tbb::parallel_for(first, last, [&](std::int64_t batch) {
      SunTracer tracer(scene, optics, tile, options);
      const std::int64_t end =
          std::min(brf_batch_photons, options.photons - batch * brf_batch_photons);
      for (std::int64_t photon = 0; photon < end; ++photon)
        tracer.trace_photon(batch, photon, tallies[batch - first]);
    });
    for (const BatchTally& tally : tallies) {  // in batch order: the same bits for any threads
      for (std::size_t i = 0; i < bands; ++i) {
        total.escaped[i] += tally.escaped[i];
        total.escaped_sq[i] += tally.escaped_sq[i];
        total.absorbed[i] += tally.absorbed[i];
        total.absorbed_sq[i] += tally.absorbed_sq[i];
        total.transmitted[i] += tally.transmitted[i];
        total.transmitted_sq[i] += tally.transmitted_sq[i];
        total.closure[i] += tally.closure[i];
        total.closure_sq[i] += tally.closure_sq[i];
      }
      for (std::size_t i = 0; i < total.part_sum.size(); ++i) {
        total.part_sum[i] += tally.part_sum[i];
        total.part_sum_sq[i] += tally.part_sum_sq[i];
      }
      for (std::size_t i = 0; i < total.sum.size(); ++i) {
        total.sum[i] += tally.sum[i];
        total.sum_sq[i] += tally.sum_sq[i];
      }
      for (std::size_t e = 0; e < tally.pixels.size(); ++e)
        for (std::size_t band = 0; band < bands; ++band)
          image[band][tally.pixels[e]] += tally.pixel_scores[e * bands + band];
      total.ray_queries += tally.ray_queries;
    }
    if (progress) progress(std::min(options.photons, last * brf_batch_photons), options.photons);
  }
  // Photons cross the tile's top uniformly, each carrying E_sun (s.N) A / photons, where s is
  // toward the sun: against a white Lambertian plane lit by E_sun cos(theta_s), the scores are
  // scaled by (s.N) / cos(theta_s) (1 over level ground).
  const Vec3 to_sun = -1.0 * options.sun_direction;
  const double n = static_cast<double>(options.photons) * std::abs(to_sun[2]) /
                   (to_sun[2] - tile.ground_slope_x * to_sun[0] - tile.ground_slope_y * to_sun[1]);
  const double photons = static_cast<double>(options.photons);
  BrfResult result;
  result.ray_queries = total.ray_queries;
  auto push = [photons](double sum, double sum_sq, std::vector<double>& mean,
                        std::vector<double>& stderr_) {
    const auto [m, e] = mean_and_stderr(sum, sum_sq, photons);
    mean.push_back(m);
    stderr_.push_back(e);
  };
  for (std::size_t band = 0; band < bands; ++band) {
    result.albedo.push_back(total.escaped[band] / photons);
    result.albedo_stderr.push_back(
        mean_and_stderr(total.escaped[band], total.escaped_sq[band], photons).second);
    push(total.absorbed[band], total.absorbed_sq[band], result.absorbed, result.absorbed_stderr);
    push(total.transmitted[band], total.transmitted_sq[band], result.transmitted,
         result.transmitted_stderr);
    push(total.closure[band], total.closure_sq[band], result.closure, result.closure_stderr);
    for (int part = 0; part < brf_parts; ++part) {
      result.part_brf[part].emplace_back();
      result.part_stderr[part].emplace_back();
      for (std::size_t v = 0; v < views; ++v) {
        const std::size_t i = (part * bands + band) * views + v;
        const auto [m, e] = mean_and_stderr(total.part_sum[i], total.part_sum_sq[i], photons);
        result.part_brf[part].back().push_back(m * photons / n);
        result.part_stderr[part].back().push_back(e * photons / n);
      }
    }
    result.brf.emplace_back();
    result.brf_stderr.emplace_back();
    for (std::size_t v = 0; v < views; ++v) {
      const double mean = total.sum[band * views + v] / photons;
      const double variance =
          photons > 1.0 ? std::max(0.0, total.sum_sq[band * views + v] / photons - mean * mean) *
                              photons / (photons - 1.0)
                        : 0.0;
      result.brf.back().push_back(mean * photons / n);
      result.brf_stderr.back().push_back(std::sqrt(variance / photons) * photons / n);
    }
    // A pixel gets n / pixels photons on average: its BRF is its scores over that.
    for (double& value : image[band]) value *= static_cast<double>(pixels) / n;
  }
  result.image = std::move(image);
  return result;
}

}  // namespace glaswave
