// The BRF's sun tracer (SunTracer: one photon from the sun through the layers and the scene,
// its local estimates toward the views) and the tally of a batch of photons it scores into,
// shared by brf_sun_tracer.cpp (the tracer's steps) and brf_transport.cpp (the batches over
// threads, summed in order and read out as the BRF). The transport's own files only; other
// code calls brf_transport.hpp.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "core/random.hpp"
#include "pipeline/transport/atmosphere.hpp"
#include "pipeline/transport/brf_transport.hpp"

namespace glaswave::brf_paths {

// Sums over photons of a per-photon value x, of its square and of x d, d being the photon's
// energy entering the scene's top: a ratio estimate sum(x) / sum(d) and its standard error.
struct RatioSums {
  explicit RatioSums(std::size_t n) : sum(n, 0.0), sum_sq(n, 0.0), sum_down(n, 0.0) {}
  void add(std::size_t i, double x, double down) {
    sum[i] += x;
    sum_sq[i] += x * x;
    sum_down[i] += x * down;
  }
  void merge(const RatioSums& other) {
    for (std::size_t i = 0; i < sum.size(); ++i) {
      sum[i] += other.sum[i];
      sum_sq[i] += other.sum_sq[i];
      sum_down[i] += other.sum_down[i];
    }
  }
  std::vector<double> sum, sum_sq, sum_down;
};

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
        part_sum_sq(brf_parts * bands * views, 0.0),
        down(bands),
        escaped_ratio(bands),
        absorbed_ratio(bands),
        transmitted_ratio(bands),
        closure_ratio(bands),
        view_ratio(bands * views),
        part_ratio(brf_parts * bands * views),
        direct(bands),
        diffuse(bands),
        toa_escaped(bands),
        toa_view(bands * views),
        layers_absorbed(bands),
        toa_closure(bands) {}
  std::vector<double> escaped, sum, sum_sq;
  // RAMI's fluxes and parts (brf_transport.hpp), with their squares.
  std::vector<double> escaped_sq, absorbed, absorbed_sq, transmitted, transmitted_sq;
  std::vector<double> closure, closure_sq;
  std::vector<double> part_sum, part_sum_sq;  // [(part * bands + band) * views + view]
  // With the layers: each photon's energy entering the scene's top (`down`), the scene's
  // quantities as ratios to it, and the sky's per photon.
  RatioSums down, escaped_ratio, absorbed_ratio, transmitted_ratio, closure_ratio, view_ratio,
      part_ratio;
  RatioSums direct, diffuse, toa_escaped, toa_view, layers_absorbed, toa_closure;
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
            const BrfOptions& options, const AtmosphereModel* layers)
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
        projection_(optics.foliage.size()),
        layers_(layers) {
    if (!layers_) return;
    toa_scores_.assign(bands_ * views_, 0.0);
    down_.assign(bands_, 0.0);
    direct_.assign(bands_, 0.0);
    diffuse_.assign(bands_, 0.0);
    toa_escaped_.assign(bands_, 0.0);
    layers_absorbed_.assign(bands_, 0.0);
    // A scene's light reaches the top of the layers toward a view unscattered by exp(-tau / mu).
    view_above_.assign(bands_ * views_, 0.0);
    for (std::size_t v = 0; v < views_; ++v)
      for (std::size_t band = 0; band < bands_; ++band)
        if (options_.views[v][2] > 0.0)
          view_above_[band * views_ + v] =
              std::exp(-layers_->column_optical_depth(band) / options_.views[v][2]);
    seen_ = [this](const Vec3& point, const Vec3& arriving, const AtmospherePhase& phase,
                   std::span<const double> weight) {
      score_layers(point, arriving, phase, weight);
    };
  }

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
  bool through_scene(Photon& path, RandomStream& random, BatchTally& tally, std::int64_t& order,
                     Vec3& exit_point);
  void through_layers(Photon& path, RandomStream& random, BatchTally& tally);
  void score_layers(const Vec3& point, const Vec3& arriving, const AtmospherePhase& phase,
                    std::span<const double> weight);
  void tally_through_layers(BatchTally& tally);

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
  // The layers, when there are: this photon's scores at their top and its energies (per band).
  const AtmosphereModel* layers_;
  AtmosphereModel::ScatterSeen seen_;
  std::vector<double> toa_scores_, view_above_;
  std::vector<double> down_, direct_, diffuse_, toa_escaped_, layers_absorbed_;
};

}  // namespace glaswave::brf_paths
