// GEDI L2B's gap probability, cover, PAI and their profiles: the rules are set out in the header.
#include "pipeline/products/gedi_l2b_algorithm.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "pipeline/products/gedi_l2a_groups.hpp"

namespace glaswave {
namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();

// The waveform above its noise mean as a piecewise-constant function of the fractional bin x
// (bin i's value over [i - 1/2, i + 1/2]), kept only inside [begin, end], with its integral.
class SignalIntegral {
 public:
  SignalIntegral(std::span<const double> waveform, double noise_mean, double begin, double end)
      : begin_(begin), end_(end), value_(waveform.size()), prefix_(waveform.size() + 1, 0.0) {
    for (std::size_t i = 0; i < waveform.size(); ++i) {
      value_[i] = waveform[i] - noise_mean;
      prefix_[i + 1] = prefix_[i] + value_[i];
    }
  }

  // The value at x (0 outside [begin, end] and the bins).
  double at(double x) const {
    if (x < begin_ || x > end_) return 0.0;
    const auto i = static_cast<long>(std::floor(x + 0.5));
    if (i < 0 || i >= static_cast<long>(value_.size())) return 0.0;
    return value_[static_cast<std::size_t>(i)];
  }

  // The integral over [a, b] (a <= b) of the kept signal.
  double over(double a, double b) const { return cumulative(clamp(b)) - cumulative(clamp(a)); }

 private:
  double clamp(double x) const { return std::clamp(x, begin_, end_); }
  // The integral from -1/2 (the first bin's top edge) to x.
  double cumulative(double x) const {
    const double n = static_cast<double>(value_.size());
    x = std::clamp(x, -0.5, n - 0.5);
    const auto i = std::min(static_cast<std::size_t>(std::floor(x + 0.5)), value_.size() - 1);
    return prefix_[i] + value_[i] * (x - (static_cast<double>(i) - 0.5));
  }

  double begin_, end_;
  std::vector<double> value_, prefix_;
};

// The canopy return counted down from the signal's begin: the signal less the mirror image about
// the ground of the signal below it, negative parts set to 0, integrated exactly (both are
// piecewise constant, with steps at the bins' edges and at their mirror images). Returns the
// cumulative integral's knots (position, integral), from begin to the ground.
struct Knots {
  std::vector<double> x, integral;

  double at(double position) const {
    if (x.empty() || position <= x.front()) return 0.0;
    if (position >= x.back()) return integral.back();
    const auto hi =
        static_cast<std::size_t>(std::upper_bound(x.begin(), x.end(), position) - x.begin());
    const double t = (position - x[hi - 1]) / (x[hi] - x[hi - 1]);
    return integral[hi - 1] + t * (integral[hi] - integral[hi - 1]);
  }
};

Knots canopy_cumulative(const SignalIntegral& signal, std::size_t bins, double begin, double ground,
                        double end) {
  std::vector<double> steps = {begin, ground};
  for (std::size_t i = 0; i <= bins; ++i) {
    const double edge = static_cast<double>(i) - 0.5;
    const double mirrored = 2.0 * ground - edge;
    if (edge > begin && edge < ground) steps.push_back(edge);
    if (mirrored > begin && mirrored < ground) steps.push_back(mirrored);
  }
  std::sort(steps.begin(), steps.end());
  steps.erase(std::unique(steps.begin(), steps.end()), steps.end());
  Knots k;
  k.x = steps;
  k.integral.assign(steps.size(), 0.0);
  for (std::size_t j = 1; j < steps.size(); ++j) {
    const double middle = 0.5 * (steps[j - 1] + steps[j]);
    const double below = 2.0 * ground - middle;  // its mirror image below the ground
    const double mirror = below <= end ? signal.at(below) : 0.0;
    const double canopy = std::max(0.0, signal.at(middle) - mirror);
    k.integral[j] = k.integral[j - 1] + canopy * (steps[j] - steps[j - 1]);
  }
  return k;
}

bool finite_waveform(std::span<const double> waveform) {
  for (const double v : waveform)
    if (!std::isfinite(v)) return false;
  return true;
}

// The fractional bin at an elevation (WaveformAxis::elevation_m's inverse).
double bin_at(const WaveformAxis& axis, std::size_t bins, double elevation_m) {
  return (axis.elev_bin0_m - elevation_m) / (axis.elev_bin0_m - axis.elev_lastbin_m) *
         static_cast<double>(bins - 1);
}

}  // namespace

GediL2bResult GediL2bResult::none(const GediL2bSettings& settings) {
  GediL2bResult r;
  r.rhov = settings.rhov;
  r.rhog = settings.rhog;
  r.rossg = settings.rossg;
  r.omega = settings.omega;
  r.rv = r.rg = r.pgap_theta = r.cover = r.pai = r.fhd_normal = nan;
  r.cover_z.fill(nan);
  r.pai_z.fill(nan);
  r.pavd_z.fill(nan);
  return r;
}

GediL2bResult gedi_l2b(const GediL2bInput& input, const GediL2bSettings& settings) {
  GediL2bResult r = GediL2bResult::none(settings);
  const std::size_t bins = input.waveform.size();
  if (bins < 3 || !finite_waveform(input.waveform) || !std::isfinite(input.noise_mean) ||
      !(input.axis.elev_bin0_m > input.axis.elev_lastbin_m) || !std::isfinite(input.zenith_rad))
    return r;
  const double begin = bin_at(input.axis, bins, input.elev_highestreturn_m);
  const double ground = bin_at(input.axis, bins, input.elev_lowestmode_m);
  const double end = bin_at(input.axis, bins, input.elev_lowestreturn_m);
  if (!(begin <= ground && ground <= end)) return r;  // also false for NaN

  const SignalIntegral signal(input.waveform, input.noise_mean, begin, end);
  const double total = signal.over(begin, end);
  if (!(total > 0.0)) return r;
  r.algorithmrun_flag = 1;
  r.rg = 2.0 * signal.over(ground, end);
  r.rv = total - r.rg;
  const double rv = std::max(0.0, r.rv);
  const double denominator = rv + settings.rhov / settings.rhog * r.rg;
  const double mu = std::cos(input.zenith_rad) / (settings.rossg * settings.omega);
  auto pai_of = [&](double pgap) { return pgap > 0.0 ? -std::log(pgap) * mu : nan; };
  r.pgap_theta = 1.0 - rv / denominator;
  r.cover = 1.0 - r.pgap_theta;
  r.pai = pai_of(r.pgap_theta);

  // Rv(z): the canopy return above height z, shaped as the mirrored-ground canopy return and
  // scaled to Rv at the ground.
  const Knots canopy = canopy_cumulative(signal, bins, begin, ground, end);
  const double canopy_total = canopy.integral.back();
  auto rv_above = [&](double height_m) {
    if (height_m <= 0.0) return rv;
    if (!(canopy_total > 0.0)) return 0.0;
    const double x = bin_at(input.axis, bins, input.elev_lowestmode_m + height_m);
    return rv * std::min(1.0, canopy.at(x) / canopy_total);
  };
  auto pgap_above = [&](double height_m) { return 1.0 - rv_above(height_m) / denominator; };

  r.pgap_theta_z.resize(bins);
  for (std::size_t i = 0; i < bins; ++i) {
    const double height_m =
        input.axis.elevation_m(static_cast<double>(i), bins) - input.elev_lowestmode_m;
    r.pgap_theta_z[i] = static_cast<double>(i) < begin ? 1.0 : pgap_above(height_m);
  }
  std::array<double, kL2bProfileBins + 1> pai_above{};
  for (int k = 0; k <= kL2bProfileBins; ++k) pai_above[k] = pai_of(pgap_above(k * kL2bDz_m));
  double pavd_sum = 0.0;
  for (int k = 0; k < kL2bProfileBins; ++k) {
    r.cover_z[k] = 1.0 - pgap_above(k * kL2bDz_m);
    r.pai_z[k] = pai_above[k];
    r.pavd_z[k] = (pai_above[k] - pai_above[k + 1]) / kL2bDz_m;
    pavd_sum += r.pavd_z[k];
  }
  if (pavd_sum > 0.0) {
    r.fhd_normal = 0.0;
    for (const double pavd : r.pavd_z) {
      const double p = pavd / pavd_sum;
      if (p > 0.0) r.fhd_normal -= p * std::log(p);
    }
  }
  // Rv may come out a rounding below 0 over bare ground (total - Rg of equal parts).
  const bool canopy_measured = r.rv >= -1e-9 * total;
  r.l2b_quality_flag = input.l2a_quality_flag && r.rg > 0.0 && canopy_measured ? 1 : 0;
  return r;
}

GediL2bInput l2b_input(std::span<const double> waveform, const WaveformAxis& axis,
                       double noise_mean, const L2aGroupResult& l2a, double zenith_rad) {
  GediL2bInput input;
  input.waveform = waveform;
  input.axis = axis;
  input.noise_mean = noise_mean;
  input.elev_highestreturn_m = l2a.elev_highestreturn_m;
  input.elev_lowestmode_m = l2a.elev_lowestmode_m;
  input.elev_lowestreturn_m = l2a.elev_lowestreturn_m;
  input.zenith_rad = zenith_rad;
  input.l2a_quality_flag = l2a.has_ground;
  return input;
}

}  // namespace glaswave
