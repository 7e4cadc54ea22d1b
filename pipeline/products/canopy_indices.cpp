// The waveform index and the photon-ratio covers: the formulas are set out in the header.
#include "pipeline/products/canopy_indices.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "pipeline/products/waveform_metrics.hpp"

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

}  // namespace

double waveform_index(double canopy_return, double ground_return) {
  if (!std::isfinite(canopy_return) || !std::isfinite(ground_return)) return nan;
  const double total = canopy_return + ground_return;
  if (!(total > 0.0)) return nan;
  return (canopy_return - ground_return) / total;
}

CanopyGroundReturns split_returns(std::span<const double> waveform, double noise_mean,
                                  double begin_bin, double split_bin, double end_bin) {
  std::vector<double> signal(waveform.begin(), waveform.end());
  for (double& v : signal) v -= noise_mean;
  const double split = std::clamp(split_bin, begin_bin, end_bin);
  CanopyGroundReturns r;
  r.canopy = energy_between(signal, begin_bin, split).total;
  r.ground = energy_between(signal, split, end_bin).total;
  return r;
}

PhotonClassCounts count_photon_classes(std::span<const std::uint8_t> classed_pc_flag) {
  PhotonClassCounts c;
  for (const std::uint8_t flag : classed_pc_flag) {
    if (flag == 1) ++c.ground;
    if (flag == 2) ++c.canopy;
    if (flag == 3) ++c.top_of_canopy;
  }
  return c;
}

PhotonCover photon_ratio_cover(const PhotonClassCounts& counts, double rhov_rhog) {
  const double canopy = static_cast<double>(counts.canopy + counts.top_of_canopy);
  const double ground = static_cast<double>(counts.ground);
  PhotonCover cover{nan, nan};
  if (!(canopy + ground > 0.0)) return cover;
  cover.photon_ratio = canopy / (canopy + ground);
  if (rhov_rhog > 0.0) cover.reflectance_corrected = canopy / (canopy + rhov_rhog * ground);
  return cover;
}

}  // namespace glaswave
