// The atmosphere's layers as the lidar's rays cross them.
#include "pipeline/transport/atmosphere.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {
namespace {

constexpr double inf = std::numeric_limits<double>::infinity();
// A ray that scatters this often in the layers is given up: at the presets' optical depths (3 at
// most) it has long left the field of view.
constexpr int most_scatterings = 200;

double henyey_greenstein(double g, double cos_angle) {
  const double d = 1.0 + g * g - 2.0 * g * cos_angle;
  return (1.0 - g * g) / (4.0 * std::numbers::pi * d * std::sqrt(d));
}

// Inverse of Henyey-Greenstein's cumulative distribution in the cosine.
double henyey_greenstein_cosine(double g, double u) {
  if (std::abs(g) < 1e-6) return 2.0 * u - 1.0;
  const double s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
  return std::clamp((1.0 + g * g - s * s) / (2.0 * g), -1.0, 1.0);
}

// `direction` turned by the angle of cosine `cos_angle` about itself, toward azimuth 2 pi u.
Vec3 turned(const Vec3& direction, double cos_angle, double u) {
  const Vec3 helper = std::abs(direction[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{1.0, 0.0, 0.0};
  const Vec3 a = normalized(cross(helper, direction));
  const Vec3 b = cross(direction, a);
  const double sin_angle = std::sqrt(std::max(0.0, 1.0 - cos_angle * cos_angle));
  const double phi = 2.0 * std::numbers::pi * u;
  return normalized(cos_angle * direction + (sin_angle * std::cos(phi)) * a +
                    (sin_angle * std::sin(phi)) * b);
}

}  // namespace

double phase_function(const AtmospherePhase& phase, double cos_angle) {
  switch (phase.kind) {
    case AtmospherePhase::Kind::rayleigh:
      return 3.0 / (16.0 * std::numbers::pi) * (1.0 + cos_angle * cos_angle);
    case AtmospherePhase::Kind::henyey_greenstein:
      return henyey_greenstein(phase.g1, cos_angle);
    case AtmospherePhase::Kind::two_term_henyey_greenstein:
      return phase.weight * henyey_greenstein(phase.g1, cos_angle) +
             (1.0 - phase.weight) * henyey_greenstein(phase.g2, cos_angle);
  }
  return 0.0;
}

double sample_phase_cosine(const AtmospherePhase& phase, double u1, double u2) {
  switch (phase.kind) {
    case AtmospherePhase::Kind::rayleigh: {
      // The cumulative (mu^3 + 3 mu + 4) / 8 inverted by Cardano's formula.
      const double q = 8.0 * u1 - 4.0;
      const double a = std::cbrt(0.5 * q + std::sqrt(0.25 * q * q + 1.0));
      return std::clamp(a - 1.0 / a, -1.0, 1.0);
    }
    case AtmospherePhase::Kind::henyey_greenstein:
      return henyey_greenstein_cosine(phase.g1, u1);
    case AtmospherePhase::Kind::two_term_henyey_greenstein:
      return henyey_greenstein_cosine(u2 < phase.weight ? phase.g1 : phase.g2, u1);
  }
  return 1.0;
}

std::vector<std::size_t> detected_layers(const AtmosphereSettings& settings, std::size_t band) {
  // A layer's volume scattering coefficient (per m) and its backscatter (per m per sr).
  auto scattering = [band](const AtmosphereLayer& layer) {
    const double thickness = layer.top_m - layer.base_m;
    return thickness > 0.0
               ? layer.optical_depth[band] * layer.single_scattering_albedo[band] / thickness
               : 0.0;
  };
  std::vector<std::size_t> found;
  for (std::size_t i = 0; i < settings.layers.size(); ++i) {
    const AtmosphereLayer& layer = settings.layers[i];
    if (layer.phase.kind == AtmospherePhase::Kind::rayleigh) continue;
    const double backscatter = scattering(layer) * phase_function(layer.phase, -1.0);
    if (!(backscatter > 0.0)) continue;
    const double middle_m = 0.5 * (layer.base_m + layer.top_m);
    double molecules = 0.0;
    for (const AtmosphereLayer& other : settings.layers)
      if (other.phase.kind == AtmospherePhase::Kind::rayleigh && other.base_m <= middle_m &&
          middle_m < other.top_m)
        molecules += scattering(other) * phase_function(other.phase, -1.0);
    if (backscatter >= molecules) found.push_back(i);
  }
  return found;
}

AtmosphereModel::AtmosphereModel(const AtmosphereSettings& settings, std::size_t bands,
                                 double ground_z_m, double ground_height_m, double floor_z_m)
    : bands_(bands), floor_z_m_(floor_z_m), column_(bands, 0.0) {
  std::vector<double> boundaries = {floor_z_m};
  for (const AtmosphereLayer& layer : settings.layers) {
    const double shift = ground_z_m - (layer.above_ellipsoid ? ground_height_m : 0.0);
    const double base = layer.base_m + shift, top = layer.top_m + shift;
    if (!(top > base)) continue;
    const double z0 = std::max(base, floor_z_m);
    if (!(top > z0)) continue;
    Slab slab;
    slab.z0 = z0;
    slab.z1 = top;
    slab.phase = layer.phase;
    for (std::size_t b = 0; b < bands; ++b) {
      const double extinction = layer.optical_depth[b] / (top - base);
      slab.extinction.push_back(extinction);
      slab.scattering.push_back(extinction * layer.single_scattering_albedo[b]);
      slab.sampling = std::max(slab.sampling, slab.scattering.back());
    }
    boundaries.push_back(slab.z0);
    boundaries.push_back(slab.z1);
    slabs_.push_back(std::move(slab));
  }
  std::sort(boundaries.begin(), boundaries.end());
  boundaries.erase(std::unique(boundaries.begin(), boundaries.end()), boundaries.end());
  for (std::size_t i = 0; i + 1 < boundaries.size(); ++i) {
    Interval interval;
    interval.z0 = boundaries[i];
    interval.z1 = boundaries[i + 1];
    interval.extinction.assign(bands, 0.0);
    for (std::size_t s = 0; s < slabs_.size(); ++s) {
      const Slab& slab = slabs_[s];
      if (slab.z0 > interval.z0 || slab.z1 < interval.z1) continue;
      interval.slabs.push_back(static_cast<int>(s));
      interval.sampling += slab.sampling;
      for (std::size_t b = 0; b < bands; ++b) {
        interval.extinction[b] += slab.extinction[b];
        interval.scattering_all += slab.scattering[b];
      }
    }
    const double thickness = interval.z1 - interval.z0;
    for (std::size_t b = 0; b < bands; ++b) column_[b] += interval.extinction[b] * thickness;
    scattering_column_ += interval.scattering_all * thickness;
    intervals_.push_back(std::move(interval));
  }
}

double AtmosphereModel::optical_depth(std::size_t band, double z_low, double z_high) const {
  double tau = 0.0;
  for (const Interval& interval : intervals_) {
    const double overlap = std::min(z_high, interval.z1) - std::max(z_low, interval.z0);
    if (overlap > 0.0) tau += interval.extinction[band] * overlap;
  }
  return tau;
}

// The interval a ray at height z moving by dz per m is in: at a boundary, the one it enters.
// -1 below the floor, size() above the top.
int AtmosphereModel::interval_at(double z, double dz) const {
  const int n = static_cast<int>(intervals_.size());
  for (int i = 0; i < n; ++i) {
    const Interval& interval = intervals_[i];
    if (z > interval.z0 && z < interval.z1) return i;
    if (z == interval.z0 && dz > 0.0) return i;
    if (z == interval.z1 && dz <= 0.0) return i;
  }
  return z <= floor_z_m_ ? -1 : n;
}

bool AtmosphereModel::cross(Vec3& position, Vec3& direction, double& path_m,
                            std::span<double> weight, const std::function<double()>& uniform,
                            int* scatterings, const ScatterSeen* seen) const {
  int scattered = 0;
  // Told however the crossing ends.
  struct Count {
    int* out;
    const int& value;
    ~Count() {
      if (out) *out = value;
    }
  } count{scatterings, scattered};
  if (intervals_.empty()) return true;
  const double top = intervals_.back().z1;
  const int n = static_cast<int>(intervals_.size());
  // From above the layers straight down to their top.
  if (position[2] > top) {
    if (!(direction[2] < 0.0)) return false;
    const double to_top = (position[2] - top) / -direction[2];
    position = position + to_top * direction;
    position[2] = top;
    path_m += to_top;
  }
  int i = interval_at(position[2], direction[2]);
  while (i >= 0 && i < n) {
    const Interval& interval = intervals_[i];
    const double dz = direction[2];
    const double exit_m = dz < 0.0   ? (position[2] - interval.z0) / -dz
                          : dz > 0.0 ? (interval.z1 - position[2]) / dz
                                     : inf;
    const double free_m =
        interval.sampling > 0.0 ? -std::log1p(-uniform()) / interval.sampling : inf;
    const double step_m = std::min(exit_m, free_m);
    if (!std::isfinite(step_m)) return false;  // level, and nothing to turn it
    for (std::size_t b = 0; b < bands_; ++b)
      weight[b] *= std::exp(-(interval.extinction[b] - interval.sampling) * step_m);
    position = position + step_m * direction;
    path_m += step_m;
    if (exit_m <= free_m) {
      position[2] = dz < 0.0 ? interval.z0 : interval.z1;
      i += dz < 0.0 ? -1 : 1;
      continue;
    }
    if (++scattered > most_scatterings) return false;
    // Which slab scattered: by its share of the sampling coefficient.
    int chosen = interval.slabs.front();
    if (interval.slabs.size() > 1) {
      double pick = uniform() * interval.sampling;
      for (int s : interval.slabs) {
        chosen = s;
        pick -= slabs_[s].sampling;
        if (pick < 0.0) break;
      }
    }
    const Slab& slab = slabs_[chosen];
    for (std::size_t b = 0; b < bands_; ++b) weight[b] *= slab.scattering[b] / slab.sampling;
    if (seen) (*seen)(position, direction, slab.phase, weight);
    const double u1 = uniform(), u2 = uniform(), u3 = uniform();
    direction = turned(direction, sample_phase_cosine(slab.phase, u1, u3), u2);
    i = interval_at(position[2], direction[2]);
  }
  return i < 0;
}

bool AtmosphereModel::scatter_point(const Vec3& sensor, const Vec3& down, double u,
                                    ScatterPoint& out) const {
  if (!(scattering_column_ > 0.0) || !(down[2] < 0.0)) return false;
  double left = u * scattering_column_;
  for (const Interval& interval : intervals_) {
    const double column = interval.scattering_all * (interval.z1 - interval.z0);
    if (column <= 0.0) continue;
    if (left < column || &interval == &intervals_.back()) {
      out.z_m = std::min(interval.z1, interval.z0 + left / interval.scattering_all);
      out.point = sensor + ((sensor[2] - out.z_m) / -down[2]) * down;
      return true;
    }
    left -= column;
  }
  return false;
}

void AtmosphereModel::scattering_factor(const ScatterPoint& at, const Vec3& down, double cos_angle,
                                        std::span<double> factor) const {
  std::fill(factor.begin(), factor.end(), 0.0);
  const int i = interval_at(at.z_m, 1.0);
  const int n = static_cast<int>(intervals_.size());
  const Interval& interval = intervals_[std::clamp(i, 0, n - 1)];
  if (!(interval.scattering_all > 0.0)) return;
  // The point's density along the ray: scattering_all(z) |dz/ds| / column.
  const double per_density = scattering_column_ / (interval.scattering_all * -down[2]);
  for (int s : interval.slabs) {
    const double p = phase_function(slabs_[s].phase, cos_angle);
    for (std::size_t b = 0; b < bands_; ++b) factor[b] += slabs_[s].scattering[b] * p;
  }
  for (double& f : factor) f *= per_density;
}

}  // namespace glaswave
