// ATL03 granules beside their ATL08 as retrieve's input, through GranuleFile: the ATL03 data
// dictionary's paths, as the real files give them and as glaswave writes them.
#include "pipeline/retrieval/atl03_reader.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>

#include "core/netcdf_lock.hpp"
#include "pipeline/retrieval/atl08_reader.hpp"
#include "pipeline/retrieval/granule_file.hpp"

namespace glaswave {
namespace {

constexpr const char* kAtl03Kind = "an ICESat-2 ATL03 granule";

// One beam's photons and 20 m segments as ATL03 gives them.
struct Atl03Beam {
  std::vector<double> h_m, along_m, photon_time_s;                   // per photon
  std::vector<std::int64_t> segment_id, first_photon, photon_count;  // per segment, first 0-based
  std::vector<double> segment_x_m, segment_time_s;
  std::vector<double> background_Hz, background_time_s;
  double photons_per_J = std::numeric_limits<double>::quiet_NaN();
};

Atl03Beam read_beam(const GranuleFile& granule, const std::string& track) {
  Atl03Beam b;
  const std::string heights = track + "/heights/", geo = track + "/geolocation/",
                    background = track + "/bckgrd_atlas/";
  b.h_m = granule.read<double>(heights + "h_ph", std::nullopt);
  const std::size_t n = b.h_m.size();
  b.along_m = granule.read<double>(heights + "dist_ph_along", n);
  b.photon_time_s = granule.read<double>(heights + "delta_time", n);
  b.segment_id = granule.read<std::int64_t>(geo + "segment_id", std::nullopt);
  const std::size_t m = b.segment_id.size();
  b.first_photon = granule.read<std::int64_t>(geo + "ph_index_beg", m);
  b.photon_count = granule.read<std::int64_t>(geo + "segment_ph_cnt", m);
  b.segment_x_m = granule.read<double>(geo + "segment_dist_x", m);
  b.segment_time_s = granule.read<double>(geo + "delta_time", m);
  b.background_Hz = granule.read<double>(background + "bckgrd_rate", std::nullopt);
  b.background_time_s = granule.read<double>(background + "delta_time", b.background_Hz.size());
  for (std::size_t j = 0; j < m; ++j) {
    if (j > 0 && b.segment_id[j] <= b.segment_id[j - 1])
      granule.refuse(geo + "segment_id", "not in increasing order");
    const std::int64_t count = b.photon_count[j], first = b.first_photon[j];
    if (count < 0) granule.refuse(geo + "segment_ph_cnt", "a count below 0");
    if (count > 0 && (first < 1 || first - 1 > static_cast<std::int64_t>(n) - count))
      granule.refuse(geo + "ph_index_beg", "segment " + std::to_string(b.segment_id[j]) +
                                               "'s photons lie beyond the " + std::to_string(n) +
                                               " of heights/h_ph");
    b.first_photon[j] = first - 1;
  }
  for (std::size_t j = 1; j < b.background_time_s.size(); ++j)
    if (!(b.background_time_s[j] >= b.background_time_s[j - 1]))
      granule.refuse(background + "delta_time", "not in increasing order");
  const std::string truth = track + "/glaswave_truth/photons_per_joule";
  if (granule.reader().has(truth)) b.photons_per_J = granule.read<double>(truth, 1).front();
  return b;
}

// The mean background rate over [t0, t1), or the nearest estimate's where none lies in it.
double background_rate_Hz(const Atl03Beam& b, double t0_s, double t1_s) {
  const std::vector<double>& t = b.background_time_s;
  if (t.empty()) return 0.0;
  const auto from = std::lower_bound(t.begin(), t.end(), t0_s);
  const auto to = std::lower_bound(from, t.end(), t1_s);
  if (from != to) {
    double sum = 0.0;
    for (auto i = from; i != to; ++i) sum += b.background_Hz[i - t.begin()];
    return sum / static_cast<double>(to - from);
  }
  const double mid = 0.5 * (t0_s + t1_s);
  std::size_t nearest = static_cast<std::size_t>(from - t.begin());
  if (nearest == t.size() || (nearest > 0 && mid - t[nearest - 1] < t[nearest] - mid)) --nearest;
  return b.background_Hz[nearest];
}

// The photons of segments [beg, end] of one beam, or none where ATL03 holds none of them.
std::optional<PhotonSegment> segment_photons(const Atl03Beam& b, std::int64_t beg, std::int64_t end,
                                             double slope) {
  const auto first = std::lower_bound(b.segment_id.begin(), b.segment_id.end(), beg);
  const auto last = std::upper_bound(first, b.segment_id.end(), end);
  if (first == last) return std::nullopt;
  const std::size_t i0 = static_cast<std::size_t>(first - b.segment_id.begin()),
                    i1 = static_cast<std::size_t>(last - b.segment_id.begin());  // [i0, i1)
  std::vector<double> x, h;
  double latest_s = b.segment_time_s[i1 - 1];
  for (std::size_t j = i0; j < i1; ++j)
    for (std::int64_t p = b.first_photon[j]; p < b.first_photon[j] + b.photon_count[j]; ++p) {
      if (!std::isfinite(b.h_m[p]) || std::abs(b.h_m[p]) > 1e5) continue;  // ATL03's fill
      x.push_back(b.segment_x_m[j] + b.along_m[p]);
      h.push_back(b.h_m[p]);
      if (std::isfinite(b.photon_time_s[p])) latest_s = std::max(latest_s, b.photon_time_s[p]);
    }
  // The pulses from the segment's first to the next segment's first, or to its last photon's.
  const double t0_s = b.segment_time_s[i0];
  const double t1_s =
      i1 < b.segment_time_s.size() ? b.segment_time_s[i1] : latest_s + 1.0 / kAtlasPulseRate_Hz;
  PhotonSegment s;
  s.pulses = std::max(1.0, std::round(std::abs(t1_s - t0_s) * kAtlasPulseRate_Hz));
  s.background_rate_Hz = background_rate_Hz(b, std::min(t0_s, t1_s), std::max(t0_s, t1_s));
  s.photons_per_J = b.photons_per_J;
  if (!x.empty()) {
    const auto [lo, hi] = std::minmax_element(x.begin(), x.end());
    const double middle_m = 0.5 * (*lo + *hi);
    for (std::size_t i = 0; i < h.size(); ++i) h[i] -= slope * (x[i] - middle_m);
  }
  s.heights_m = std::move(h);
  return s;
}

}  // namespace

bool is_atl03(const std::filesystem::path& file) {
  std::lock_guard lock(netcdf_library_mutex());
  const Hdf5Reader reader(file);
  for (const char* track : kAtlasTracks)
    if (reader.has(std::string(track) + "/heights/h_ph")) return true;
  return false;
}

void attach_atl03(const std::filesystem::path& file, MeasuredShots& segments) {
  std::lock_guard lock(netcdf_library_mutex());
  const GranuleFile granule(file, kAtl03Kind);
  for (std::size_t t = 0; t < kAtlasTracks.size(); ++t) {
    const std::string track = kAtlasTracks[t];
    if (!granule.reader().has(track + "/heights/h_ph")) continue;
    const Atl03Beam beam = read_beam(granule, track);
    for (MeasuredShot& s : segments.shots)
      if (s.segment && s.beam == static_cast<int>(t) + 1)
        s.photons = segment_photons(beam, s.shot_number, s.segment->segment_id_end,
                                    s.segment->terrain_slope);
  }
  segments.atl03 = true;
}

}  // namespace glaswave
