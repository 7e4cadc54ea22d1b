// The physics of a photon-counting receiver (ICESat-2's ATLAS): the simulated received energy
// becomes expected photon counts, the sun adds a background rate, photon events are drawn as
// Poisson counts keyed by (seed, shot, beam, bin) and spread by the pulse, and each detector
// channel's dead time removes events as a non-paralysable counter does. Pure functions: the
// receiver of pipeline/shot/ feeds them a shot's binned returns and geolocates the events they give
// back.
#pragma once

#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "footprints/lidar_settings.hpp"
#include "pipeline/transport/sky_light.hpp"

namespace glaswave {

// Energy of one photon, h c / lambda (CODATA 2018 exact constants), J.
double photon_energy_J(double wavelength_nm);
// The photons a detector of this efficiency counts per joule of light at `wavelength_nm`.
double photons_per_J(double efficiency, double wavelength_nm);

// The photons detected on average from the energy received in each bin: energy_J[bin] /
// (h c / lambda) * efficiency, the efficiency being the receiver's optical throughput times the
// detector's photon detection efficiency.
std::vector<double> expected_photons(std::span<const double> energy_J, double wavelength_nm,
                                     double efficiency);

// Top-of-atmosphere solar spectral irradiance at 532 nm at the mean Sun-Earth distance,
// W m^-2 nm^-1: the ASTM E-490 (2000) air mass zero spectrum, 1.87 within the 1 nm around 532 nm.
inline constexpr double solar_irradiance_532_W_m2_nm = 1.87;

// What sunlight in the field of view depends on. The scene is Lambertian of reflectance
// `reflectance` under the sun; the atmosphere is a plane-parallel layer of vertical one-way
// transmission `transmission_one_way`, crossed by the sun's light along its slant path and by the
// reflected light toward a receiver near nadir.
struct SolarBackground {
  double irradiance_W_m2_nm = solar_irradiance_532_W_m2_nm;
  double sun_zenith_deg = 0.0;
  double reflectance = 0.0;
  double transmission_one_way = 1.0;
  double filter_bandwidth_nm = 0.0;  // the receiver filter's equivalent (rectangular) width
  double ifov_rad = 0.0;             // full angle of the top-hat field of view
  double telescope_area_m2 = 0.0;
  double efficiency = 1.0;  // as for expected_photons
  double wavelength_nm = 532.0;
  // The atmosphere's layers (issue 40), when there are: the light reaching the receiver is then
  // R(mu0, rho) E mu0 / pi, the layers' own light and their diffuse light included, in place of
  // the transmission's.
  const SkyLight* sky = nullptr;
};

// Detected background photons per second:
//   L = (rho / pi) F cos(theta_s) T^(1/cos theta_s)           surface radiance, W m^-2 sr^-1 nm^-1
//   rate = L T A_T Omega dlambda efficiency / (h c / lambda),  Omega = 2 pi (1 - cos(ifov / 2))
// (the radiance does not change with range, so neither does the rate); with `sky`,
//   L = R(mu0, rho) F mu0 / pi,  rate = L A_T Omega dlambda efficiency / (h c / lambda).
// 0 with the sun at or below the horizon.
double background_rate_Hz(const SolarBackground& background);

// Where the background light comes from: the sun at each shot's time and place over the scene's
// reflectance, nowhere, or a fixed rate.
enum class BackgroundSource : std::uint8_t { sun, none, rate };

// A photon-counting receiver's own settings: its detector (the sensor's: ATLAS's strong beam by
// default, docs/icesat2.md) and its beam's.
struct PhotonCountingSettings : PhotonDetectorSettings {
  int channels = 16;          // 16 a strong beam, 4 a weak one
  double energy_ratio = 1.0;  // the beam's pulse energy over the band's (45/175 weak)
  std::uint32_t beam = 0;     // the beam's key in the draws
  BackgroundSource background = BackgroundSource::sun;
  double background_rate_Hz = 0.0;  // BackgroundSource::rate
  bool keep_orders = false;  // the run writes per-order waveforms (the receiver always has them)
};

// Truth classes of photon events, the coding of ATL08's classed_pc_flag.
enum class PhotonTruth : std::uint8_t { background = 0, ground = 1, canopy = 2, top_of_canopy = 3 };

// One source of signal photons: its expected photons in each of the signal's bins (all sources
// of a shot share them: PhotonDraw's signal_bins) and what its photons are in truth.
struct PhotonSource {
  std::span<const double> mean_per_bin;
  PhotonTruth truth_class = PhotonTruth::ground;
  std::uint8_t order = 1;  // the scattering order, 0 for background
};

// One detected photon: its time after the start of the range window, what it is in truth, and
// the detector channel that counted it.
struct PhotonEvent {
  double time_ns = 0.0;
  PhotonTruth truth_class = PhotonTruth::background;
  std::uint8_t order = 0;
  std::uint8_t channel = 0;

  bool operator==(const PhotonEvent&) const = default;
};

// Which shot and beam the draws belong to, the range window, and the signal's bins.
struct PhotonDraw {
  std::uint64_t seed = 0;
  std::int64_t shot = 0;
  std::uint32_t beam = 0;  // < 256
  double bin_ns = 0.0;
  std::size_t bins = 0;  // the window is bins * bin_ns long
  double background_rate_Hz = 0.0;
  int channels = 1;  // detector channels the beam's photons fall on, uniformly (1..255)
  // The signal's bins are a grid of bin_ns beginning `grid_offset_bins` bins after the window's
  // start (a transport tally's begins its pulse margin before it: negative), each keyed by its
  // index in the grid (< 2^24 - 1). The sources' means are given for the grid's bins
  // `signal_bins` (increasing: a shot's return scores a few dozen of the grid's thousands of
  // bins, and the caller passes those), or for its bins from 0 on when there are none.
  std::span<const std::uint32_t> signal_bins{};
  int grid_offset_bins = 0;
  // The pulse that spreads each signal photon's time: a Gaussian of this standard deviation
  // (the sources' means being the energies scored before the pulse), photons it moves out of
  // the window being lost. 0: the means are the pulse-shaped ones already.
  double pulse_sigma_ns = 0.0;
};

// The photon events of one shot and beam, in time order, before dead time:
// - signal: in each bin expecting more than 1e-12 photons (fewer than 2e-5 a shot are left out
//   over the longest window), Poisson(sum of the sources' means) photons from the stream
//   (seed, shot, beam, bin), each given a source with probability proportional to its mean (so
//   each source's counts are Poisson of its own mean), a time uniform within the bin, then the
//   pulse's spread (a Poisson process whose points are each moved by an independent draw is the
//   Poisson process of the intensity convolved with the draw's density), and a channel;
// - background: a Poisson process of `background_rate_Hz` over the whole window, from the one
//   stream (seed, shot, beam, 2^24 - 1): Poisson(rate * window) events at uniform times.
// A shot's events therefore depend only on the seed, its shot number and its beam.
// Throws std::invalid_argument for sources of unequal lengths or out-of-range keys.
std::vector<PhotonEvent> draw_photons(const PhotonDraw& draw,
                                      std::span<const PhotonSource> sources);

// The events a non-paralysable detector records: on each channel an event is counted only when
// at least `dead_time_ns` has passed since the last event counted on that channel; the others
// are lost (and do not extend the dead time). At a true rate r per channel the recorded rate is
// r / (1 + r tau). `events` must be in time order; the recorded ones keep it.
std::vector<PhotonEvent> apply_dead_time(std::span<const PhotonEvent> events, double dead_time_ns);

}  // namespace glaswave
