// The scattering kernels shared by the transports.
#include "pipeline/transport/scattering.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace glaswave {

std::optional<FreePath> free_path_depth(const std::vector<VolumeSpan>& spans,
                                        const std::vector<double>& projection, double target) {
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
      if (depth + step >= target)
        return FreePath{t_previous + (target - depth) / extinction, extinction};
      depth += step;
    }
    t_previous = t;
    extinction += change;
  }
  return std::nullopt;
}

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

Vec3 cosine_direction(const Vec3& normal, double u1, double u2) {
  const Vec3 helper = std::abs(normal[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{1.0, 0.0, 0.0};
  const Vec3 across = normalized(cross(helper, normal));
  const Vec3 along = cross(normal, across);
  const double r = std::sqrt(u1);
  const SinCos phi = sincos_turn(u2);
  return (r * phi.cos) * across + (r * phi.sin) * along +
         std::sqrt(std::max(0.0, 1.0 - u1)) * normal;
}

bool sample_scattering(RayElement element, const Foliage* material, const SceneOptics& optics,
                       const Vec3& normal, RayRandom& random, Vec3& direction,
                       std::span<double> throughput) {
  const std::size_t bands = throughput.size();
  if (element == RayElement::leaf || element == RayElement::facet) {
    // Reflection sends the path back to the side it came from, transmission through.
    double reflected = 0.0, transmitted = 0.0;
    for (std::size_t band = 0; band < bands; ++band) {
      reflected += throughput[band] * material->reflectance[band];
      transmitted += throughput[band] * material->transmittance[band];
    }
    if (reflected + transmitted <= 0.0) return false;
    const double p_reflect = reflected / (reflected + transmitted);
    const bool reflect = random.uniform() < p_reflect;
    const Vec3 back = -1.0 * direction;  // the side the path arrived from
    const Vec3 facing = dot(normal, back) >= 0.0 ? normal : -1.0 * normal;
    const double v1 = random.uniform(), v2 = random.uniform();
    direction = cosine_direction(reflect ? facing : -1.0 * facing, v1, v2);
    for (std::size_t band = 0; band < bands; ++band)
      throughput[band] *= reflect ? material->reflectance[band] / p_reflect
                                  : material->transmittance[band] / (1.0 - p_reflect);
  } else {
    const double v1 = random.uniform(), v2 = random.uniform();
    direction = cosine_direction(normal, v1, v2);
    for (std::size_t band = 0; band < bands; ++band)
      throughput[band] *= element == RayElement::ground ? optics.soil_reflectance[band]
                                                        : material->trunk_reflectance[band];
  }
  return true;
}

double element_response(RayElement element, const Foliage* material, const SceneOptics& optics,
                        std::size_t band, const Vec3& normal, const Vec3& incoming,
                        const Vec3& outgoing) {
  if (element == RayElement::leaf || element == RayElement::facet)
    return bilambertian_response(normal, incoming, outgoing, material->reflectance[band],
                                 material->transmittance[band]);
  const double reflectance = element == RayElement::ground ? optics.soil_reflectance[band]
                                                           : material->trunk_reflectance[band];
  return reflectance * std::max(0.0, dot(normal, -1.0 * incoming));
}

void project_foliage(const SceneOptics& optics, double cos_zenith,
                     std::vector<double>& projection) {
  for (std::size_t m = 0; m < optics.foliage.size(); ++m) {
    const LeafAngles* angles = optics.foliage[m].leaf_angles;
    projection[m] = m > 0 && angles == optics.foliage[m - 1].leaf_angles
                        ? projection[m - 1]
                        : angles->projection(cos_zenith);
  }
}

std::vector<double> nadir_projection(const SceneOptics& optics) {
  std::vector<double> projection;
  for (const Foliage& foliage : optics.foliage)
    projection.push_back(foliage.leaf_angles ? foliage.leaf_angles->projection(1.0) : 0.0);
  return projection;
}

}  // namespace glaswave
