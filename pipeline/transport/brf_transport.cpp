// Forward Monte Carlo from the sun with local estimates toward the views (FLIGHT's BRF mode):
// the photons traced in batches on threads (brf_sun_tracer.cpp traces each), the batches'
// tallies summed in order and read out as the BRFs, fluxes and image with their standard errors.
#include "pipeline/transport/brf_transport.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include "pipeline/transport/atmosphere.hpp"
#include "pipeline/transport/brf_sun_tracer.hpp"

namespace glaswave {
namespace {

using brf_paths::BatchTally;
using brf_paths::RatioSums;
using brf_paths::SunTracer;

// Batches traced at once between progress reports, and summed in order.
constexpr std::int64_t batches_per_group = 64;

// The mean of n scores from their sum and sum of squares, and its standard error.
std::pair<double, double> mean_and_stderr(double sum, double sum_sq, double n) {
  const double mean = sum / n;
  const double variance = n > 1.0 ? std::max(0.0, sum_sq / n - mean * mean) * n / (n - 1.0) : 0.0;
  return {mean, std::sqrt(variance / n)};
}

// A ratio sum(x) / sum(d) over n photons, and its standard error by the delta method:
// sqrt(sum (x - R d)^2) / sum(d).
std::pair<double, double> ratio_and_stderr(const RatioSums& x, std::size_t i, const RatioSums& d,
                                           std::size_t band) {
  const double total = d.sum[band];
  if (!(total > 0.0)) return {0.0, 0.0};
  const double r = x.sum[i] / total;
  const double spread = x.sum_sq[i] - 2.0 * r * x.sum_down[i] + r * r * d.sum_sq[band];
  return {r, std::sqrt(std::max(0.0, spread)) / total};
}

// The result of photons traced through the layers (BrfResult's and BrfSky's definitions).
BrfResult sky_result(const BatchTally& total, std::vector<std::vector<double>> image,
                     std::int64_t photon_count) {
  const std::size_t bands = total.down.sum.size(), views = total.sum.size() / bands;
  const double photons = static_cast<double>(photon_count);
  BrfResult result;
  result.ray_queries = total.ray_queries;
  BrfSky& sky = result.sky.emplace();
  auto ratio = [&](const RatioSums& x, std::size_t i, std::size_t band, std::vector<double>& mean,
                   std::vector<double>& stderr_) {
    const auto [m, e] = ratio_and_stderr(x, i, total.down, band);
    mean.push_back(m);
    stderr_.push_back(e);
  };
  auto per_photon = [&](const RatioSums& x, std::size_t i, std::vector<double>& mean,
                        std::vector<double>& stderr_) {
    const auto [m, e] = mean_and_stderr(x.sum[i], x.sum_sq[i], photons);
    mean.push_back(m);
    stderr_.push_back(e);
  };
  for (std::size_t band = 0; band < bands; ++band) {
    ratio(total.escaped_ratio, band, band, result.albedo, result.albedo_stderr);
    ratio(total.absorbed_ratio, band, band, result.absorbed, result.absorbed_stderr);
    ratio(total.transmitted_ratio, band, band, result.transmitted, result.transmitted_stderr);
    ratio(total.closure_ratio, band, band, result.closure, result.closure_stderr);
    result.brf.emplace_back();
    result.brf_stderr.emplace_back();
    sky.brf.emplace_back();
    sky.brf_stderr.emplace_back();
    for (std::size_t v = 0; v < views; ++v) {
      ratio(total.view_ratio, band * views + v, band, result.brf.back(), result.brf_stderr.back());
      per_photon(total.toa_view, band * views + v, sky.brf.back(), sky.brf_stderr.back());
    }
    for (int part = 0; part < brf_parts; ++part) {
      result.part_brf[part].emplace_back();
      result.part_stderr[part].emplace_back();
      for (std::size_t v = 0; v < views; ++v)
        ratio(total.part_ratio, (part * bands + band) * views + v, band,
              result.part_brf[part].back(), result.part_stderr[part].back());
    }
    per_photon(total.direct, band, sky.direct, sky.direct_stderr);
    per_photon(total.diffuse, band, sky.diffuse, sky.diffuse_stderr);
    per_photon(total.down, band, sky.downward, sky.downward_stderr);
    per_photon(total.toa_escaped, band, sky.albedo, sky.albedo_stderr);
    per_photon(total.layers_absorbed, band, sky.absorbed, sky.absorbed_stderr);
    per_photon(total.toa_closure, band, sky.closure, sky.closure_stderr);
    // A pixel gets its share of the energy entering the top: its BRF is its scores over that.
    const double per_pixel = total.down.sum[band] / static_cast<double>(image[band].size());
    for (double& value : image[band]) value = per_pixel > 0.0 ? value / per_pixel : 0.0;
  }
  result.image = std::move(image);
  return result;
}

}  // namespace

BrfResult simulate_brf(const Scene& scene, const SceneOptics& optics, const BrfTile& tile,
                       const BrfOptions& options, const BrfProgress& progress) {
  const std::size_t bands = optics.soil_reflectance.size(), views = options.views.size();
  const std::int64_t pixels =
      static_cast<std::int64_t>(options.image_pixels) * options.image_pixels;
  BatchTally total(bands, views);
  std::vector<std::vector<double>> image(bands, std::vector<double>(pixels, 0.0));
  // The layers are cut at the scene's top, as SunTracer's top_m_ (level: the tile must be).
  std::optional<AtmosphereModel> layers;
  if (options.atmosphere) {
    // A level plane's own fit on the curved Earth is within 1e-6 of level.
    constexpr double most_gradient = 1e-4;
    if (std::abs(tile.ground_slope_x) > most_gradient ||
        std::abs(tile.ground_slope_y) > most_gradient)
      throw std::invalid_argument("brf through the layers needs a level tile");
    layers.emplace(*options.atmosphere, bands, 0.0, options.ground_height_m, scene.top_m() + 1.0);
  }
  const std::int64_t batches = (options.photons + brf_batch_photons - 1) / brf_batch_photons;
  for (std::int64_t first = 0; first < batches; first += batches_per_group) {
    const std::int64_t last = std::min(batches, first + batches_per_group);
    std::vector<BatchTally> tallies(last - first, BatchTally(bands, views));
    tbb::parallel_for(first, last, [&](std::int64_t batch) {
      SunTracer tracer(scene, optics, tile, options, layers ? &*layers : nullptr);
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
      if (!layers) continue;
      for (auto [into, from] : {std::pair{&total.down, &tally.down},
                                {&total.escaped_ratio, &tally.escaped_ratio},
                                {&total.absorbed_ratio, &tally.absorbed_ratio},
                                {&total.transmitted_ratio, &tally.transmitted_ratio},
                                {&total.closure_ratio, &tally.closure_ratio},
                                {&total.view_ratio, &tally.view_ratio},
                                {&total.part_ratio, &tally.part_ratio},
                                {&total.direct, &tally.direct},
                                {&total.diffuse, &tally.diffuse},
                                {&total.toa_escaped, &tally.toa_escaped},
                                {&total.toa_view, &tally.toa_view},
                                {&total.layers_absorbed, &tally.layers_absorbed},
                                {&total.toa_closure, &tally.toa_closure}})
        into->merge(*from);
    }
    if (progress) progress(std::min(options.photons, last * brf_batch_photons), options.photons);
  }
  if (layers) return sky_result(total, std::move(image), options.photons);
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
