// ATL08-style classification of a photon cloud: neighbour-count noise filter, iterative ground
// surface, canopy and top of canopy, and the 100 m land segments.
#include "pipeline/products/atl08_classification.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <numeric>

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

double median(std::vector<double> values) {
  if (values.empty()) return nan;
  const std::size_t mid = values.size() / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  const double upper = values[mid];
  if (values.size() % 2 == 1) return upper;
  return 0.5 * (upper + *std::max_element(values.begin(),
                                          values.begin() + static_cast<std::ptrdiff_t>(mid)));
}

// The q-quantile by linear interpolation between order statistics (numpy's default).
double quantile(std::vector<double> values, double q) {
  if (values.empty()) return nan;
  std::sort(values.begin(), values.end());
  const double position = q * static_cast<double>(values.size() - 1);
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, values.size() - 1);
  return values[below] + (position - static_cast<double>(below)) * (values[above] - values[below]);
}

// The least-squares line through the values at `known` indices [from, to), evaluated at `i`.
double line_at(const std::vector<double>& values, const std::vector<std::size_t>& known,
               std::size_t from, std::size_t to, std::size_t i) {
  double n = 0.0, sx = 0.0, sy = 0.0;
  for (std::size_t k = from; k < to; ++k) {
    n += 1.0, sx += static_cast<double>(known[k]), sy += values[known[k]];
  }
  const double mx = sx / n, my = sy / n;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t k = from; k < to; ++k) {
    const double dx = static_cast<double>(known[k]) - mx;
    sxx += dx * dx, sxy += dx * (values[known[k]] - my);
  }
  return my + (sxx > 0.0 ? sxy / sxx : 0.0) * (static_cast<double>(i) - mx);
}

// Fills the NaN entries by linear interpolation between the nearest known ones; beyond the first
// and last, along the line through the five nearest (a track's end under crowns that hide its
// ground keeps the slope of the ground before them, where it stayed level before).
void fill_gaps(std::vector<double>& values) {
  std::vector<std::size_t> known;
  for (std::size_t i = 0; i < values.size(); ++i)
    if (!std::isnan(values[i])) known.push_back(i);
  if (known.empty()) return;
  const std::size_t ends = std::min<std::size_t>(5, known.size());
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!std::isnan(values[i])) continue;
    const auto next = std::lower_bound(known.begin(), known.end(), i);
    if (next == known.begin()) {
      values[i] = line_at(values, known, 0, ends, i);
    } else if (next == known.end()) {
      values[i] = line_at(values, known, known.size() - ends, known.size(), i);
    } else {
      const std::size_t a = *(next - 1), b = *next;
      const double t = static_cast<double>(i - a) / static_cast<double>(b - a);
      values[i] = values[a] + t * (values[b] - values[a]);
    }
  }
}

struct Cells {
  double first_m = 0.0, cell_m = 1.0;
  std::size_t count = 0;
  std::size_t of(double along_m) const {
    const double i = std::floor((along_m - first_m) / cell_m);
    return static_cast<std::size_t>(std::clamp(i, 0.0, static_cast<double>(count - 1)));
  }
};

Cells cells_over(std::span<const CloudPhoton> photons, double cell_m) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const CloudPhoton& p : photons) {
    lo = std::min(lo, p.along_m);
    hi = std::max(hi, p.along_m);
  }
  Cells cells;
  cells.cell_m = cell_m;
  cells.first_m = std::floor(lo / cell_m) * cell_m;
  cells.count = static_cast<std::size_t>(std::floor((hi - cells.first_m) / cell_m)) + 1;
  return cells;
}

// Step 1: each photon's neighbour count against the noise expected in its box.
void filter_noise(std::span<const CloudPhoton> photons, const Atl08Settings& s, Atl08Classes& out,
                  std::vector<bool>& signal) {
  std::vector<std::size_t> order(photons.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return photons[a].along_m < photons[b].along_m; });
  const double box_m2 = 4.0 * s.search_along_m * s.search_vertical_m;
  std::size_t begin = 0, end = 0;
  for (const std::size_t i : order) {
    const CloudPhoton& p = photons[i];
    while (photons[order[begin]].along_m < p.along_m - s.search_along_m) ++begin;
    while (end < order.size() && photons[order[end]].along_m <= p.along_m + s.search_along_m) ++end;
    double neighbours = -1.0;  // not itself
    for (std::size_t k = begin; k < end; ++k)
      if (std::abs(photons[order[k]].h_m - p.h_m) <= s.search_vertical_m) neighbours += 1.0;
    const double mu = p.noise_per_m2 * box_m2;
    const double threshold = mu + s.noise_sigmas * std::sqrt(mu) + 1.0;
    signal[i] = neighbours > threshold;
    out.confidence[i] = !signal[i]                      ? 0
                        : neighbours >= 2.0 * threshold ? 4
                        : neighbours >= 1.5 * threshold ? 3
                                                        : 2;
  }
}

// The 25 % quantile-regression line through `points` (x, y), evaluated at `x`: of the lines
// through two of the points (an optimum of the check loss lies on one), the one whose weighted
// residuals, 0.25 |r| above it and 0.75 |r| below, sum least; one point: its height.
double lower_envelope_at(const std::vector<std::array<double, 2>>& points, double x) {
  if (points.size() == 1) return points[0][1];
  constexpr double quarter = 0.25;
  double best_loss = std::numeric_limits<double>::infinity(), best = nan;
  for (std::size_t i = 0; i < points.size(); ++i)
    for (std::size_t j = i + 1; j < points.size(); ++j) {
      const double slope = (points[j][1] - points[i][1]) / (points[j][0] - points[i][0]);
      double loss = 0.0;
      for (const auto& p : points) {
        const double r = p[1] - (points[i][1] + slope * (p[0] - points[i][0]));
        loss += r >= 0.0 ? quarter * r : (quarter - 1.0) * r;
      }
      if (loss < best_loss) {
        best_loss = loss;
        best = points[i][1] + slope * (x - points[i][0]);
      }
    }
  return best;
}

// Step 2: the ground surface at the cells' centres.
std::vector<double> fit_ground(std::span<const CloudPhoton> photons,
                               const std::vector<bool>& signal, const Cells& cells) {
  // Each cell's candidate: the lowest 1 m height bin holding at least 3 signal photons and a
  // tenth of the fullest bin's (a lone noise photon below the ground does not make one).
  std::vector<std::vector<double>> heights(cells.count);
  for (std::size_t i = 0; i < photons.size(); ++i)
    if (signal[i]) heights[cells.of(photons[i].along_m)].push_back(photons[i].h_m);
  std::vector<double> lowest(cells.count, nan);
  for (std::size_t c = 0; c < cells.count; ++c) {
    if (heights[c].empty()) continue;
    const auto [lo, hi] = std::minmax_element(heights[c].begin(), heights[c].end());
    std::vector<double> bins(static_cast<std::size_t>(*hi - *lo) + 1, 0.0);
    for (const double h : heights[c]) bins[static_cast<std::size_t>(h - *lo)] += 1.0;
    const double needed = std::max(3.0, 0.1 * *std::max_element(bins.begin(), bins.end()));
    for (std::size_t k = 0; k < bins.size(); ++k)
      if (bins[k] >= needed) {
        lowest[c] = *lo + static_cast<double>(k) + 0.5;
        break;
      }
  }
  // A cell's candidate is its ground when it lies within 5 m above the lower envelope of the
  // other cells' candidates within 100 m: the line under which a quarter of them lie (the 25 %
  // quantile regression, one-sided at the track's ends), the cell itself left out so that the
  // line cannot climb to it. A line follows a slope as the ground does; a quarter of 20 cells
  // keeps canopy-only cells (a weak beam under dense crowns, several together at a track's end)
  // from outvoting the ground, as a median of five did. A ground candidate rejected on a sharp
  // ridge (more than 5 m above the line) is filled from its neighbours and refined below.
  std::vector<double> ground(cells.count, nan);
  for (std::size_t c = 0; c < cells.count; ++c) {
    if (std::isnan(lowest[c])) continue;
    std::vector<std::array<double, 2>> around;
    for (std::size_t k = c >= 10 ? c - 10 : 0; k < std::min(cells.count, c + 11); ++k)
      if (k != c && !std::isnan(lowest[k])) around.push_back({static_cast<double>(k), lowest[k]});
    if (around.empty() || lowest[c] <= lower_envelope_at(around, static_cast<double>(c)) + 5.0)
      ground[c] = lowest[c];
  }
  fill_gaps(ground);
  for (const double band_m : {3.0, 1.5, 1.0}) {
    std::vector<std::vector<double>> near(cells.count);
    for (std::size_t i = 0; i < photons.size(); ++i) {
      if (!signal[i]) continue;
      const std::size_t c = cells.of(photons[i].along_m);
      if (std::abs(photons[i].h_m - ground[c]) <= band_m) near[c].push_back(photons[i].h_m);
    }
    for (std::size_t c = 0; c < cells.count; ++c) ground[c] = median(near[c]);
    fill_gaps(ground);
  }
  return ground;
}

// Step 3: ground, canopy and top of canopy about the fitted surface.
void assign_classes(std::span<const CloudPhoton> photons, const std::vector<bool>& signal,
                    const Cells& cells, const Atl08Settings& s, Atl08Classes& out) {
  std::vector<double> residuals;
  for (std::size_t i = 0; i < photons.size(); ++i) {
    const double r = photons[i].h_m - out.ground_at(photons[i].along_m);
    if (signal[i] && std::abs(r) <= 1.5) residuals.push_back(std::abs(r));
  }
  const double sigma = residuals.empty() ? 0.0 : 1.4826 * median(residuals);
  const double band_m = std::max(s.min_ground_band_m, 2.5 * sigma);
  std::vector<std::vector<double>> canopy(cells.count);
  for (std::size_t i = 0; i < photons.size(); ++i) {
    out.classes[i] = 0;
    if (!signal[i]) continue;
    const double r = photons[i].h_m - out.ground_at(photons[i].along_m);
    if (std::abs(r) <= band_m) {
      out.classes[i] = 1;
    } else if (r > band_m) {
      out.classes[i] = 2;
      canopy[cells.of(photons[i].along_m)].push_back(r);
    }
  }
  std::vector<double> top(cells.count, nan);
  for (std::size_t c = 0; c < cells.count; ++c)
    top[c] = quantile(canopy[c], s.top_of_canopy_quantile);
  for (std::size_t i = 0; i < photons.size(); ++i) {
    if (out.classes[i] != 2) continue;
    const double r = photons[i].h_m - out.ground_at(photons[i].along_m);
    if (r >= top[cells.of(photons[i].along_m)]) out.classes[i] = 3;
  }
}

}  // namespace

double Atl08Classes::ground_at(double along_m) const {
  if (ground_m.empty()) return nan;
  const double position = (along_m - first_cell_m) / cell_m;
  if (position <= 0.0) return ground_m.front();
  const std::size_t below = static_cast<std::size_t>(std::floor(position));
  if (below + 1 >= ground_m.size()) return ground_m.back();
  const double t = position - static_cast<double>(below);
  return ground_m[below] + t * (ground_m[below + 1] - ground_m[below]);
}

Atl08Classes classify_photons(std::span<const CloudPhoton> photons, const Atl08Settings& settings) {
  Atl08Classes out;
  out.classes.assign(photons.size(), 0);
  out.confidence.assign(photons.size(), 0);
  out.cell_m = settings.cell_m;
  if (photons.empty()) return out;
  std::vector<bool> signal(photons.size(), false);
  filter_noise(photons, settings, out, signal);
  const Cells cells = cells_over(photons, settings.cell_m);
  out.first_cell_m = cells.first_m + 0.5 * cells.cell_m;
  out.ground_m = fit_ground(photons, signal, cells);
  assign_classes(photons, signal, cells, settings, out);
  return out;
}

namespace {

// The photons of one land segment, as its metrics need them.
struct SegmentPhotons {
  std::vector<double> ground_along_m, ground_h_m;  // ground photons
  std::vector<double> canopy_m, canopy_abs_m;      // canopy and top of canopy: above ground, WGS84
  std::vector<double> canopy_along_m;
  std::vector<double> toc_m;  // top of canopy, above ground
};

// The sample standard deviation (n - 1), NaN for fewer than two values.
double standard_deviation(const std::vector<double>& values) {
  const double n = static_cast<double>(values.size());
  if (n < 2.0) return std::numeric_limits<double>::quiet_NaN();
  const double mean = std::accumulate(values.begin(), values.end(), 0.0) / n;
  double sum2 = 0.0;
  for (const double v : values) sum2 += (v - mean) * (v - mean);
  return std::sqrt(sum2 / (n - 1.0));
}

// h_te_mean, h_te_median, terrain_slope and h_te_uncertainty from the ground photons.
void terrain_metrics(LandSegment& segment, const SegmentPhotons& p) {
  const double n = static_cast<double>(p.ground_h_m.size());
  const double mean_h = std::accumulate(p.ground_h_m.begin(), p.ground_h_m.end(), 0.0) / n;
  const double mean_x = std::accumulate(p.ground_along_m.begin(), p.ground_along_m.end(), 0.0) / n;
  double sxx = 0.0, sxh = 0.0;
  for (std::size_t i = 0; i < p.ground_h_m.size(); ++i) {
    sxx += (p.ground_along_m[i] - mean_x) * (p.ground_along_m[i] - mean_x);
    sxh += (p.ground_along_m[i] - mean_x) * (p.ground_h_m[i] - mean_h);
  }
  const double slope = sxx > 0.0 ? sxh / sxx : 0.0;
  double residual2 = 0.0;
  for (std::size_t i = 0; i < p.ground_h_m.size(); ++i) {
    const double r = p.ground_h_m[i] - mean_h - slope * (p.ground_along_m[i] - mean_x);
    residual2 += r * r;
  }
  segment.h_te_mean = mean_h;
  segment.h_te_median = median(p.ground_h_m);
  const auto [low, high] = std::minmax_element(p.ground_h_m.begin(), p.ground_h_m.end());
  segment.h_te_min = *low;
  segment.h_te_max = *high;
  segment.terrain_slope = slope;
  // The line's two parameters leave n - 2 degrees of freedom.
  segment.h_te_uncertainty = n > 2.0 ? std::sqrt(residual2 / (n - 2.0)) / std::sqrt(n) : nan;
  segment.h_te_std = standard_deviation(p.ground_h_m);
}

// h_canopy, canopy_openness, h_mean_canopy and h_mean_canopy_abs from the canopy photons.
void canopy_metrics(LandSegment& segment, const SegmentPhotons& p) {
  const std::vector<double>& heights = p.canopy_m;
  const double n = static_cast<double>(heights.size());
  segment.h_canopy = quantile(heights, 0.98);
  const double mean = std::accumulate(heights.begin(), heights.end(), 0.0) / n;
  double sum2 = 0.0;
  for (const double h : heights) sum2 += (h - mean) * (h - mean);
  segment.canopy_openness = n > 1.0 ? std::sqrt(sum2 / (n - 1.0)) : nan;
  segment.h_mean_canopy = mean;
  const auto [low, high] = std::minmax_element(heights.begin(), heights.end());
  segment.h_min_canopy = *low;
  segment.h_max_canopy = *high;
  segment.h_median_canopy = median(heights);
  for (std::size_t q = 0; q < segment.canopy_h_metrics.size(); ++q)
    segment.canopy_h_metrics[q] = quantile(heights, 0.10 + 0.05 * static_cast<double>(q));
  segment.h_mean_canopy_abs =
      std::accumulate(p.canopy_abs_m.begin(), p.canopy_abs_m.end(), 0.0) / n;
  segment.toc_roughness = standard_deviation(p.toc_m);
}

// The five sub-segments' ground and canopy heights.
void sub_segment_metrics(LandSegment& segment, const SegmentPhotons& p, const Atl08Classes& classes,
                         const Atl08Settings& settings) {
  const double width_m = settings.segment_m / 5.0;
  for (std::size_t j = 0; j < 5; ++j) {
    const double from = segment.start_m + static_cast<double>(j) * width_m, to = from + width_m;
    const auto inside = [&](double along_m) { return along_m >= from && along_m < to; };
    const auto ground = std::count_if(p.ground_along_m.begin(), p.ground_along_m.end(), inside);
    segment.h_te_best_fit_20m[j] = ground >= 3 ? classes.ground_at(from + 0.5 * width_m) : nan;
    std::vector<double> canopy;
    for (std::size_t i = 0; i < p.canopy_m.size(); ++i)
      if (inside(p.canopy_along_m[i])) canopy.push_back(p.canopy_m[i]);
    segment.h_canopy_20m[j] = static_cast<int>(canopy.size()) >= settings.min_canopy_photons
                                  ? quantile(canopy, 0.98)
                                  : nan;
  }
}

// Heights to 0.1 m bins: the fullest bin's centre, the lowest of ties.
double histogram_mode(const std::vector<double>& heights_m) {
  constexpr double bin_m = 0.1;
  std::map<long long, int> counts;
  for (const double h : heights_m) ++counts[std::llround(h / bin_m)];
  long long best = 0;
  int most = 0;
  for (const auto& [bin, n] : counts)
    if (n > most) best = bin, most = n;
  return static_cast<double>(best) * bin_m;
}

std::int8_t canopy_confidence(double canopy, double ground) {
  const double classified = canopy + ground;
  if (classified <= 0.0) return -1;
  if (canopy < 0.05 * classified) return 0;
  return ground < 0.05 * classified ? 1 : 2;
}

void no_canopy(LandSegment& segment) {
  segment.h_canopy = segment.canopy_openness = segment.h_mean_canopy = segment.h_mean_canopy_abs =
      segment.h_min_canopy = segment.h_median_canopy = segment.h_max_canopy =
          segment.toc_roughness = nan;
  segment.canopy_h_metrics.fill(nan);
}

}  // namespace

std::vector<LandSegment> land_segments(std::span<const CloudPhoton> photons,
                                       const Atl08Classes& classes, double first_m, double end_m,
                                       const Atl08Settings& settings) {
  const std::size_t count =
      end_m > first_m ? static_cast<std::size_t>(std::ceil((end_m - first_m) / settings.segment_m))
                      : 0;
  std::vector<LandSegment> segments(count);
  std::vector<SegmentPhotons> members(count);
  for (std::size_t i = 0; i < photons.size(); ++i) {
    const double k = std::floor((photons[i].along_m - first_m) / settings.segment_m);
    if (k < 0.0 || k >= static_cast<double>(count)) continue;
    LandSegment& segment = segments[static_cast<std::size_t>(k)];
    SegmentPhotons& p = members[static_cast<std::size_t>(k)];
    const std::uint8_t c = classes.classes[i];
    if (c == 0) ++segment.n_noise_photons;
    if (c == 1) {
      ++segment.n_te_photons;
      p.ground_along_m.push_back(photons[i].along_m);
      p.ground_h_m.push_back(photons[i].h_m);
    }
    if (c == 2) ++segment.n_ca_photons;
    if (c == 3) ++segment.n_toc_photons;
    if (c >= 2) {
      p.canopy_m.push_back(photons[i].h_m - classes.ground_at(photons[i].along_m));
      p.canopy_abs_m.push_back(photons[i].h_m);
      p.canopy_along_m.push_back(photons[i].along_m);
      if (c == 3) p.toc_m.push_back(p.canopy_m.back());
    }
  }
  for (std::size_t k = 0; k < count; ++k) {
    LandSegment& segment = segments[k];
    segment.start_m = first_m + static_cast<double>(k) * settings.segment_m;
    const bool terrain = segment.n_te_photons >= settings.min_ground_photons;
    segment.h_te_best_fit =
        terrain ? classes.ground_at(segment.start_m + 0.5 * settings.segment_m) : nan;
    sub_segment_metrics(segment, members[k], classes, settings);
    if (terrain)
      terrain_metrics(segment, members[k]);
    else
      segment.h_te_mean = segment.h_te_median = segment.h_te_min = segment.h_te_max =
          segment.h_te_uncertainty = segment.terrain_slope = segment.h_te_std = nan;
    segment.h_te_mode = members[k].ground_h_m.empty() ? nan : histogram_mode(members[k].ground_h_m);
    const double canopy = static_cast<double>(members[k].canopy_m.size());
    const double signal = canopy + segment.n_te_photons;
    segment.canopy_rh_conf = canopy_confidence(canopy, segment.n_te_photons);
    if (canopy < settings.min_canopy_photons || canopy < settings.min_canopy_fraction * signal)
      no_canopy(segment);
    else
      canopy_metrics(segment, members[k]);
  }
  return segments;
}

}  // namespace glaswave
