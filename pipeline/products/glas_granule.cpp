// GLAS GLAH01- and GLAH14-style granules: NSIDC's paths (GLAH01/GLAH14 release 34 HDF5) and
// GLA14's units; docs/granules.md.
#include "pipeline/products/glas_granule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/part_switch.hpp"
#include "core/registry.hpp"

namespace glaswave {
namespace {

constexpr double kDeg = std::numbers::pi / 180.0;

double or_fill(double value) { return std::isfinite(value) ? value : kGlasFill; }

struct Ellipsoid {
  double a, f;
  double e2() const { return f * (2.0 - f); }
};
constexpr Ellipsoid kWgs84{6378137.0, 1.0 / 298.257223563};
constexpr Ellipsoid kTopex{6378136.3, 1.0 / 298.257};

// The height above `e` of an Earth-fixed point (Bowring's iteration, converged to the
// micrometre in a few steps away from the poles).
double height_above(const Ellipsoid& e, double x, double y, double z) {
  const double p = std::hypot(x, y);
  double lat = std::atan2(z, p * (1.0 - e.e2()));
  double h = 0;
  for (int i = 0; i < 8; ++i) {
    const double s = std::sin(lat);
    const double n = e.a / std::sqrt(1.0 - e.e2() * s * s);
    h = std::abs(std::cos(lat)) > 1e-3 ? p / std::cos(lat) - n : z / s - n * (1.0 - e.e2());
    lat = std::atan2(z, p * (1.0 - e.e2() * n / (n + h)));
  }
  return h;
}

constexpr double kHalfC_m_per_ns = 0.5 * 299792458.0 * 1e-9;  // range per ns of two-way time
constexpr std::int32_t kInt32Fill = std::numeric_limits<std::int32_t>::max();
constexpr std::int8_t kInt8Fill = std::numeric_limits<std::int8_t>::max();  // GLAS's 127

// The fractional bin at `elevation_m` on a waveform's axis (bin 0 at elev_bin0_m).
double bin_at(const ShotRecord& r, std::size_t bins, double elevation_m) {
  const double span = r.elev_bin0_m - r.elev_lastbin_m;
  if (bins < 2 || !(std::abs(span) > 0)) return std::numeric_limits<double>::quiet_NaN();
  return (r.elev_bin0_m - elevation_m) / span * static_cast<double>(bins - 1);
}

// The transmit pulse's peak as an address on the 1 GHz digitiser clock from the first sample
// of r_tx_wf (GLAH01's i_time_txWfPk): the transmitted waveform's times are about its peak.
std::int32_t tx_peak_address(const RunInfo& info) {
  if (info.tx_time_ns.empty() || !std::isfinite(info.tx_time_ns.front())) return 0;
  return static_cast<std::int32_t>(std::lround(-info.tx_time_ns.front()));
}

// The transmitted pulse's RMS width in ns (its power's second moment about its centre).
double tx_sigma_ns(const RunInfo& info, std::size_t band) {
  if (band >= info.tx_waveform_W.size()) return 0.0;
  const std::vector<double>& p = info.tx_waveform_W[band];
  double w = 0, m1 = 0, m2 = 0;
  for (std::size_t i = 0; i < p.size() && i < info.tx_time_ns.size(); ++i) {
    w += p[i];
    m1 += p[i] * info.tx_time_ns[i];
    m2 += p[i] * info.tx_time_ns[i] * info.tx_time_ns[i];
  }
  if (!(w > 0)) return 0.0;
  return std::sqrt(std::max(0.0, m2 / w - (m1 / w) * (m1 / w)));
}

// The skewness in time of the waveform less its noise mean over bins [begin, end]: its third
// central moment over the cube of its RMS width (positive: a tail toward later, lower returns).
double waveform_skewness(const std::vector<double>& counts, double noise_mean, std::size_t begin,
                         std::size_t end) {
  double w = 0, m1 = 0;
  for (std::size_t i = begin; i <= end && i < counts.size(); ++i) {
    w += counts[i] - noise_mean;
    m1 += (counts[i] - noise_mean) * static_cast<double>(i);
  }
  if (!(w > 0)) return std::numeric_limits<double>::quiet_NaN();
  const double mean = m1 / w;
  double m2 = 0, m3 = 0;
  for (std::size_t i = begin; i <= end && i < counts.size(); ++i) {
    const double d = static_cast<double>(i) - mean, v = counts[i] - noise_mean;
    m2 += v * d * d;
    m3 += v * d * d * d;
  }
  m2 /= w;
  m3 /= w;
  return m2 > 0 ? m3 / std::pow(m2, 1.5) : std::numeric_limits<double>::quiet_NaN();
}

// The peaks of the waveform smoothed by a Gaussian of the pulse's width (`sigma_bins`) between
// bins [begin, end] that stand above the noise mean by 4 noise sd and by 1 % of the smoothed
// peak (waveform_metrics.hpp's threshold): GLA14's i_nPeaks1, its smoothed waveform's peaks.
std::int32_t smoothed_peaks(const std::vector<double>& counts, double noise_mean, double noise_sd,
                            double sigma_bins, std::size_t begin, std::size_t end) {
  const std::size_t n = counts.size();
  if (n == 0 || begin > end) return 0;
  std::vector<double> smooth(counts);
  if (sigma_bins > 0) {
    const int reach = static_cast<int>(std::ceil(3.0 * sigma_bins));
    for (std::size_t i = 0; i < n; ++i) {
      double sum = 0, weight = 0;
      for (int k = -reach; k <= reach; ++k) {
        const std::int64_t j = static_cast<std::int64_t>(i) + k;
        if (j < 0 || j >= static_cast<std::int64_t>(n)) continue;
        const double g = std::exp(-0.5 * k * k / (sigma_bins * sigma_bins));
        sum += g * counts[static_cast<std::size_t>(j)];
        weight += g;
      }
      smooth[i] = sum / weight;
    }
  }
  end = std::min(end, n - 1);
  const double peak = *std::max_element(smooth.begin() + static_cast<std::ptrdiff_t>(begin),
                                        smooth.begin() + static_cast<std::ptrdiff_t>(end) + 1);
  const double threshold = noise_mean + std::max(4.0 * noise_sd, 0.01 * (peak - noise_mean));
  std::int32_t peaks = 0;
  for (std::size_t i = std::max<std::size_t>(begin, 1); i <= end && i + 1 < n; ++i)
    if (smooth[i] > threshold && smooth[i] > smooth[i - 1] && smooth[i] >= smooth[i + 1]) ++peaks;
  return peaks;
}

}  // namespace

double glas_delta_ellipsoid_m(double lat_deg, double lon_deg, double h_m) {
  const double lat = lat_deg * kDeg, lon = lon_deg * kDeg;
  const double s = std::sin(lat);
  const double n = kWgs84.a / std::sqrt(1.0 - kWgs84.e2() * s * s);
  const double x = (n + h_m) * std::cos(lat) * std::cos(lon);
  const double y = (n + h_m) * std::cos(lat) * std::sin(lon);
  const double z = (n * (1.0 - kWgs84.e2()) + h_m) * s;
  return h_m - height_above(kTopex, x, y, z);
}

GlasGranuleWriter::GlasGranuleWriter(const std::filesystem::path& final_path, GlasLevel level,
                                     bool topex, const RunInfo& info,
                                     std::optional<std::vector<CloudLayer>> cloud_layers)
    : Hdf5GranuleWriter(final_path, info),
      level_(level),
      topex_(topex),
      cloud_layers_(std::move(cloud_layers)),
      band_(nearest_band(info, 1064.0)) {
  shots_.resize(static_cast<std::size_t>(info.shots));
}

void GlasGranuleWriter::keep(std::int64_t index, const ShotRecord& r) {
  Shot& s = shots_[static_cast<std::size_t>(index)];
  const std::size_t b = band_;
  const std::int64_t number = std::max<std::int64_t>(0, r.source_shot_number);
  s.record = static_cast<std::int32_t>(
      std::min<std::int64_t>(number / 40, std::numeric_limits<std::int32_t>::max()));
  s.count = static_cast<std::int16_t>(number % 40 + 1);
  s.time = r.time_s;
  s.lat = r.lat_deg;
  s.lon = std::isfinite(r.lon_deg) ? std::fmod(r.lon_deg + 360.0, 360.0) : r.lon_deg;
  s.delta_ellip = std::isfinite(r.lat_deg) && std::isfinite(r.lon_deg) && std::isfinite(r.elev_m)
                      ? glas_delta_ellipsoid_m(r.lat_deg, r.lon_deg, r.elev_m)
                      : std::numeric_limits<double>::quiet_NaN();
  // Heights on T/P are WGS84's less d_deltaEllip.
  const double shift = topex_ ? (std::isfinite(s.delta_ellip) ? s.delta_ellip : 0.0) : 0.0;
  auto at = [&](const std::vector<double>& v) {
    return b < v.size() ? v[b] : std::numeric_limits<double>::quiet_NaN();
  };
  s.elev = at(r.centroid_m) - shift;
  s.dem = r.elev_m - shift;
  // GLA14's reflectivity is not corrected for the atmosphere: the seed's eq. (1) without T.
  const double transmission =
      b < info().bands.size() ? info().bands[b].atmos_transmission_roundtrip : 1.0;
  s.reflectance_uc = at(r.reflectance) * transmission;
  const double centroid = at(r.centroid_m);
  // Range offsets from d_elev's: an elevation is d_elev - its offset.
  s.begin_off = centroid - at(r.sig_begin_m);
  s.end_off = centroid - at(r.sig_end_m);
  s.peaks = b < r.n_peaks.size() ? r.n_peaks[b] : 0;
  // GLA14 numbers the Gaussians from the last (lowest) peak; the record from the first.
  std::vector<std::size_t> used;
  if (b < r.gauss_amp_W.size())
    for (std::size_t k = 0; k < r.gauss_amp_W[b].size(); ++k)
      if (std::isfinite(r.gauss_amp_W[b][k])) used.push_back(k);
  std::reverse(used.begin(), used.end());
  const double per_W = info().counts_per_W;
  for (std::size_t i = 0; i < 6; ++i) {
    s.amp[i] = s.area[i] = s.sigma[i] = s.center_off[i] = std::numeric_limits<double>::quiet_NaN();
    if (i >= used.size()) continue;
    const std::size_t k = used[i];
    s.amp[i] = r.gauss_amp_W[b][k] * per_W;
    // The area of a Gaussian of amplitude A counts and width sigma ns, in counts x ns.
    s.sigma[i] = r.gauss_sigma_ns[b][k];
    s.area[i] = s.amp[i] * s.sigma[i] * std::sqrt(2.0 * std::numbers::pi);
    s.center_off[i] = centroid - r.gauss_center_m[b][k];
  }
  s.cover = r.cover_true;
  s.pai = r.pai_true;
  s.height = r.canopy_height_true_m;
  s.pgap = r.pgap_true;
  keep_reader_fields(s, r);
  if (level_ == GlasLevel::glah01) {
    if (b < r.rx_waveform_W.size()) s.rx = to_counts(r.rx_waveform_W[b], per_W);
    if (b < r.rx_waveform_canopy_W.size())
      s.rx_canopy = to_counts(r.rx_waveform_canopy_W[b], per_W);
    if (b < r.rx_waveform_ground_W.size())
      s.rx_ground = to_counts(r.rx_waveform_ground_W[b], per_W);
  }
}

void GlasGranuleWriter::keep_reader_fields(Shot& s, const ShotRecord& r) const {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::size_t b = band_;
  const std::vector<double>& t = info().bin_time_ns;
  const std::size_t n = t.size();
  s.ref_range = s.land_off = s.skew = s.noise_mean = s.noise_sd = nan;
  s.peaks1 = 0;
  s.resp_end = kInt32Fill;
  s.saturated = false;
  if (n < 2 || !std::isfinite(r.range_m)) return;
  // d_refRng: the range to the last (farthest) gate; a bin's range is range_m plus its time.
  s.ref_range = r.range_m + kHalfC_m_per_ns * t.back();
  const double two_way_ns = s.ref_range / kHalfC_m_per_ns;
  if (two_way_ns < 2e9)
    s.resp_end = tx_peak_address(info()) + static_cast<std::int32_t>(std::llround(two_way_ns));
  const double step_ns = (t.back() - t.front()) / static_cast<double>(n - 1);
  auto range_of_elevation = [&](double elevation_m) {
    return r.range_m + kHalfC_m_per_ns * (t.front() + bin_at(r, n, elevation_m) * step_ns);
  };
  const double centroid = b < r.centroid_m.size() ? r.centroid_m[b] : nan;
  s.land_off = range_of_elevation(centroid) - s.ref_range;
  if (b >= r.rx_waveform_W.size() || r.rx_waveform_W[b].size() != n) return;
  std::vector<double> counts(r.rx_waveform_W[b]);
  for (double& c : counts) c *= info().counts_per_W;
  if (info().full_scale_counts > 0)
    s.saturated = *std::max_element(counts.begin(), counts.end()) >= info().full_scale_counts - 0.5;
  const std::vector<float> as_float(counts.begin(), counts.end());
  const double begin_m = b < r.sig_begin_m.size() ? r.sig_begin_m[b] : nan;
  const double end_m = b < r.sig_end_m.size() ? r.sig_end_m[b] : nan;
  const WaveformNoise noise = waveform_noise(as_float, r.elev_bin0_m, r.elev_lastbin_m, begin_m);
  s.noise_mean = noise.mean;
  s.noise_sd = noise.stddev;
  const double first = bin_at(r, n, begin_m), last = bin_at(r, n, end_m);
  if (!std::isfinite(first) || !std::isfinite(last)) return;
  const std::size_t begin = static_cast<std::size_t>(std::clamp(std::floor(first), 0.0, n - 1.0));
  const std::size_t end = static_cast<std::size_t>(std::clamp(std::ceil(last), 0.0, n - 1.0));
  s.skew = waveform_skewness(counts, noise.mean, begin, end);
  s.peaks1 = smoothed_peaks(counts, noise.mean, noise.stddev, tx_sigma_ns(info(), b) / step_ns,
                            begin, end);
}

namespace {

template <typename T, typename Shot, typename F>
std::vector<T> of(const std::vector<Shot>& shots, F get) {
  std::vector<T> values;
  values.reserve(shots.size());
  for (const Shot& s : shots) values.push_back(static_cast<T>(get(s)));
  return values;
}

// A (shot, n) array of a per-shot fixed-length member, missing rows as fill.
template <typename Shot, typename F>
std::vector<float> rows(const std::vector<Shot>& shots, std::size_t n, F get) {
  std::vector<float> values;
  values.reserve(shots.size() * n);
  for (const Shot& s : shots) {
    const std::vector<float>& row = get(s);
    if (row.size() == n)
      values.insert(values.end(), row.begin(), row.end());
    else
      values.insert(values.end(), n, std::numeric_limits<float>::max());
  }
  return values;
}

}  // namespace

namespace {

// GLAH01: the received and transmitted waveforms, and their truth.
template <typename Shot>
void write_glah01(Hdf5Writer& f, const std::string& d, const std::vector<Shot>& shots,
                  std::size_t bins, const std::vector<float>& tx) {
  const std::uint64_t n = shots.size();
  write_dataset(f, d + "Waveform/RecWaveform/r_rng_wf",
                rows(shots, bins, [](const Shot& s) -> const std::vector<float>& { return s.rx; }),
                {"counts", "Received waveform, in digitiser counts (bin 0 first in time)"},
                {n, bins});
  std::vector<float> all_tx;
  for (std::uint64_t i = 0; i < n; ++i) all_tx.insert(all_tx.end(), tx.begin(), tx.end());
  write_dataset(f, d + "Waveform/TransmitWaveform/r_tx_wf", all_tx,
                {"counts", "Transmitted waveform, in digitiser counts"}, {n, tx.size()});
  described_group(f, d + "glaswave_truth",
                  "The simulation's truth, not a GLAS product field: the parts of r_rng_wf last "
                  "scattered by vegetation and by the ground");
  write_dataset(
      f, d + "glaswave_truth/r_rng_wf_canopy",
      rows(shots, bins, [](const Shot& s) -> const std::vector<float>& { return s.rx_canopy; }),
      {"counts", "The part of r_rng_wf last scattered by vegetation"}, {n, bins});
  write_dataset(
      f, d + "glaswave_truth/r_rng_wf_ground",
      rows(shots, bins, [](const Shot& s) -> const std::vector<float>& { return s.rx_ground; }),
      {"counts", "The part of r_rng_wf last scattered by the ground"}, {n, bins});
}

// GLAH14: where the footprint is, its elevations, reflectivity and peak count.
template <typename Shot>
void write_glah14_surfaces(Hdf5Writer& f, const std::string& d, const std::vector<Shot>& shots,
                           const char* heights) {
  const Hdf5Attributes deg_n{"degrees_north", "Latitude of the footprint centre", kGlasFill};
  write_dataset(f, d + "Geolocation/d_lat",
                of<double>(shots, [](const Shot& s) { return or_fill(s.lat); }), deg_n);
  write_dataset(f, d + "Geolocation/d_lon",
                of<double>(shots, [](const Shot& s) { return or_fill(s.lon); }),
                {"degrees_east", "Longitude of the footprint centre, 0 to 360 east", kGlasFill});
  write_dataset(
      f, d + "Elevation_Surfaces/d_elev",
      of<double>(shots, [](const Shot& s) { return or_fill(s.elev); }),
      {heights, "Land surface elevation: the waveform's centroid between signal begin and end",
       kGlasFill});
  write_dataset(f, d + "Geophysical/d_DEM_elv",
                of<double>(shots, [](const Shot& s) { return or_fill(s.dem); }),
                {heights, "The simulation's terrain under the footprint centre", kGlasFill});
  write_dataset(f, d + "Geophysical/d_deltaEllip",
                of<double>(shots, [](const Shot& s) { return or_fill(s.delta_ellip); }),
                {"meters", "WGS84 height less TOPEX/Poseidon height of the footprint", kGlasFill});
  write_dataset(
      f, d + "Reflectivity/d_reflctUC",
      of<double>(shots, [](const Shot& s) { return or_fill(s.reflectance_uc); }),
      {"1", "Reflectivity not corrected for the atmosphere: pi E_rec R^2 / (E_t A_t)", kGlasFill});
  write_dataset(f, d + "Waveform/i_numPk",
                of<std::int32_t>(shots, [](const Shot& s) { return s.peaks; }),
                {"counter", "Number of Gaussian peaks fitted"});
}

// GLAH14: the Gaussians (six a shot, the first the lowest) and the signal's offsets.
template <typename Shot>
void write_glah14_offsets(Hdf5Writer& f, const std::string& d, const std::vector<Shot>& shots) {
  const std::uint64_t n = shots.size();
  auto six = [&](auto member) {
    std::vector<double> values;
    for (const Shot& s : shots)
      for (int i = 0; i < 6; ++i) values.push_back(or_fill((s.*member)[i]));
    return values;
  };
  write_dataset(
      f, d + "Waveform/d_Gamp", six(&Shot::amp),
      {"counts", "Amplitude of each Gaussian, the first the last (lowest) peak", kGlasFill},
      {n, 6});
  write_dataset(f, d + "Waveform/d_Garea", six(&Shot::area),
                {"counts ns", "Area of each Gaussian", kGlasFill}, {n, 6});
  write_dataset(f, d + "Waveform/d_Gsigma", six(&Shot::sigma),
                {"ns", "Standard deviation of each Gaussian", kGlasFill}, {n, 6});
  write_dataset(
      f, d + "Elevation_Offsets/d_SigBegOff",
      of<double>(shots, [](const Shot& s) { return or_fill(s.begin_off); }),
      {"meters", "Signal begin range offset: its elevation is d_elev less it", kGlasFill});
  write_dataset(f, d + "Elevation_Offsets/d_SigEndOff",
                of<double>(shots, [](const Shot& s) { return or_fill(s.end_off); }),
                {"meters", "Signal end range offset: its elevation is d_elev less it", kGlasFill});
  write_dataset(
      f, d + "Elevation_Offsets/d_gpCntRngOff", six(&Shot::center_off),
      {"meters", "Range offset of each Gaussian's centre: its elevation is d_elev less it",
       kGlasFill},
      {n, 6});
}

// GLAH14: the footprint's truth.
template <typename Shot>
void write_glah14_truth(Hdf5Writer& f, const std::string& d, const std::vector<Shot>& shots) {
  described_group(f, d + "glaswave_truth",
                  "The simulation's truth, not a GLAS product field: the footprint's cover, PAI, "
                  "canopy height and gap probability, beam-weighted");
  write_dataset(f, d + "glaswave_truth/cover",
                of<double>(shots, [](const Shot& s) { return or_fill(s.cover); }),
                {"1", "Crown cover over the footprint, beam-weighted", kGlasFill});
  write_dataset(f, d + "glaswave_truth/pai",
                of<double>(shots, [](const Shot& s) { return or_fill(s.pai); }),
                {"1", "Plant area index over the footprint, beam-weighted", kGlasFill});
  write_dataset(f, d + "glaswave_truth/canopy_height",
                of<double>(shots, [](const Shot& s) { return or_fill(s.height); }),
                {"meters", "Canopy height over the footprint, beam-weighted", kGlasFill});
  write_dataset(f, d + "glaswave_truth/pgap",
                of<double>(shots, [](const Shot& s) { return or_fill(s.pgap); }),
                {"1", "Vertical gap probability over the footprint, beam-weighted", kGlasFill});
}

// GLAH14's fields the GLAS readers open besides (carbonplan/trace's extract_GLAH14_data,
// SpaceLiDAR.jl's GLAH14 points(); docs/granules.md): elevation corrections and flags, the
// reference range, the waveform's skewness, peaks and the receiver's gain.
template <typename Shot>
void write_glah14_reader_fields(Hdf5Writer& f, const std::string& d, const std::vector<Shot>& shots,
                                double gain,
                                const std::optional<std::vector<CloudLayer>>& cloud_layers) {
  auto valid = [](const Shot& s) { return std::isfinite(s.elev); };
  write_dataset(
      f, d + "Elevation_Corrections/d_satElevCorr",
      of<double>(shots, [&](const Shot& s) { return valid(s) && !s.saturated ? 0.0 : kGlasFill; }),
      {"meters",
       "Saturation elevation correction, to be added to d_elev: 0 where the waveform "
       "did not reach the digitiser's full scale; fill where it did (glaswave computes "
       "no saturation correction) or where there is no elevation",
       kGlasFill});
  write_dataset(f, d + "Quality/elev_use_flg",
                of<std::int8_t>(shots, [&](const Shot& s) { return valid(s) ? 0 : 1; }),
                {"1", "Elevation use flag: 0 valid, 1 not valid (no elevation)"});
  write_dataset(f, d + "Quality/sat_corr_flg",
                of<std::int8_t>(shots, [](const Shot& s) { return s.saturated ? 3 : 0; }),
                {"1",
                 "Saturation correction flag: 0 not saturated, 3 not computed (the waveform "
                 "reached the digitiser's full scale; glaswave computes no correction)"});
  write_dataset(f, d + "Quality/sigma_att_flg", std::vector<std::int8_t>(shots.size(), 0),
                {"1", "Attitude quality: 0 good (the simulation's pointing is exact)"});
  // The atmosphere's layers are horizontally uniform: a reported one lies in every shot's column.
  const bool clouds = cloud_layers && !cloud_layers->empty();
  write_dataset(f, d + "Elevation_Flags/elv_cloud_flg",
                std::vector<std::int8_t>(shots.size(), clouds ? 1 : 0),
                {"1", cloud_layers ? "Cloud contamination: 1 where a cloud or aerosol layer the "
                                     "layer finder reports at 1064 nm lies in the column, else 0"
                                   // Runs without an atmosphere keep main's bits.
                                   : "Cloud contamination: 0, no cloud detected (glaswave does "
                                     "not flag clouds from the atmosphere)"});
  const std::int32_t gain_value =
      std::isfinite(gain) && gain < 2e9 ? static_cast<std::int32_t>(std::lround(gain)) : kInt32Fill;
  write_dataset(
      f, d + "Waveform/i_gval_rcv", std::vector<std::int32_t>(shots.size(), gain_value),
      {"counts", "Gain of the received pulse: detector.gain rounded (fill without a detector)",
       static_cast<double>(kInt32Fill)});
  write_dataset(
      f, d + "Elevation_Surfaces/d_refRng",
      of<double>(shots, [](const Shot& s) { return or_fill(s.ref_range); }),
      {"meters", "Range from the spacecraft to the waveform's last (farthest) gate", kGlasFill});
  write_dataset(f, d + "Elevation_Offsets/d_ldRngOff",
                of<double>(shots, [](const Shot& s) { return or_fill(s.land_off); }),
                {"meters",
                 "Land range offset, to be added to d_refRng: the range to the waveform's "
                 "centroid (d_elev) less d_refRng",
                 kGlasFill});
  write_dataset(f, d + "Geophysical/d_gdHt", std::vector<double>(shots.size(), kGlasFill),
                {"meters", "Geoid height: fill, glaswave carries no geoid model", kGlasFill});
  write_dataset(f, d + "Waveform/d_skew1",
                of<double>(shots, [](const Shot& s) { return or_fill(s.skew); }),
                {"1",
                 "Skewness in time of the received waveform less its noise mean between signal "
                 "begin and end",
                 kGlasFill});
  write_dataset(f, d + "Waveform/i_nPeaks1",
                of<std::int32_t>(shots, [](const Shot& s) { return s.peaks1; }),
                {"counts",
                 "Peaks of the received waveform smoothed by a Gaussian of the pulse's width, "
                 "between signal begin and end, above noise mean + 4 sd and 1 % of its peak"});
}

// GLAH01's fields the GLAS readers open besides (carbonplan/trace's extract_GLAH01_data): the
// noise, the sample-location index and times, and ANCILLARY_DATA's sample-location tables
// (times in ns: a received sample's from the last gate's, a transmitted one's from the peak).
template <typename Shot>
void write_glah01_reader_fields(Hdf5Writer& f, const std::string& d, const std::vector<Shot>& shots,
                                const RunInfo& info) {
  write_dataset(f, d + "Waveform/Characteristics/d_4nsBgMean",
                of<double>(shots, [](const Shot& s) { return or_fill(s.noise_mean); }),
                {"counts",
                 "Background noise mean of r_rng_wf over the bins before the signal (the first "
                 "eighth without one)",
                 kGlasFill});
  write_dataset(
      f, d + "Waveform/Characteristics/d_4nsBgSDEV",
      of<double>(shots, [](const Shot& s) { return or_fill(s.noise_sd); }),
      {"counts", "Background noise standard deviation of r_rng_wf, as d_4nsBgMean", kGlasFill});
  write_dataset(f, d + "Waveform/RecWaveform/i_rec_wf_location_index",
                std::vector<std::int8_t>(shots.size(), 1),
                {"1",
                 "1-based row of ANCILLARY_DATA's rec_wf_sample_location_table giving the times "
                 "of r_rng_wf's samples: 1 (every shot's samples are evenly spaced)",
                 static_cast<double>(kInt8Fill)});
  write_dataset(f, d + "Waveform/RecWaveform/i_RespEndTime",
                of<std::int32_t>(shots, [](const Shot& s) { return s.resp_end; }),
                {"counts",
                 "Time of r_rng_wf's last sample in 1 ns counts from the start of r_tx_wf "
                 "(i_time_txWfPk plus the two-way time to d_refRng, rounded to the ns)",
                 static_cast<double>(kInt32Fill)});
  write_dataset(
      f, d + "Waveform/TransmitWaveform/i_time_txWfPk",
      std::vector<std::int32_t>(shots.size(), tx_peak_address(info)),
      {"counts", "Address of the transmit pulse's peak in 1 ns counts from r_tx_wf's start"});
  const std::vector<double>& t = info.bin_time_ns;
  std::vector<double> rec(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) rec[i] = t[i] - t.back();
  described_group(f, "ANCILLARY_DATA",
                  "rec_wf_sample_location_table: r_rng_wf's sample times (ns) from its last "
                  "sample, one row; tx_wf_sample_location_table: r_tx_wf's (ns) from the peak");
  f.double_array_attribute("ANCILLARY_DATA", "rec_wf_sample_location_table", rec,
                           {1, static_cast<std::uint64_t>(rec.size())});
  f.double_array_attribute("ANCILLARY_DATA", "tx_wf_sample_location_table", info.tx_time_ns,
                           {static_cast<std::uint64_t>(info.tx_time_ns.size())});
}

}  // namespace

void GlasGranuleWriter::write_file(Hdf5Writer& f) {
  const std::string d = "Data_40HZ/";
  const char* heights =
      topex_ ? "meters above the TOPEX/Poseidon ellipsoid" : "meters above the WGS84 ellipsoid";
  described_group(f, "Data_40HZ");
  f.text_attribute("Data_40HZ", "glaswave_ellipsoid", topex_ ? "topex" : "wgs84");
  write_dataset(f, d + "Time/d_UTCTime_40",
                of<double>(shots_, [](const Shot& s) { return s.time; }),
                {"seconds since 2000-01-01 12:00:00 UTC", "Transmit time of each 40 Hz shot"});
  write_dataset(f, d + "Time/i_rec_ndx",
                of<std::int32_t>(shots_, [](const Shot& s) { return s.record; }),
                {"counter", "Record index: the 1 s record of the shot"});
  write_dataset(f, d + "Time/i_shot_count",
                of<std::int16_t>(shots_, [](const Shot& s) { return s.count; }),
                {"counter", "The shot within its record, 1 to 40"});
  // The 40 Hz time dimension scale, as SpaceLiDAR.jl reads GLAH14's time.
  write_dataset(f, d + "DS_UTCTime_40", of<double>(shots_, [](const Shot& s) { return s.time; }),
                {"seconds since 2000-01-01 12:00:00 UTC", "Transmit time of each 40 Hz shot"});
  if (level_ == GlasLevel::glah01) {
    std::vector<float> tx;
    if (band_ < info().tx_waveform_W.size())
      tx = to_counts(info().tx_waveform_W[band_], info().counts_per_W);
    write_glah01(f, d, shots_, info().bin_time_ns.size(), tx);
    write_dataset(f, d + "glaswave_truth/counts_per_watt", std::vector<double>{info().counts_per_W},
                  {"counts W-1",
                   "The simulated digitiser's counts per watt of received power: r_rng_wf and its "
                   "noise are shots.nc's rx_waveform (W) times this. A real granule's scale is "
                   "unknown (glaswave retrieve --counts-per-watt)"});
    write_glah01_reader_fields(f, d, shots_, info());
    return;
  }
  write_glah14_surfaces(f, d, shots_, heights);
  write_glah14_offsets(f, d, shots_);
  write_glah14_reader_fields(f, d, shots_, info().detector_gain, cloud_layers_);
  write_glah14_truth(f, d, shots_);
}

namespace {

// output.glah01 and output.glah14 (core/part_switch.hpp); the heights' ellipsoid,
// output.glas_ellipsoid, is more than a switch: the configuration declares it.
const Registration<PartSwitch> glah01_key(
    "glah01", 40, {"output", false, "write `glah01.h5`, a GLAS GLAH01-style granule (waveforms)"});
const Registration<PartSwitch> glah14_key(
    "glah14", 41,
    {"output", false, "write `glah14.h5`, a GLAS GLAH14-style granule (elevations, Gaussians)"});

const Registration<ProductWriter> glah01_writer(
    "glah01.h5", 40, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!switched_on(c.settings.switches, "glah01")) return nullptr;
      return std::make_unique<GlasGranuleWriter>(c.out_dir / "glah01.h5", GlasLevel::glah01,
                                                 c.settings.glas_topex, c.info);
    });
const Registration<ProductWriter> glah14_writer(
    "glah14.h5", 41, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!switched_on(c.settings.switches, "glah14")) return nullptr;
      return std::make_unique<GlasGranuleWriter>(c.out_dir / "glah14.h5", GlasLevel::glah14,
                                                 c.settings.glas_topex, c.info,
                                                 c.settings.glas_cloud_layers);
    });

}  // namespace

}  // namespace glaswave
