// GEDI L1B- and L2A-style granules: the dictionaries' paths, dtypes and attributes
// (GEDI01_B and GEDI02_A data dictionaries, LP DAAC; docs/granules.md).
#include "pipeline/products/gedi_granule.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>

#include "core/registry.hpp"

namespace glaswave {
namespace {

constexpr double kGediFill = -9999.0;

// The L1B's sample-indexed truth, glaswave_truth/BEAMxxxx/ (docs/granules.md).
constexpr const char* kWaveformTruthGroup = "glaswave_truth";

double or_fill(double value) { return std::isfinite(value) ? value : kGediFill; }

std::uint8_t channel_of(std::uint16_t beam) {
  for (std::uint8_t i = 0; i < 8; ++i)
    if (kGediBeams[i] == beam) return kGediChannels[i];
  return 0;
}

}  // namespace

std::string gedi_beam_group(std::uint16_t beam) {
  std::string name = "BEAM";
  for (int bit = 3; bit >= 0; --bit) name += ((beam >> bit) & 1) ? '1' : '0';
  return name;
}

double gedi_sensitivity(double noise_stddev, double pulse_sigma_bins, double energy_counts) {
  if (!(energy_counts > 0) || !std::isfinite(energy_counts)) return kGediFill;
  const double least_counts =
      kSensitivitySigmas * noise_stddev * std::sqrt(2.0 * std::numbers::pi) * pulse_sigma_bins;
  return std::clamp(1.0 - least_counts / energy_counts, 0.0, 1.0);
}

GediGranuleWriter::GediGranuleWriter(const std::filesystem::path& final_path, GediLevel level,
                                     const RunInfo& info)
    : Hdf5GranuleWriter(final_path, info), level_(level), band_(nearest_band(info, 1064.0)) {
  shots_.resize(static_cast<std::size_t>(info.shots));
  if (band_ < info.tx_waveform_W.size()) {
    const std::vector<double>& tx = info.tx_waveform_W[band_];
    tx_counts_ = to_counts(tx, info.counts_per_W);
    // The pulse's RMS width in bins, from its samples (tx_time_ns spacing is the bin's).
    double sum = 0, first = 0, second = 0;
    for (std::size_t i = 0; i < tx.size(); ++i) {
      sum += tx[i];
      first += tx[i] * static_cast<double>(i);
      second += tx[i] * static_cast<double>(i) * static_cast<double>(i);
    }
    if (sum > 0) {
      const double mean = first / sum;
      pulse_sigma_bins_ = std::sqrt(std::max(0.0, second / sum - mean * mean));
      if (info.tx_time_ns.size() > 1 && info.bin_time_ns.size() > 1)
        pulse_sigma_bins_ *=
            (info.tx_time_ns[1] - info.tx_time_ns[0]) / (info.bin_time_ns[1] - info.bin_time_ns[0]);
    }
  }
}

void GediGranuleWriter::keep(std::int64_t index, const ShotRecord& r) {
  Shot& s = shots_[static_cast<std::size_t>(index)];
  const std::size_t b = band_;
  s.beam = r.beam == kNoBeam ? kGediDefaultBeam : r.beam;
  s.degrade = r.degrade_flag;
  s.quality = r.quality_flag;
  s.shot_number = static_cast<std::uint64_t>(std::max<std::int64_t>(0, r.source_shot_number));
  s.delta_time = r.time_s - kGediEpochS;
  s.dem = r.elev_m;
  s.elev_bin0 = r.elev_bin0_m;
  s.elev_lastbin = r.elev_lastbin_m;
  s.bin0 = beam_point(r, r.elev_bin0_m);
  s.lastbin = beam_point(r, r.elev_lastbin_m);
  s.solar_elevation = r.solar_elevation_deg;
  s.solar_azimuth = r.solar_azimuth_deg;
  auto at = [&](const std::vector<double>& v) {
    return b < v.size() ? v[b] : std::numeric_limits<double>::quiet_NaN();
  };
  s.modes = static_cast<std::uint8_t>(std::clamp(b < r.n_peaks.size() ? r.n_peaks[b] : 0, 0, 255));
  s.elev_lowest = at(r.ground_elev_est_m);
  s.elev_highest = at(r.sig_begin_m);
  s.lowest = beam_point(r, s.elev_lowest);
  s.highest = beam_point(r, s.elev_highest);
  s.elev_lowest_return = at(r.sig_end_m);
  s.lowest_return = beam_point(r, s.elev_lowest_return);
  s.cover = r.cover_true;
  s.pai = r.pai_true;
  s.height = r.canopy_height_true_m;
  s.pgap = r.pgap_true;
  s.energy_canopy_J = at(r.rx_energy_canopy_J);
  s.energy_ground_J = at(r.rx_energy_ground_J);
  const double per_W = info().counts_per_W;
  if (b < r.rx_waveform_W.size()) s.rx = to_counts(r.rx_waveform_W[b], per_W);
  if (level_ == GediLevel::l1b) {
    if (b < r.rx_waveform_canopy_W.size())
      s.rx_canopy = to_counts(r.rx_waveform_canopy_W[b], per_W);
    if (b < r.rx_waveform_ground_W.size())
      s.rx_ground = to_counts(r.rx_waveform_ground_W[b], per_W);
  }
  const WaveformNoise noise = waveform_noise(s.rx, s.elev_bin0, s.elev_lastbin, s.elev_highest);
  s.noise_mean = noise.mean;
  s.noise_stddev = noise.stddev;
  double energy = 0;
  for (float c : s.rx) energy += c - noise.mean;
  s.rx_energy = energy;
  s.sensitivity = gedi_sensitivity(noise.stddev, pulse_sigma_bins_, energy);
  if (level_ == GediLevel::l2a) {
    s.rh.assign(101, static_cast<float>(kGediFill));
    if (b < r.rh_m.size())
      for (std::size_t i = 0; i < std::min<std::size_t>(101, r.rh_m[b].size()); ++i)
        s.rh[i] = static_cast<float>(or_fill(r.rh_m[b][i]));
    s.rx.clear();
  }
}

void GediGranuleWriter::write_file(Hdf5Writer& file) {
  // Beam groups in the order of their numbers, each with its shots in record (shot) order.
  std::map<std::uint16_t, std::vector<const Shot*>> beams;
  for (const Shot& s : shots_) beams[s.beam].push_back(&s);
  if (level_ == GediLevel::l1b)
    described_group(
        file, kWaveformTruthGroup,
        "The simulation's truth, not a GEDI product field: per beam, the parts of rxwaveform last "
        "scattered by vegetation and by the ground, indexed as the beam's rxwaveform "
        "(rx_sample_start_index, rx_sample_count). Outside the beams because rGEDI's "
        "clipLevel1B takes any beam dataset of rxwaveform's length for rxwaveform itself");
  if (level_ == GediLevel::l1b)
    write_dataset(file, std::string(kWaveformTruthGroup) + "/counts_per_watt",
                  std::vector<double>{info().counts_per_W},
                  {"counts W-1",
                   "The simulated digitiser's counts per watt of received power: rxwaveform and "
                   "its noise are shots.nc's rx_waveform (W) times this. A real granule's scale "
                   "is unknown (glaswave retrieve --counts-per-watt)"});
  for (const auto& [beam, shots] : beams) {
    const std::string group = gedi_beam_group(beam);
    described_group(file, group, beam < 4 ? "Coverage beam" : "Full power beam");
    if (level_ == GediLevel::l1b)
      write_l1b_beam(file, group, shots);
    else
      write_l2a_beam(file, group, shots);
  }
}

namespace {

template <typename T, typename Shot, typename F>
std::vector<T> of(const std::vector<const Shot*>& shots, F get) {
  std::vector<T> values;
  values.reserve(shots.size());
  for (const Shot* s : shots) values.push_back(static_cast<T>(get(*s)));
  return values;
}

}  // namespace

void GediGranuleWriter::write_shot_ids(Hdf5Writer& f, const std::string& g,
                                       const std::vector<const Shot*>& shots,
                                       const char* delta_time_meaning) {
  write_dataset(f, g + "/shot_number",
                of<std::uint64_t>(shots, [](const Shot& s) { return s.shot_number; }),
                {"counter", "Unique shot ID."});
  write_dataset(f, g + "/delta_time", of<double>(shots, [](const Shot& s) { return s.delta_time; }),
                {"seconds since 2018-01-01", delta_time_meaning});
  write_dataset(f, g + "/beam", of<std::uint16_t>(shots, [](const Shot& s) { return s.beam; }),
                {"counter", "Beam number"});
  write_dataset(f, g + "/channel",
                of<std::uint8_t>(shots, [](const Shot& s) { return channel_of(s.beam); }),
                {"counter",
                 "Channel number (as real files number it: 0 0 1 1 2 3 4 5 for BEAM0000 ... "
                 "BEAM1011)"});
}

namespace {

// A beam's waveforms, concatenated; each shot's from its 1-based start index.
struct Concatenated {
  std::vector<float> rx, canopy, ground, tx;
  std::vector<std::uint64_t> rx_start, tx_start;
  std::vector<std::uint16_t> rx_count, tx_count;
};

template <typename Shot>
Concatenated concatenate(const std::vector<const Shot*>& shots,
                         const std::vector<float>& tx_counts) {
  Concatenated w;
  auto& [rx, canopy, ground, tx, rx_start, tx_start, rx_count, tx_count] = w;
  for (const Shot* s : shots) {
    rx_start.push_back(rx.size() + 1);
    rx_count.push_back(static_cast<std::uint16_t>(s->rx.size()));
    rx.insert(rx.end(), s->rx.begin(), s->rx.end());
    auto truth = [&](std::vector<float>& all, const std::vector<float>& part) {
      if (part.size() == s->rx.size())
        all.insert(all.end(), part.begin(), part.end());
      else
        all.insert(all.end(), s->rx.size(), static_cast<float>(kGediFill));
    };
    truth(canopy, s->rx_canopy);
    truth(ground, s->rx_ground);
    tx_start.push_back(tx.size() + 1);
    tx_count.push_back(static_cast<std::uint16_t>(tx_counts.size()));
    tx.insert(tx.end(), tx_counts.begin(), tx_counts.end());
  }
  return w;
}

// L1B's waveform datasets, the energy and the noise.
template <typename Shot>
void write_l1b_waveforms(Hdf5Writer& f, const std::string& g, const std::vector<const Shot*>& shots,
                         const Concatenated& w) {
  write_dataset(f, g + "/rxwaveform", w.rx,
                {"counts",
                 "The corrected receive (RX) waveforms, concatenated; a shot's are "
                 "rx_sample_count samples from rx_sample_start_index (1-based)"});
  write_dataset(f, g + "/rx_sample_start_index", w.rx_start,
                {"counter", "The index in rxwaveform of each RX waveform's first sample, from 1"});
  write_dataset(f, g + "/rx_sample_count", w.rx_count,
                {"counter", "The number of samples of each RX waveform"});
  write_dataset(f, g + "/txwaveform", w.tx,
                {"counts", "The transmitted (TX) waveforms, concatenated"});
  write_dataset(f, g + "/tx_sample_start_index", w.tx_start,
                {"counter", "The index in txwaveform of each TX waveform's first sample, from 1"});
  write_dataset(f, g + "/tx_sample_count", w.tx_count,
                {"counter", "The number of samples of each TX waveform"});
  write_dataset(
      f, g + "/rx_energy", of<float>(shots, [](const Shot& s) { return s.rx_energy; }),
      {"counts", "Integrated energy in the RX waveform after subtracting the noise mean"});
  write_dataset(f, g + "/noise_mean_corrected",
                of<float>(shots, [](const Shot& s) { return s.noise_mean; }),
                {"counts", "Noise mean (the samples before the signal begins)"});
  write_dataset(f, g + "/noise_stddev_corrected",
                of<float>(shots, [](const Shot& s) { return s.noise_stddev; }),
                {"counts", "Noise standard deviation (the samples before the signal begins)"});
}

// L1B's ancillary epoch and geolocation group.
template <typename Shot>
void write_l1b_geolocation(Hdf5Writer& f, const std::string& g,
                           const std::vector<const Shot*>& shots) {
  const std::string geo = g + "/geolocation/";
  write_dataset(f, g + "/ancillary/master_time_epoch", std::vector<double>{kGediMasterTimeEpoch},
                {"seconds", "GPS seconds of 2018-01-01T00:00:00Z, the epoch of delta_time"});
  write_dataset(f, geo + "shot_number",
                of<std::uint64_t>(shots, [](const Shot& s) { return s.shot_number; }),
                {"counter", "Unique shot ID."});
  write_dataset(f, geo + "delta_time",
                of<double>(shots, [](const Shot& s) { return s.delta_time; }),
                {"seconds since 2018-01-01", "Transmit time of the shot"});
  write_dataset(f, geo + "elevation_bin0",
                of<double>(shots, [](const Shot& s) { return s.elev_bin0; }),
                {"meters", "Elevation of the first RX sample above the WGS84 ellipsoid"});
  write_dataset(f, geo + "elevation_lastbin",
                of<double>(shots, [](const Shot& s) { return s.elev_lastbin; }),
                {"meters", "Elevation of the last RX sample above the WGS84 ellipsoid"});
  write_dataset(f, geo + "latitude_bin0",
                of<double>(shots, [](const Shot& s) { return s.bin0.lat_deg; }),
                {"degrees", "Latitude of the first RX sample"});
  write_dataset(f, geo + "longitude_bin0",
                of<double>(shots, [](const Shot& s) { return s.bin0.lon_deg; }),
                {"degrees", "Longitude of the first RX sample"});
  write_dataset(f, geo + "latitude_lastbin",
                of<double>(shots, [](const Shot& s) { return s.lastbin.lat_deg; }),
                {"degrees", "Latitude of the last RX sample"});
  write_dataset(f, geo + "longitude_lastbin",
                of<double>(shots, [](const Shot& s) { return s.lastbin.lon_deg; }),
                {"degrees", "Longitude of the last RX sample"});
  write_dataset(
      f, geo + "digital_elevation_model",
      of<float>(shots, [](const Shot& s) { return or_fill(s.dem); }),
      {"meters", "The simulation's terrain under the footprint centre, above WGS84", kGediFill});
  write_dataset(f, geo + "solar_elevation",
                of<float>(shots, [](const Shot& s) { return s.solar_elevation; }),
                {"degrees", "The sun's elevation at the footprint (geometric, ERFA)"});
  write_dataset(f, geo + "solar_azimuth",
                of<float>(shots, [](const Shot& s) { return s.solar_azimuth; }),
                {"degrees", "The sun's azimuth at the footprint, east of north (ERFA)"});
  write_dataset(f, geo + "degrade_flag",
                of<std::uint8_t>(shots, [](const Shot& s) { return s.degrade; }),
                {"counter", "The granule track's degrade_flag, 0 for a synthetic track"});
}

// The footprint's truth both levels end their glaswave_truth group with.
template <typename Shot>
void write_footprint_truth(Hdf5Writer& f, const std::string& truth,
                           const std::vector<const Shot*>& shots) {
  write_dataset(f, truth + "cover",
                of<float>(shots, [](const Shot& s) { return or_fill(s.cover); }),
                {"1", "Crown cover over the footprint, beam-weighted", kGediFill});
  write_dataset(f, truth + "pai", of<float>(shots, [](const Shot& s) { return or_fill(s.pai); }),
                {"1", "Plant area index over the footprint, beam-weighted", kGediFill});
  write_dataset(f, truth + "canopy_height",
                of<float>(shots, [](const Shot& s) { return or_fill(s.height); }),
                {"meters", "Canopy height over the footprint, beam-weighted", kGediFill});
  write_dataset(f, truth + "pgap", of<float>(shots, [](const Shot& s) { return or_fill(s.pgap); }),
                {"1", "Vertical gap probability over the footprint, beam-weighted", kGediFill});
}

}  // namespace

void GediGranuleWriter::write_l1b_beam(Hdf5Writer& f, const std::string& g,
                                       const std::vector<const Shot*>& shots) {
  write_shot_ids(f, g, shots, "Transmit time of the shot, since master_time_epoch");
  const Concatenated w = concatenate(shots, tx_counts_);
  write_l1b_waveforms(f, g, shots, w);
  write_l1b_geolocation(f, g, shots);
  const std::string truth = g + "/glaswave_truth/";
  described_group(
      f, g + "/glaswave_truth",
      "The simulation's truth, not a GEDI product field: the received energy last scattered by "
      "vegetation and by the ground, and the footprint's cover, PAI, height and gap probability "
      "(the waveform's "
      "parts are in /glaswave_truth/BEAMxxxx)");
  const std::string parts = std::string(kWaveformTruthGroup) + "/" + g + "/";
  write_dataset(
      f, parts + "rxwaveform_canopy", w.canopy,
      {"counts", "The part of rxwaveform last scattered by vegetation (same indices)", kGediFill});
  write_dataset(
      f, parts + "rxwaveform_ground", w.ground,
      {"counts", "The part of rxwaveform last scattered by the ground (same indices)", kGediFill});
  write_dataset(f, truth + "rx_energy_canopy",
                of<double>(shots, [](const Shot& s) { return or_fill(s.energy_canopy_J); }),
                {"J", "Received energy last scattered by vegetation", kGediFill});
  write_dataset(f, truth + "rx_energy_ground",
                of<double>(shots, [](const Shot& s) { return or_fill(s.energy_ground_J); }),
                {"J", "Received energy last scattered by the ground", kGediFill});
  write_footprint_truth(f, truth, shots);
}

// ancillary/l2a_alg_count and geolocation/*_a1, as rGEDI's clipLevel2A reads them (it clips
// geolocation/{lat,lon}_{highest,lowest}return_aN for N in 1..l2a_alg_count): glaswave runs one
// setting group (the signal's start and end, the lowest mode of the product's own), so the
// count is 1, not real L2A's 6, and a1 is the beam group's own.
void GediGranuleWriter::write_l2a_algorithm(Hdf5Writer& f, const std::string& g,
                                            const std::vector<const Shot*>& shots) {
  write_dataset(f, g + "/ancillary/l2a_alg_count", std::vector<std::uint8_t>{1},
                {"counter", "Number of algorithm setting groups (glaswave runs one)"});
  const std::string geo = g + "/geolocation/";
  struct Return {
    const char* name;
    LatLon Shot::*where;
    double Shot::*elev;
    const char *lat, *lon, *height;
  };
  for (const Return& r :
       {Return{"highestreturn", &Shot::highest, &Shot::elev_highest,
               "Latitude of the highest detected return (the signal's start)",
               "Longitude of the highest detected return (the signal's start)",
               "Elevation of the highest detected return above the WGS84 ellipsoid"},
        Return{"lowestreturn", &Shot::lowest_return, &Shot::elev_lowest_return,
               "Latitude of the lowest detected return (the signal's end)",
               "Longitude of the lowest detected return (the signal's end)",
               "Elevation of the lowest detected return above the WGS84 ellipsoid"}}) {
    const std::string suffix = std::string(r.name) + "_a1";
    write_dataset(f, geo + "lat_" + suffix,
                  of<double>(shots, [&](const Shot& s) { return or_fill((s.*r.where).lat_deg); }),
                  {"degrees", r.lat, kGediFill});
    write_dataset(f, geo + "lon_" + suffix,
                  of<double>(shots, [&](const Shot& s) { return or_fill((s.*r.where).lon_deg); }),
                  {"degrees", r.lon, kGediFill});
    write_dataset(f, geo + "elev_" + suffix,
                  of<float>(shots, [&](const Shot& s) { return or_fill(s.*r.elev); }),
                  {"meters", r.height, kGediFill});
  }
}

void GediGranuleWriter::write_l2a_beam(Hdf5Writer& f, const std::string& g,
                                       const std::vector<const Shot*>& shots) {
  write_shot_ids(f, g, shots, "Transmit time of the shot since 2018-01-01T00:00:00Z");
  write_dataset(f, g + "/lat_lowestmode",
                of<double>(shots, [](const Shot& s) { return or_fill(s.lowest.lat_deg); }),
                {"degrees", "Latitude of the center of the lowest mode", kGediFill});
  write_dataset(f, g + "/lon_lowestmode",
                of<double>(shots, [](const Shot& s) { return or_fill(s.lowest.lon_deg); }),
                {"degrees", "Longitude of the center of the lowest mode", kGediFill});
  write_dataset(f, g + "/elev_lowestmode",
                of<float>(shots, [](const Shot& s) { return or_fill(s.elev_lowest); }),
                {"meters", "Elevation of the center of the lowest mode above the WGS84 ellipsoid",
                 kGediFill});
  write_dataset(f, g + "/lat_highestreturn",
                of<double>(shots, [](const Shot& s) { return or_fill(s.highest.lat_deg); }),
                {"degrees", "Latitude of the highest detected return", kGediFill});
  write_dataset(f, g + "/lon_highestreturn",
                of<double>(shots, [](const Shot& s) { return or_fill(s.highest.lon_deg); }),
                {"degrees", "Longitude of the highest detected return", kGediFill});
  write_dataset(
      f, g + "/elev_highestreturn",
      of<float>(shots, [](const Shot& s) { return or_fill(s.elev_highest); }),
      {"meters", "Elevation of the highest detected return above the WGS84 ellipsoid", kGediFill});
  std::vector<float> rh;
  for (const Shot* s : shots) rh.insert(rh.end(), s->rh.begin(), s->rh.end());
  write_dataset(f, g + "/rh", rh,
                {"meters", "Relative height metrics rh0..rh100 above the lowest mode", kGediFill},
                {shots.size(), 101});
  write_dataset(f, g + "/num_detectedmodes",
                of<std::uint8_t>(shots, [](const Shot& s) { return s.modes; }),
                {"counter", "Number of detected modes in the waveform"});
  write_dataset(f, g + "/quality_flag",
                of<std::uint8_t>(shots, [](const Shot& s) { return s.quality; }),
                {"counter", "1 for a valid waveform, 0 for none"});
  write_dataset(f, g + "/degrade_flag",
                of<std::uint8_t>(shots, [](const Shot& s) { return s.degrade; }),
                {"counter", "The granule track's degrade_flag, 0 for a synthetic track"});
  write_dataset(f, g + "/sensitivity",
                of<float>(shots, [](const Shot& s) { return s.sensitivity; }),
                {"1",
                 "Largest canopy cover whose ground return stays detectable (glaswave's "
                 "definition, docs/granules.md)",
                 kGediFill});
  write_dataset(f, g + "/solar_elevation",
                of<float>(shots, [](const Shot& s) { return s.solar_elevation; }),
                {"degrees", "The sun's elevation at the footprint (geometric, ERFA)"});
  write_dataset(f, g + "/solar_azimuth",
                of<float>(shots, [](const Shot& s) { return s.solar_azimuth; }),
                {"degrees", "The sun's azimuth at the footprint, east of north (ERFA)"});
  write_dataset(
      f, g + "/digital_elevation_model",
      of<float>(shots, [](const Shot& s) { return or_fill(s.dem); }),
      {"meters", "The simulation's terrain under the footprint centre, above WGS84", kGediFill});
  write_l2a_algorithm(f, g, shots);
  const std::string truth = g + "/glaswave_truth/";
  described_group(
      f, g + "/glaswave_truth",
      "The simulation's truth, not a GEDI product field: the footprint's cover, PAI, gap "
      "probability and "
      "canopy height, beam-weighted");
  write_footprint_truth(f, truth, shots);
}

namespace {

// Each granule's key, output.gedi_l1b and output.gedi_l2a, declared here beside its writer.
const Registration<PartSwitch> gedi_l1b_key(
    "gedi_l1b", 30,
    {"output", false,
     "write `gedi_l1b.h5`, a GEDI L1B-style granule (waveforms in counts; docs/granules.md)"});
const Registration<PartSwitch> gedi_l2a_key(
    "gedi_l2a", 31,
    {"output", false,
     "write `gedi_l2a.h5`, a GEDI L2A-style granule (elevations, rh); itself a valid `granule` "
     "track"});

const Registration<ProductWriter> gedi_l1b_writer(
    "gedi_l1b.h5", 30, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!switched_on(c.settings.switches, "gedi_l1b")) return nullptr;
      return std::make_unique<GediGranuleWriter>(c.out_dir / "gedi_l1b.h5", GediLevel::l1b, c.info);
    });
const Registration<ProductWriter> gedi_l2a_writer(
    "gedi_l2a.h5", 31, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!switched_on(c.settings.switches, "gedi_l2a")) return nullptr;
      return std::make_unique<GediGranuleWriter>(c.out_dir / "gedi_l2a.h5", GediLevel::l2a, c.info);
    });

}  // namespace

}  // namespace glaswave
