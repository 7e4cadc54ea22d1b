// Beam, field of view, time bins and pulse of the lidar.
#include "pipeline/transport/lidar_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace glaswave {

namespace {

// Solid angle of a cone of half-angle a: 2 pi (1 - cos a) = 4 pi sin^2(a / 2), in sines that keep
// their precision at microradians.
double cone_solid_angle_sr(double half_angle_rad) {
  const double s = std::sin(0.5 * half_angle_rad);
  return 4.0 * std::numbers::pi * s * s;
}

}  // namespace

LidarModel::LidarModel(const LidarSettings& sensor)
    : sensor_(sensor), uniform_beam_(sensor.beam_profile == "uniform") {
  const double sigma = sensor.divergence_sigma_rad;
  const double half_fov = 0.5 * sensor.ifov_rad;
  fov_fraction_ = uniform_beam_
                      ? std::min(1.0, cone_solid_angle_sr(half_fov) /
                                          cone_solid_angle_sr(uniform_beam_half_angle_rad()))
                      : -std::expm1(-half_fov * half_fov / (2.0 * sigma * sigma));
  // Rays for multiple scattering come from the whole field of view (see shot_transport.cpp).
  max_angle_rad_ = half_fov;
  // The reference return sits at the centre of a bin two thirds into the window: canopy comes
  // before the ground, and a level surface's return is not shifted by half a bin.
  lead_ns_ = std::floor(2.0 * sensor.bins / 3.0) * sensor.bin_ns;
  margin_bins_ = pulse_margin_bins(sensor);
  double sum = 0.0;
  for (int k = -margin_bins_; k <= margin_bins_; ++k) {
    const double t = k * sensor.bin_ns / sensor.pulse_sigma_ns;
    kernel_.push_back(std::exp(-0.5 * t * t));
    sum += kernel_.back();
  }
  for (double& weight : kernel_) {
    weight /= sum;
    kernel_squared_.push_back(weight * weight);
  }
}

double LidarModel::fov_solid_angle_sr() const {
  return cone_solid_angle_sr(0.5 * sensor_.ifov_rad);
}

double LidarModel::beam_density_sr(double angle_rad) const {
  if (uniform_beam_) {
    // 1 / (Omega_beam f_fov) where the beam lights, inside the view: the density of
    // BeamSampler::direction's uniform draw.
    const double lit_rad = std::min(uniform_beam_half_angle_rad(), max_angle_rad_);
    return angle_rad <= lit_rad ? 1.0 / cone_solid_angle_sr(lit_rad) : 0.0;
  }
  const double two_sigma_sq = 2.0 * sensor_.divergence_sigma_rad * sensor_.divergence_sigma_rad;
  return std::exp(-angle_rad * angle_rad / two_sigma_sq) /
         (std::numbers::pi * two_sigma_sq * fov_fraction_);
}

std::vector<double> LidarModel::bin_time_ns() const {
  std::vector<double> times(sensor_.bins);
  for (int i = 0; i < sensor_.bins; ++i) times[i] = bin_time_ns(i);
  return times;
}

int LidarModel::tally_index(double time_ns) const {
  const double position = (time_ns + lead_ns_) / sensor_.bin_ns + 0.5 + margin_bins_;
  if (!(position >= 0.0) || position >= tally_size()) return -1;
  return static_cast<int>(position);
}

namespace {

// A tally (bins of the window with `margin` more either side) convolved with a kernel of
// 2 margin + 1 weights, over the window's `bins`, divided by `divisor`. A window bin that reaches
// no scored tally bin stays 0 (a few-ray shot's tally is mostly zeros), the sum over zeros being
// 0 to the bit, whether it is summed or not.
std::vector<double> convolve_scored(const std::vector<double>& tally,
                                    const std::vector<double>& kernel, int bins, double divisor) {
  std::vector<double> out(bins, 0.0);
  const int width = static_cast<int>(kernel.size());
  // Scored tally bins so far.
  std::vector<int> scored(tally.size() + 1, 0);
  for (std::size_t j = 0; j < tally.size(); ++j) scored[j + 1] = scored[j] + (tally[j] != 0.0);
  // Window bin i is tally bin i + margin; the kernel reaches margin bins either side. Four bins
  // at a time, each summed in the same order as alone: four chains of additions at once.
  int i = 0;
  for (; i + 4 <= bins; i += 4) {
    if (scored[i + 3 + width] == scored[i]) continue;
    const double* last = tally.data() + i + width - 1;
    double sum0 = 0.0, sum1 = 0.0, sum2 = 0.0, sum3 = 0.0;
    for (int k = 0; k < width; ++k) {
      sum0 += kernel[k] * last[-k];
      sum1 += kernel[k] * last[1 - k];
      sum2 += kernel[k] * last[2 - k];
      sum3 += kernel[k] * last[3 - k];
    }
    out[i] = sum0 / divisor;
    out[i + 1] = sum1 / divisor;
    out[i + 2] = sum2 / divisor;
    out[i + 3] = sum3 / divisor;
  }
  for (; i < bins; ++i) {
    if (scored[i + width] == scored[i]) continue;
    double sum = 0.0;
    for (int k = 0; k < width; ++k) sum += kernel[k] * tally[i + width - 1 - k];
    out[i] = sum / divisor;
  }
  return out;
}

}  // namespace

std::vector<double> LidarModel::power_W(const std::vector<double>& tally_J) const {
  const double bin_s = sensor_.bin_ns * 1e-9;
  return convolve_scored(tally_J, kernel_, sensor_.bins, bin_s);
}

std::vector<double> LidarModel::power_variance_W2(const std::vector<double>& variance_J2) const {
  const double bin_s = sensor_.bin_ns * 1e-9;
  return convolve_scored(variance_J2, kernel_squared_, sensor_.bins, bin_s * bin_s);
}

std::vector<double> LidarModel::tx_time_ns() const {
  std::vector<double> times;
  for (int k = -margin_bins_; k <= margin_bins_; ++k) times.push_back(k * sensor_.bin_ns);
  return times;
}

std::vector<double> LidarModel::tx_waveform_W(std::size_t band) const {
  const double energy_J = sensor_.bands[band].pulse_energy_mJ * 1e-3;
  const double sigma_s = sensor_.pulse_sigma_ns * 1e-9;
  std::vector<double> power;
  for (double t_ns : tx_time_ns()) {
    const double t = t_ns / sensor_.pulse_sigma_ns;
    power.push_back(energy_J * std::exp(-0.5 * t * t) /
                    (std::sqrt(2.0 * std::numbers::pi) * sigma_s));
  }
  return power;
}

BeamSampler::BeamSampler(const LidarModel& lidar, const Vec3& axis)
    : axis_(normalized(axis)),
      two_sigma_sq_(2.0 * lidar.beam_sigma_rad() * lidar.beam_sigma_rad()),
      fov_fraction_(lidar.fov_fraction()),
      sin_quarter_fov_(std::sin(0.25 * lidar.sensor().ifov_rad)),
      uniform_beam_(lidar.uniform_beam()),
      sin_half_lit_(std::sin(
          0.5 * std::min(lidar.uniform_beam_half_angle_rad(), 0.5 * lidar.sensor().ifov_rad))) {
  // Any two unit vectors across the axis will do; this pair is stable for a nadir axis.
  const Vec3 helper = std::abs(axis_[2]) < 0.9 ? Vec3{0.0, 0.0, 1.0} : Vec3{0.0, 1.0, 0.0};
  across_ = normalized(cross(helper, axis_));
  along_ = cross(axis_, across_);
}

Vec3 BeamSampler::direction(double u1, double u2) const {
  // A uniform beam: uniform in solid angle over the part of its cone inside the view.
  if (uniform_beam_)
    return direction_at(2.0 * std::asin(std::sqrt(u1) * sin_half_lit_), sincos_turn(u2));
  // Radial density of a 2-D Gaussian truncated at the field of view, inverted.
  const double angle_rad = std::sqrt(-two_sigma_sq_ * std::log1p(-u1 * fov_fraction_));
  return direction_at(angle_rad, sincos_turn(u2));
}

Vec3 BeamSampler::uniform_direction(double u1, double u2) const {
  // Uniform in solid angle: 1 - cos(angle) = 2 sin^2(angle / 2) is uniform (written with sines,
  // which keep their precision at the microradians of a lidar's field of view).
  const double angle_rad = 2.0 * std::asin(std::sqrt(u1) * sin_quarter_fov_);
  return direction_at(angle_rad, sincos_turn(u2));
}

Vec3 BeamSampler::direction_at(double angle_rad, double azimuth_rad) const {
  return direction_at(angle_rad, SinCos{std::sin(azimuth_rad), std::cos(azimuth_rad)});
}

Vec3 BeamSampler::direction_at(double angle_rad, const SinCos& azimuth) const {
  const double s = std::sin(angle_rad);
  return std::cos(angle_rad) * axis_ + (s * azimuth.cos) * across_ + (s * azimuth.sin) * along_;
}

}  // namespace glaswave
