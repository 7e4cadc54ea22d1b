// GLAS GLAH01- and GLAH14-style granules: NSIDC's paths (GLAH01/GLAH14 release 34 HDF5) and
// GLA14's units; docs/granules.md.
#include "pipeline/products/glas_granule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

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
                                     bool topex, const RunInfo& info)
    : Hdf5GranuleWriter(final_path, info),
      level_(level),
      topex_(topex),
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
  if (level_ == GlasLevel::glah01) {
    if (b < r.rx_waveform_W.size()) s.rx = to_counts(r.rx_waveform_W[b], per_W);
    if (b < r.rx_waveform_canopy_W.size())
      s.rx_canopy = to_counts(r.rx_waveform_canopy_W[b], per_W);
    if (b < r.rx_waveform_ground_W.size())
      s.rx_ground = to_counts(r.rx_waveform_ground_W[b], per_W);
  }
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
  described_group(
      f, d + "glaswave_truth",
      "The simulation's truth, not a GLAS product field: the footprint's cover, PAI and "
      "canopy height, beam-weighted");
  write_dataset(f, d + "glaswave_truth/cover",
                of<double>(shots, [](const Shot& s) { return or_fill(s.cover); }),
                {"1", "Crown cover over the footprint, beam-weighted", kGlasFill});
  write_dataset(f, d + "glaswave_truth/pai",
                of<double>(shots, [](const Shot& s) { return or_fill(s.pai); }),
                {"1", "Plant area index over the footprint, beam-weighted", kGlasFill});
  write_dataset(f, d + "glaswave_truth/canopy_height",
                of<double>(shots, [](const Shot& s) { return or_fill(s.height); }),
                {"meters", "Canopy height over the footprint, beam-weighted", kGlasFill});
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
  if (level_ == GlasLevel::glah01) {
    std::vector<float> tx;
    if (band_ < info().tx_waveform_W.size())
      tx = to_counts(info().tx_waveform_W[band_], info().counts_per_W);
    write_glah01(f, d, shots_, info().bin_time_ns.size(), tx);
    return;
  }
  write_glah14_surfaces(f, d, shots_, heights);
  write_glah14_offsets(f, d, shots_);
  write_glah14_truth(f, d, shots_);
}

namespace {

const Registration<ProductWriter> glah01_writer(
    "glah01.h5", 40, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!c.settings.glah01) return nullptr;
      return std::make_unique<GlasGranuleWriter>(c.out_dir / "glah01.h5", GlasLevel::glah01,
                                                 c.settings.glas_topex, c.info);
    });
const Registration<ProductWriter> glah14_writer(
    "glah14.h5", 41, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!c.settings.glah14) return nullptr;
      return std::make_unique<GlasGranuleWriter>(c.out_dir / "glah14.h5", GlasLevel::glah14,
                                                 c.settings.glas_topex, c.info);
    });

}  // namespace

}  // namespace glaswave
