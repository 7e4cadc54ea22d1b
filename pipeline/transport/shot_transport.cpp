// Monte Carlo transport of one shot: its rays traced in a fixed number of groups (on threads
// for a long shot), their tallies summed in order, and the sum read out as the shot's waveforms
// (lidar_path_tracer.cpp traces each ray).
#include "pipeline/transport/shot_transport.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>

#include "pipeline/transport/atmosphere.hpp"
#include "pipeline/transport/lidar_path_tracer.hpp"

namespace glaswave {
namespace {

using lidar_paths::PathTracer;
using lidar_paths::Tally;

// Rays are tallied in a fixed number of contiguous groups (transport_ray_groups), summed in
// order: the result is the same bits for any thread count, and memory does not grow with the rays.
constexpr std::int64_t ray_groups = transport_ray_groups;
// Shots of fewer rays are traced on the calling thread: the engine runs shots in parallel, and
// splitting a short shot costs more than it saves.
constexpr std::int64_t parallel_rays = 2048;

// A thread's two tallies for its shots of few rays, kept between its shots and handed back zero
// (clear() zeroes only where the shot scored): a photon-counting pass's 10,000 shots a second
// would otherwise allocate and zero some 300 kB each. A shot of another shape, or one begun
// while the thread's pair is out, gets its own.
class ThreadTallies {
 public:
  ThreadTallies(std::size_t bands, int size, int orders) {
    thread_local std::unique_ptr<Pair> kept;
    thread_local bool out = false;
    if (out) {
      own_ = std::make_unique<Pair>(bands, size, orders);
      pair_ = own_.get();
      return;
    }
    if (!kept || kept->total.total.size() != bands * static_cast<std::size_t>(size) ||
        kept->total.size != static_cast<std::size_t>(size) || kept->total.orders != orders)
      kept = std::make_unique<Pair>(bands, size, orders);
    pair_ = kept.get();
    out_ = &out;
    out = true;
  }
  ~ThreadTallies() {
    pair_->total.clear();
    pair_->group.clear();
    if (out_) *out_ = false;
  }
  ThreadTallies(const ThreadTallies&) = delete;
  ThreadTallies& operator=(const ThreadTallies&) = delete;

  Tally& total() const { return pair_->total; }
  Tally& group() const { return pair_->group; }

 private:
  struct Pair {
    Pair(std::size_t bands, int size, int orders)
        : total(bands, size, orders), group(bands, size, orders) {}
    Tally total, group;
  };
  std::unique_ptr<Pair> own_;
  Pair* pair_ = nullptr;
  bool* out_ = nullptr;
};

// Row `row` of a tally's `size`-bin rows at the bins `bins`, scaled.
std::vector<double> scored_row(const std::vector<double>& flat, std::size_t size, std::size_t row,
                               const std::vector<std::uint32_t>& bins, double scale) {
  std::vector<double> values;
  values.reserve(bins.size());
  for (const std::uint32_t bin : bins) values.push_back(flat[row * size + bin] * scale);
  return values;
}

// The shot's returns from its tally of normalised returns: each band's scale (section 1 of
// PHYSICS.md: E_t T A_T f_fov / (pi R^2), shared by the rays), then the power through the
// pulse and its integrals, and/or the energies scored before the pulse.
ShotWaveforms shot_waveforms(const Tally& tally, const LidarModel& lidar, double range_m,
                             const TransportOptions& options) {
  // With an atmosphere its layers weigh each return; the bands' fixed transmission is not used.
  const bool layers = options.atmosphere.has_value();
  ShotWaveforms waveforms;
  waveforms.ray_queries = tally.ray_queries;
  const double bin_s = lidar.sensor().bin_ns * 1e-9;
  const auto rays = static_cast<double>(options.rays);
  // The bins scored into, in increasing order.
  std::vector<std::uint32_t> scored_bins(tally.bins.begin(), tally.bins.end());
  std::sort(scored_bins.begin(), scored_bins.end());
  ScoredReturns& scored = waveforms.scored;
  if (options.scored_energies) scored.bins = scored_bins;
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
  auto scored_J = [&](const std::vector<double>& flat, std::size_t band, double scale) {
    double sum = 0.0;
    for (const std::uint32_t bin : scored_bins) sum += flat[band * tally.size + bin];
    return sum * scale;
  };
  for (std::size_t band = 0; band < lidar.band_count(); ++band) {
    const LidarBand& b = lidar.sensor().bands[band];
    const double scale = b.pulse_energy_mJ * 1e-3 *
                         (layers ? 1.0 : b.atmos_transmission_roundtrip) *
                         lidar.sensor().telescope_area_m2 * lidar.fov_fraction() /
                         (std::numbers::pi * range_m * range_m) / rays;
    if (options.scored_energies) {
      scored.total_J.push_back(scored_row(tally.total, tally.size, band, scored_bins, scale));
      scored.canopy_J.push_back(scored_row(tally.canopy, tally.size, band, scored_bins, scale));
      scored.ground_J.push_back(scored_row(tally.ground, tally.size, band, scored_bins, scale));
      if (tally.orders > 0) {
        std::vector<std::vector<double>>& orders = scored.order_J.emplace_back();
        for (int k = 0; k < tally.orders; ++k)
          orders.push_back(scored_row(
              tally.order, tally.size,
              band * static_cast<std::size_t>(tally.orders) + static_cast<std::size_t>(k),
              scored_bins, scale));
      }
    }
    if (!options.power_waveforms) {
      waveforms.energy_J.push_back(scored_J(tally.total, band, scale));
      waveforms.canopy_energy_J.push_back(scored_J(tally.canopy, band, scale));
      waveforms.ground_energy_J.push_back(scored_J(tally.ground, band, scale));
      continue;
    }
    waveforms.total_W.push_back(slice(tally.total, band, scale));
    // Variance of the mean of `rays` scores, (sum w^2 - (sum w)^2 / N) / N^2 per bin (scale
    // holds the 1 / N), carried through the pulse like the power.
    std::vector<double> variance_J2(tally.size);
    for (std::size_t i = 0; i < tally.size; ++i) {
      const double sum = tally.total[band * tally.size + i];
      variance_J2[i] =
          scale * scale * std::max(tally.squares[band * tally.size + i] - sum * sum / rays, 0.0);
    }
    waveforms.total_variance_W2.push_back(lidar.power_variance_W2(variance_J2));
    // Where no return came from one part, the other's is the total, bit for bit (the same
    // scores added in the same order): bare ground needs no third convolution.
    auto none = [&](const std::vector<double>& flat) {
      return std::all_of(flat.begin() + band * tally.size, flat.begin() + (band + 1) * tally.size,
                         [](double value) { return value == 0.0; });
    };
    waveforms.canopy_W.push_back(none(tally.ground) ? waveforms.total_W.back()
                                                    : slice(tally.canopy, band, scale));
    waveforms.ground_W.push_back(none(tally.canopy) ? waveforms.total_W.back()
                                                    : slice(tally.ground, band, scale));
    waveforms.energy_J.push_back(integral_J(waveforms.total_W.back()));
    waveforms.canopy_energy_J.push_back(integral_J(waveforms.canopy_W.back()));
    waveforms.ground_energy_J.push_back(integral_J(waveforms.ground_W.back()));
    if (tally.orders > 0) {
      waveforms.order_W.emplace_back();
      for (int k = 0; k < tally.orders; ++k)
        waveforms.order_W.back().push_back(slice(tally.order, band * tally.orders + k, scale));
    }
  }
  return waveforms;
}

// The shot's truth of its atmosphere, when it has one: the layers' direct two-way transmission
// along the beam's axis, and of the returns in the window the part the layers scattered and their
// energy-weighted extra path (NaN without a return).
void add_atmosphere_truth(const Tally& tally, const Scene& scene, const ShotGeometry& geometry,
                          const TransportOptions& options, ShotWaveforms& waveforms) {
  if (!options.atmosphere) return;
  const std::size_t bands = tally.atmosphere.size() / Tally::atmosphere_sums;
  // The layers as the tracer cuts them: above the scene's top, where its rays start.
  const AtmosphereModel layers(*options.atmosphere, bands, geometry.ground_z_m,
                               geometry.ground_height_m, scene.top_m() + 1.0);
  const double mu = -geometry.axis[2];
  for (std::size_t band = 0; band < bands; ++band) {
    const double* sums = &tally.atmosphere[band * Tally::atmosphere_sums];
    waveforms.atmosphere_transmission.push_back(
        std::exp(-2.0 * layers.column_optical_depth(band) / mu));
    const double none = std::numeric_limits<double>::quiet_NaN();
    waveforms.atmosphere_scattered_fraction.push_back(sums[0] > 0.0 ? sums[1] / sums[0] : none);
    waveforms.atmosphere_delay_m.push_back(sums[0] > 0.0 ? sums[2] / sums[0] : none);
  }
}

}  // namespace

const char* to_string(RayEventKind kind) {
  switch (kind) {
    case RayEventKind::enter:
      return "enter";
    case RayEventKind::interaction:
      return "interaction";
    case RayEventKind::score:
      return "score";
    case RayEventKind::blocked:
      return "blocked";
    case RayEventKind::scatter:
      return "scatter";
    case RayEventKind::roulette:
      return "roulette";
    case RayEventKind::absorbed:
      return "absorbed";
    case RayEventKind::leave:
      return "leave";
    case RayEventKind::end:
      return "end";
  }
  return "?";
}

const char* to_string(RayElement element) {
  switch (element) {
    case RayElement::none:
      return "none";
    case RayElement::ground:
      return "ground";
    case RayElement::leaf:
      return "leaf";
    case RayElement::trunk:
      return "trunk";
    case RayElement::facet:
      return "facet";
  }
  return "?";
}

ShotWaveforms simulate_shot(const Scene& scene, const LidarModel& lidar,
                            const ShotGeometry& geometry, const SceneOptics& optics,
                            const TransportOptions& options, std::int64_t shot_number) {
  const int orders = options.per_order ? options.max_order : 0;
  const std::int64_t groups = std::min(ray_groups, options.rays);
  auto first_ray = [&](std::int64_t group) { return group * options.rays / groups; };
  if (options.rays < parallel_rays) {
    // The groups one after the other through one scratch tally, each added as it ends: the
    // same sums in the same order as below, without a tally a group.
    const ThreadTallies tallies(lidar.band_count(), lidar.tally_size(), orders);
    Tally &tally = tallies.total(), &group_tally = tallies.group();
    PathTracer tracer(scene, lidar, geometry, optics, options, shot_number, nullptr);
    for (std::int64_t group = 0; group < groups; ++group) {
      for (std::int64_t ray = first_ray(group); ray < first_ray(group + 1); ++ray)
        tracer.trace_ray(ray, group_tally);
      tally += group_tally;
      group_tally.clear();
    }
    ShotWaveforms waveforms = shot_waveforms(tally, lidar, geometry.range_m, options);
    add_atmosphere_truth(tally, scene, geometry, options, waveforms);
    return waveforms;
  }
  Tally tally(lidar.band_count(), lidar.tally_size(), orders);
  std::vector<Tally> group_tallies(groups, Tally(lidar.band_count(), lidar.tally_size(), orders));
  tbb::parallel_for(std::int64_t{0}, groups, [&](std::int64_t group) {
    PathTracer tracer(scene, lidar, geometry, optics, options, shot_number, nullptr);
    for (std::int64_t ray = first_ray(group); ray < first_ray(group + 1); ++ray)
      tracer.trace_ray(ray, group_tallies[group]);
  });
  for (const Tally& group : group_tallies) tally += group;
  ShotWaveforms waveforms = shot_waveforms(tally, lidar, geometry.range_m, options);
  add_atmosphere_truth(tally, scene, geometry, options, waveforms);
  return waveforms;
}

ShotWaveforms simulate_ray(const Scene& scene, const LidarModel& lidar,
                           const ShotGeometry& geometry, const SceneOptics& optics,
                           const TransportOptions& options, std::int64_t shot_number,
                           std::int64_t ray, const RayObserver& observer) {
  Tally tally(lidar.band_count(), lidar.tally_size(), options.per_order ? options.max_order : 0);
  PathTracer tracer(scene, lidar, geometry, optics, options, shot_number,
                    observer ? &observer : nullptr);
  tracer.trace_ray(ray, tally);
  ShotWaveforms waveforms = shot_waveforms(tally, lidar, geometry.range_m, options);
  add_atmosphere_truth(tally, scene, geometry, options, waveforms);
  return waveforms;
}

}  // namespace glaswave
