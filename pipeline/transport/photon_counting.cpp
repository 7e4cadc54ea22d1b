// Photon counting: expected counts, the sun's background, keyed Poisson draws and dead time.
#include "pipeline/transport/photon_counting.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <tuple>

#include "core/random.hpp"
#include "core/samplers.hpp"

namespace glaswave {
namespace {

constexpr double planck_J_s = 6.62607015e-34;
constexpr double light_m_s = 299792458.0;
constexpr std::size_t bin_bits = 24;
constexpr std::uint64_t background_key = (std::uint64_t{1} << bin_bits) - 1;
// A bin expecting fewer signal photons than this is not drawn (each stream costs about as much
// as the rest of a bin's work): over a whole window of 2^24 bins that loses 2e-5 photons a shot
// at most, against the Gaussian pulse's tails that would otherwise be drawn bin by bin.
constexpr double negligible_mean = 1e-12;

RandomStream photon_stream(const PhotonDraw& draw, std::uint64_t bin) {
  return RandomStream(draw.seed, static_cast<std::uint64_t>(draw.shot),
                      (std::uint64_t{draw.beam} << bin_bits) | bin, RandomPurpose::photons);
}

// The signal's streams, bin after bin: bin b's is photon_stream(draw, b), stepped from the last
// bin's rather than keyed afresh (the keying was most of a bin's cost over a forest, where
// scattered light reaches most bins).
class BinStreams {
 public:
  explicit BinStreams(const PhotonDraw& draw)
      : key_(std::uint64_t{draw.beam} << bin_bits),
        streams_(draw.seed, static_cast<std::uint64_t>(draw.shot), RandomPurpose::photons) {}
  RandomStream at(std::size_t bin) { return streams_.at(key_ | bin); }

 private:
  std::uint64_t key_;
  RandomStreams streams_;
};

std::uint8_t draw_channel(RandomStream& random, int channels) {
  return static_cast<std::uint8_t>(
      std::min(channels - 1, static_cast<int>(random.uniform() * channels)));
}

// The range window's length.
double window_ns(const PhotonDraw& draw) { return static_cast<double>(draw.bins) * draw.bin_ns; }

// The sources' bins: their common length, checked with the draw's other inputs.
std::size_t checked_bins(const PhotonDraw& draw, std::span<const PhotonSource> sources) {
  const std::size_t bins = sources.empty() ? 0 : sources.front().mean_per_bin.size();
  const bool listed = !draw.signal_bins.empty();
  const bool keys = listed ? draw.signal_bins.size() == bins &&
                                 std::is_sorted(draw.signal_bins.begin(), draw.signal_bins.end()) &&
                                 draw.signal_bins.back() < background_key
                           : bins < background_key;
  if (draw.beam >= 256 || draw.bins >= background_key || !keys || draw.channels < 1 ||
      draw.channels > 255 || !(draw.bin_ns > 0.0) || !(draw.background_rate_Hz >= 0.0) ||
      !(draw.pulse_sigma_ns >= 0.0))
    throw std::invalid_argument(
        "draw_photons: beam < 256, bins < 2^24 - 1 (the signal's listed in increasing order, one "
        "a mean), 1..255 channels, bin_ns > 0, a background rate >= 0 and a pulse sigma >= 0");
  for (const PhotonSource& source : sources)
    if (source.mean_per_bin.size() != bins)
      throw std::invalid_argument("draw_photons: every source has one mean per bin");
  return bins;
}

// The signal photons of the sources' entry `entry` (the grid's bin signal_bins[entry], or
// `entry`), `total` being the sum of the sources' means there; those the pulse moves out of the
// window are lost.
void draw_bin(const PhotonDraw& draw, std::span<const PhotonSource> sources, std::size_t entry,
              double total, BinStreams& streams, std::vector<PhotonEvent>& events) {
  const std::size_t bin = draw.signal_bins.empty() ? entry : draw.signal_bins[entry];
  RandomStream random = streams.at(bin);
  const double count = poisson(random, total);
  const double window_length_ns = window_ns(draw);
  const double grid_bin = static_cast<double>(draw.grid_offset_bins) + static_cast<double>(bin);
  for (double k = 0.0; k < count; k += 1.0) {
    double pick = random.uniform() * total;
    std::size_t source = 0;
    while (source + 1 < sources.size() && pick >= sources[source].mean_per_bin[entry]) {
      pick -= sources[source].mean_per_bin[entry];
      ++source;
    }
    double time_ns = (grid_bin + random.uniform()) * draw.bin_ns;
    if (draw.pulse_sigma_ns > 0.0) time_ns += draw.pulse_sigma_ns * standard_normal(random);
    const std::uint8_t channel = draw_channel(random, draw.channels);
    if (time_ns >= 0.0 && time_ns < window_length_ns)
      events.push_back({time_ns, sources[source].truth_class, sources[source].order, channel});
  }
}

}  // namespace

double photon_energy_J(double wavelength_nm) {
  return planck_J_s * light_m_s / (wavelength_nm * 1e-9);
}

double photons_per_J(double efficiency, double wavelength_nm) {
  return efficiency / photon_energy_J(wavelength_nm);
}

std::vector<double> expected_photons(std::span<const double> energy_J, double wavelength_nm,
                                     double efficiency) {
  const double per_J = photons_per_J(efficiency, wavelength_nm);
  std::vector<double> photons(energy_J.size());
  std::transform(energy_J.begin(), energy_J.end(), photons.begin(),
                 [per_J](double e) { return std::max(e, 0.0) * per_J; });
  return photons;
}

double background_rate_Hz(const SolarBackground& b) {
  const double cos_sun = std::cos(b.sun_zenith_deg * std::numbers::pi / 180.0);
  if (!(cos_sun > 0.0)) return 0.0;
  const double solid_angle_sr = 2.0 * std::numbers::pi * (1.0 - std::cos(0.5 * b.ifov_rad));
  // The radiance reaching the receiver.
  const double radiance = b.sky ? b.sky->reflectance(cos_sun, b.reflectance) / std::numbers::pi *
                                      b.irradiance_W_m2_nm * cos_sun
                                : b.reflectance / std::numbers::pi * b.irradiance_W_m2_nm *
                                      cos_sun * std::pow(b.transmission_one_way, 1.0 / cos_sun) *
                                      b.transmission_one_way;
  const double power_W = radiance * b.telescope_area_m2 * solid_angle_sr * b.filter_bandwidth_nm;
  return power_W * b.efficiency / photon_energy_J(b.wavelength_nm);
}

std::vector<PhotonEvent> draw_photons(const PhotonDraw& draw,
                                      std::span<const PhotonSource> sources) {
  const std::size_t bins = checked_bins(draw, sources);
  std::vector<PhotonEvent> events;
  BinStreams streams(draw);
  // Each bin's sum of the sources' means, added source after source in the order a bin's loop
  // would add them (the same bits), over contiguous memory.
  std::vector<double> totals(bins, 0.0);
  for (const PhotonSource& source : sources)
    for (std::size_t entry = 0; entry < bins; ++entry)
      totals[entry] += std::max(source.mean_per_bin[entry], 0.0);
  for (std::size_t entry = 0; entry < bins; ++entry)
    if (totals[entry] > negligible_mean)
      draw_bin(draw, sources, entry, totals[entry], streams, events);
  const double window_length_ns = window_ns(draw);
  if (draw.background_rate_Hz > 0.0) {
    RandomStream random = photon_stream(draw, background_key);
    const double count = poisson(random, draw.background_rate_Hz * window_length_ns * 1e-9);
    for (double k = 0.0; k < count; k += 1.0) {
      const double time_ns = random.uniform() * window_length_ns;
      events.push_back({time_ns, PhotonTruth::background, 0, draw_channel(random, draw.channels)});
    }
  }
  // A total order, so that the sequence (and the dead time after it) never depends on the sort.
  std::sort(events.begin(), events.end(), [](const PhotonEvent& a, const PhotonEvent& b) {
    return std::tie(a.time_ns, a.truth_class, a.order, a.channel) <
           std::tie(b.time_ns, b.truth_class, b.order, b.channel);
  });
  return events;
}

std::vector<PhotonEvent> apply_dead_time(std::span<const PhotonEvent> events, double dead_time_ns) {
  std::vector<double> live_from(256, -std::numeric_limits<double>::infinity());
  std::vector<PhotonEvent> recorded;
  recorded.reserve(events.size());
  for (const PhotonEvent& event : events) {
    double& live = live_from[event.channel];
    if (event.time_ns < live) continue;
    recorded.push_back(event);
    live = event.time_ns + dead_time_ns;
  }
  return recorded;
}

}  // namespace glaswave
