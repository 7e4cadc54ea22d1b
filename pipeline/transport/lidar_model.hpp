// The lidar as the transport sees it (the seed's section 2.2): a Gaussian (or uniform) beam inside
// a top-hat field of view, time bins about the reference return, and the Gaussian pulse.
#pragma once

#include <vector>

#include "core/turn_trig.hpp"
#include "core/vec3.hpp"
#include "footprints/lidar_settings.hpp"

namespace glaswave {

constexpr double speed_of_light_m_s = 299792458.0;

class LidarModel {
 public:
  explicit LidarModel(const LidarSettings& sensor);

  const LidarSettings& sensor() const { return sensor_; }
  std::size_t band_count() const { return sensor_.bands.size(); }

  // Part of the beam's energy inside the field of view: 1 - exp(-ifov^2 / (8 sigma^2)) for a
  // Gaussian beam; for a uniform one the field of view's solid angle over the beam's, at most 1.
  double fov_fraction() const { return fov_fraction_; }
  // The beam's angular RMS width per axis, whatever its profile.
  double beam_sigma_rad() const { return sensor_.divergence_sigma_rad; }
  bool uniform_beam() const { return uniform_beam_; }
  // A uniform beam's half-angle: 2 sigma (the RMS per axis of a uniform disc is its radius / 2).
  double uniform_beam_half_angle_rad() const { return 2.0 * sensor_.divergence_sigma_rad; }
  // The beam's irradiance at `angle_rad` from its axis as a density over the field of view's
  // directions (per sr): what the beam's rays are drawn by.
  double beam_density_sr(double angle_rad) const;
  // Largest angle from the axis at which a ray is sampled: the field of view's edge.
  double max_angle_rad() const { return max_angle_rad_; }
  // Solid angle of the field of view (sr).
  double fov_solid_angle_sr() const;

  // Time bins: bin i is centred at bin_time_ns()[i] after the return from the reference range.
  int bins() const { return sensor_.bins; }
  std::vector<double> bin_time_ns() const;
  double bin_time_ns(int bin) const { return bin * sensor_.bin_ns - lead_ns_; }

  // Tallies cover the bins plus a margin of pulse width on each side, so that light just
  // outside the window still spreads into it. Index for a two-way time after the reference
  // return, or -1 outside the tally.
  int tally_size() const { return sensor_.bins + 2 * margin_bins_; }
  int margin_bins() const { return margin_bins_; }
  int tally_index(double time_ns) const;
  // An energy tally (J per bin) convolved with the pulse: power (W) in each window bin.
  std::vector<double> power_W(const std::vector<double>& tally_J) const;
  // The variance of power_W for independent tally bins of the given variances (J^2): W^2.
  std::vector<double> power_variance_W2(const std::vector<double>& variance_J2) const;

  // The transmitted pulse of a band: power (W) at tx_time_ns about its peak.
  std::vector<double> tx_time_ns() const;
  std::vector<double> tx_waveform_W(std::size_t band) const;

 private:
  LidarSettings sensor_;
  bool uniform_beam_;
  double fov_fraction_;
  double max_angle_rad_;
  double lead_ns_;                      // time from the centre of bin 0 to the reference return
  int margin_bins_;                     // half-width of the pulse kernel
  std::vector<double> kernel_;          // pulse sampled at the bin spacing, sums to 1
  std::vector<double> kernel_squared_;  // its squares, for variances
};

// Samples ray directions about a beam axis in proportion to the beam's irradiance, within
// the field of view (importance sampling: a wide field of view costs nothing).
class BeamSampler {
 public:
  BeamSampler(const LidarModel& lidar, const Vec3& axis);
  // Direction for two uniform numbers in [0, 1).
  Vec3 direction(double u1, double u2) const;
  // Direction uniform over the field of view, for two uniform numbers in [0, 1).
  Vec3 uniform_direction(double u1, double u2) const;
  // Direction at angle `angle_rad` from the axis, toward `azimuth_rad` about it.
  Vec3 direction_at(double angle_rad, double azimuth_rad) const;

 private:
  Vec3 direction_at(double angle_rad, const SinCos& azimuth) const;

  Vec3 axis_, across_, along_;
  double two_sigma_sq_;
  double fov_fraction_;
  double sin_quarter_fov_;
  bool uniform_beam_;
  double sin_half_lit_;  // a uniform beam: sin of half the half-angle it lights inside the view
};

}  // namespace glaswave
