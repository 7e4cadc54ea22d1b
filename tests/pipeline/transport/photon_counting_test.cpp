// Tests of the photon-counting physics against numbers computed here, independently of the code:
// signal photons over flat Lambertian ground at nadir (the transport's energies, scored before the
// pulse, turned into counts and each photon spread by the pulse, as the photon-counting receiver
// draws them) against E T A_T rho f_fov eta / (pi R^2 h nu), Poisson in their variance, their
// times spread as the pulse; photons spread out of the window lost; Gardner's slope width; the
// sun's background against the radiometric closed form; the recorded rate under dead time against
// the non-paralysable law r / (1 + r tau); the keying by (seed, shot, beam); and ATLAS's strong and
// weak beams over a surface of reflectance 0.9 against the mission's published range.
#include "pipeline/transport/photon_counting.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>
#include <tuple>
#include <vector>

#include "core/random.hpp"
#include "core/samplers.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

// h c / lambda at 532 nm from the CODATA 2018 constants: 3.7340e-19 J.
constexpr double kPhoton532J = 6.62607015e-34 * 299792458.0 / 532e-9;

// ATLAS as the atlas preset declares it (share/presets/atlas.json, docs/icesat2.md): a 1.5 ns
// FWHM pulse, a footprint 11 m across at 1/e^2 from 496 km, an 83.5 um-rad field of view, 0.41 m^2
// of unobscured telescope, 45 % optical throughput times 15 % detection efficiency.
constexpr double kRangeM = 496000.0;
constexpr double kSigmaRad = 11.0 / (4.0 * kRangeM);
constexpr double kIfovRad = 83.5e-6;
constexpr double kAreaM2 = 0.41;
constexpr double kEfficiency = 0.45 * 0.15;

LidarSettings atlas_sensor(double energy_mJ, double transmission) {
  LidarSettings s;
  s.pulse_sigma_ns = 1.5 / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  s.divergence_sigma_rad = kSigmaRad;
  s.ifov_rad = kIfovRad;
  s.telescope_area_m2 = kAreaM2;
  s.bin_ns = 0.1;
  s.bins = 150;
  s.bands = {{532.0, energy_mJ, transmission, "532"}};
  return s;
}

// A shot's expected photons as the photon-counting receiver takes them: band 0's energies as the
// transport scored them before the pulse (the tally's bins from first_bin on, the tally beginning
// its pulse margin before the window), and the draw that spreads each photon by the pulse.
struct ScoredPhotons {
  std::vector<double> photons;
  std::vector<std::uint32_t> bins;  // the tally's bins scored into
  PhotonDraw draw;                  // all but its signal_bins, which are `bins`
};

ScoredPhotons scored_photons(const Scene& scene, const ShotGeometry& geometry,
                             const SceneOptics& optics, const LidarSettings& sensor, int rays,
                             std::int64_t shot) {
  const LidarModel lidar(sensor);
  TransportOptions options;
  options.rays = rays;
  options.max_order = 1;
  options.power_waveforms = false;
  options.scored_energies = true;
  const ShotWaveforms w = simulate_shot(scene, lidar, geometry, optics, options, shot);
  ScoredPhotons s;
  s.photons = expected_photons(w.scored.total_J[0], 532.0, kEfficiency);
  s.draw.bin_ns = sensor.bin_ns;
  s.draw.bins = static_cast<std::size_t>(sensor.bins);
  s.draw.channels = 16;
  s.bins = w.scored.bins;
  s.draw.grid_offset_bins = -lidar.margin_bins();
  s.draw.pulse_sigma_ns = sensor.pulse_sigma_ns;
  return s;
}

// Over level Lambertian ground of reflectance rho at nadir from 496 km.
ScoredPhotons flat_ground_photons(double rho, double energy_mJ, double transmission) {
  test_support::CrownScene scene({}, {}, {rho});
  scene.geometry.sensor_m = {0.0, 0.0, kRangeM};
  scene.geometry.range_m = kRangeM;
  return scored_photons(*scene.scene, scene.geometry, scene.optics,
                        atlas_sensor(energy_mJ, transmission), 2000, 5);
}

// E T A_T rho cos(0) f_fov eta / (pi R^2 h nu), f_fov = 1 - exp(-ifov^2 / (8 sigma^2)).
double flat_ground_closed_form(double rho, double energy_J, double transmission) {
  const double f_fov = 1.0 - std::exp(-kIfovRad * kIfovRad / (8.0 * kSigmaRad * kSigmaRad));
  return energy_J * transmission * kAreaM2 * rho * f_fov * kEfficiency /
         (std::numbers::pi * kRangeM * kRangeM * kPhoton532J);
}

// The counts' moments over many shots, and the photons' times' (each shot's window clock).
struct CountMoments {
  double mean = 0.0, variance = 0.0;
  double time_mean_ns = 0.0, time_rms_ns = 0.0;
};

CountMoments signal_counts(const ScoredPhotons& scored, int shots, std::uint32_t beam,
                           std::uint64_t seed = 7) {
  const PhotonSource ground{scored.photons, PhotonTruth::ground, 1};
  std::vector<double> counts;
  double n = 0.0, sum = 0.0, sum2 = 0.0;
  for (int shot = 0; shot < shots; ++shot) {
    PhotonDraw draw = scored.draw;
    draw.signal_bins = scored.bins;
    draw.seed = seed;
    draw.shot = shot;
    draw.beam = beam;
    const std::vector<PhotonEvent> events = draw_photons(draw, {&ground, 1});
    counts.push_back(static_cast<double>(events.size()));
    for (const PhotonEvent& e : events) {
      n += 1.0;
      sum += e.time_ns;
      sum2 += e.time_ns * e.time_ns;
    }
  }
  CountMoments m;
  for (double c : counts) m.mean += c;
  m.mean /= shots;
  for (double c : counts) m.variance += (c - m.mean) * (c - m.mean);
  m.variance /= shots - 1;
  m.time_mean_ns = sum / n;
  m.time_rms_ns = std::sqrt(sum2 / n - m.time_mean_ns * m.time_mean_ns);
  return m;
}

// 20 000 shots of a strong beam over rho = 0.3 through a clear atmosphere (T = 0.64 both ways):
// the mean count to 3 standard errors, and its variance equal to the mean to 3 standard errors
// of a Poisson sample variance, sqrt((mu + 2 mu^2) / N). The photons' times spread as the pulse
// (sigma 0.637 ns) and the bin (0.1 ns, uniform) add, sqrt(sigma^2 + bin^2 / 12) = 0.638 ns
// (the footprint's curvature adds 1e-4 ns), to 2 % (about 53 000 photons: the RMS's standard
// error is 0.3 %), about the reference return 2/3 into the window.
TEST(PhotonCounting, SignalOverFlatLambertianGroundAtNadir) {
  const ScoredPhotons scored = flat_ground_photons(0.3, 0.175, 0.64);
  const double mu = flat_ground_closed_form(0.3, 175e-6, 0.64);
  const int shots = 20000;
  const CountMoments m = signal_counts(scored, shots, 0);
  EXPECT_NEAR(m.mean, mu, 3.0 * std::sqrt(mu / shots));
  EXPECT_NEAR(m.variance, mu, 3.0 * std::sqrt((mu + 2.0 * mu * mu) / shots));
  const double sigma_tx_ns = 1.5 / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  EXPECT_NEAR(m.time_rms_ns / std::sqrt(sigma_tx_ns * sigma_tx_ns + 0.01 / 12.0), 1.0, 0.02);
  // Bin 100 of 150 is centred on the return, which the window's clock puts at 10.05 ns.
  EXPECT_NEAR(m.time_mean_ns, 10.05, 0.01);
}

// The pulse moves photons out of the window, and they are lost: one bin's photons at the
// window's very start, spread by a 1 ns pulse, are kept with probability
// P(u bin + sigma z >= 0) = integral over u in [0, 1) of Phi(u bin / sigma), for a 0.1 ns bin by
// Phi's series 1/2 + phi(0) (x - x^3 / 6): 1/2 + 0.05 phi(0) - 0.001 phi(0) / 24 = 0.519930;
// 40 000 shots of one photon each on average, to 3 standard errors.
TEST(PhotonCounting, ThePulseSpreadsPhotonsOutOfTheWindowAndTheyAreLost) {
  const std::vector<double> photons{1.0};
  const std::uint32_t bin[] = {20};
  const PhotonSource ground{photons, PhotonTruth::ground, 1};
  double kept = 0.0;
  const int shots = 40000;
  for (int shot = 0; shot < shots; ++shot) {
    PhotonDraw draw{3, shot, 0, 0.1, 50, 0.0, 16};
    draw.signal_bins = bin;
    draw.grid_offset_bins = -20;  // the grid's bin 20 is the window's first
    draw.pulse_sigma_ns = 1.0;
    for (const PhotonEvent& e : draw_photons(draw, {&ground, 1})) {
      EXPECT_GE(e.time_ns, 0.0);
      EXPECT_LT(e.time_ns, 5.0);
      kept += 1.0;
    }
  }
  double expected = 0.0;  // the integral by the midpoint rule over 10 000 steps
  for (int k = 0; k < 10000; ++k)
    expected += 0.5 * std::erfc(-((k + 0.5) / 10000.0) * 0.1 / 1.0 / std::sqrt(2.0)) / 10000.0;
  EXPECT_NEAR(expected, 0.519930, 2e-6);
  EXPECT_NEAR(kept / shots, expected, 3.0 * std::sqrt(expected / shots));
}

// The background rate over a bright (0.9) and a dark (0.05) surface under a sun 30 degrees from
// the zenith, one-way transmission 0.8, a 38 pm filter, measured from the drawn events (10 us
// windows) against L = (rho/pi) F cos(30) 0.8^(1/cos 30), rate = L 0.8 A_T pi (ifov/2)^2 dlambda
// eta / (h nu), F = 1.87 W m^-2 nm^-1 (ASTM E-490 at 532 nm), within 2 %.
TEST(PhotonCounting, SolarBackgroundEqualsTheClosedForm) {
  for (const double rho : {0.9, 0.05}) {
    SolarBackground sun;
    sun.sun_zenith_deg = 30.0;
    sun.reflectance = rho;
    sun.transmission_one_way = 0.8;
    sun.filter_bandwidth_nm = 0.038;
    sun.ifov_rad = kIfovRad;
    sun.telescope_area_m2 = kAreaM2;
    sun.efficiency = kEfficiency;
    const double cos30 = std::sqrt(3.0) / 2.0;
    const double radiance = rho / std::numbers::pi * 1.87 * cos30 * std::pow(0.8, 1.0 / cos30);
    const double closed_form_Hz = radiance * 0.8 * kAreaM2 * std::numbers::pi * kIfovRad *
                                  kIfovRad / 4.0 * 0.038 * kEfficiency / kPhoton532J;
    EXPECT_NEAR(background_rate_Hz(sun) / closed_form_Hz, 1.0, 1e-6);
    const int shots = 4000;
    double events = 0.0;
    for (int shot = 0; shot < shots; ++shot)
      events += static_cast<double>(
          draw_photons({3, shot, 2, 1.0, 10000, background_rate_Hz(sun), 4}, {}).size());
    const double measured_Hz = events / (shots * 10e-6);
    EXPECT_NEAR(measured_Hz / closed_form_Hz, 1.0, 0.02) << "rho " << rho;
  }
  SolarBackground night;
  night.sun_zenith_deg = 95.0;
  night.reflectance = 0.9;
  EXPECT_EQ(background_rate_Hz(night), 0.0);
}

// 16 channels, 3.2 ns dead time, true rates per channel r tau = 0.1, 1 and 4: the recorded rate
// per channel r / (1 + r tau) within 1.5 % (two windows of 10^5 events each: a standard error
// of 0.3 %).
TEST(PhotonCounting, DeadTimeFollowsTheNonParalysableLaw) {
  const double tau_ns = 3.2;
  for (const double r_tau : {0.1, 1.0, 4.0}) {
    const double per_channel_Hz = r_tau / (tau_ns * 1e-9);
    const std::size_t window_ns = static_cast<std::size_t>(1e5 / (16.0 * per_channel_Hz * 1e-9));
    double recorded = 0.0, window_s = 0.0;
    for (int shot = 0; shot < 2; ++shot) {
      const std::vector<PhotonEvent> events =
          draw_photons({11, shot, 0, 1.0, window_ns, 16.0 * per_channel_Hz, 16}, {});
      recorded += static_cast<double>(apply_dead_time(events, tau_ns).size());
      window_s += static_cast<double>(window_ns) * 1e-9;
    }
    const double recorded_per_channel_Hz = recorded / window_s / 16.0;
    EXPECT_NEAR(recorded_per_channel_Hz / (per_channel_Hz / (1.0 + r_tau)), 1.0, 0.015)
        << "r tau " << r_tau;
  }
}

TEST(PhotonCounting, DeadTimeIsPerChannelAndKeepsTimeOrder) {
  const std::vector<PhotonEvent> events = {{1.0, PhotonTruth::ground, 1, 0},
                                           {2.0, PhotonTruth::ground, 1, 1},
                                           {3.0, PhotonTruth::canopy, 1, 0},
                                           {4.5, PhotonTruth::background, 0, 0},
                                           {5.0, PhotonTruth::canopy, 2, 0}};
  const std::vector<PhotonEvent> kept = apply_dead_time(events, 3.2);
  // Channel 0 counts at 1.0 and is dead until 4.2 (the 3.0 event lost does not extend it);
  // it counts at 4.5, dead until 7.7, losing 5.0. Channel 1 counts its only event.
  ASSERT_EQ(kept.size(), 3u);
  EXPECT_EQ(kept[0].time_ns, 1.0);
  EXPECT_EQ(kept[1].time_ns, 2.0);
  EXPECT_EQ(kept[2].time_ns, 4.5);
}

// A shot's events depend on (seed, shot, beam) alone: the same call twice gives the same bits,
// another beam or shot other events; each source keeps its class and order.
TEST(PhotonCounting, EventsAreKeyedBySeedShotAndBeam) {
  std::vector<double> ground(100, 0.0), canopy(100, 0.0);
  for (std::size_t bin = 40; bin < 60; ++bin) ground[bin] = 0.5;
  for (std::size_t bin = 10; bin < 30; ++bin) canopy[bin] = 0.3;
  const PhotonSource sources[] = {{ground, PhotonTruth::ground, 1},
                                  {canopy, PhotonTruth::canopy, 2}};
  const PhotonDraw draw{5, 123, 1, 0.5, 100, 2e8, 16};
  const std::vector<PhotonEvent> a = draw_photons(draw, sources);
  EXPECT_EQ(a, draw_photons(draw, sources));
  PhotonDraw other_beam = draw, other_shot = draw;
  other_beam.beam = 2;
  other_shot.shot = 124;
  EXPECT_NE(a, draw_photons(other_beam, sources));
  EXPECT_NE(a, draw_photons(other_shot, sources));
  ASSERT_FALSE(a.empty());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (i > 0) {
      EXPECT_LE(a[i - 1].time_ns, a[i].time_ns);
    }
    EXPECT_LT(a[i].channel, 16);
    if (a[i].truth_class == PhotonTruth::ground) {
      EXPECT_GE(a[i].time_ns, 20.0);
      EXPECT_LT(a[i].time_ns, 30.0);
      EXPECT_EQ(a[i].order, 1);
    } else if (a[i].truth_class == PhotonTruth::canopy) {
      EXPECT_GE(a[i].time_ns, 5.0);
      EXPECT_LT(a[i].time_ns, 15.0);
      EXPECT_EQ(a[i].order, 2);
    } else {
      EXPECT_EQ(a[i].order, 0);
    }
  }
  EXPECT_THROW(draw_photons({5, 1, 256, 0.5, 100, 0.0, 16}, sources), std::invalid_argument);
}

// The draw as the header states it, from RandomStream itself: bin b's photons from the stream
// (seed, shot, (beam << 24) | b), the background's from (seed, shot, (beam << 24) | 2^24 - 1),
// sorted.
std::vector<PhotonEvent> keyed_draw(const PhotonDraw& draw, std::span<const PhotonSource> sources) {
  std::vector<PhotonEvent> events;
  auto channel = [&](RandomStream& random) {
    return static_cast<std::uint8_t>(
        std::min(draw.channels - 1, static_cast<int>(random.uniform() * draw.channels)));
  };
  for (std::size_t bin = 0; bin < draw.bins; ++bin) {
    double total = 0.0;
    for (const PhotonSource& source : sources) total += std::max(source.mean_per_bin[bin], 0.0);
    if (!(total > 1e-12)) continue;
    RandomStream random(draw.seed, static_cast<std::uint64_t>(draw.shot),
                        (std::uint64_t{draw.beam} << 24) | bin, RandomPurpose::photons);
    const double count = poisson(random, total);
    for (double k = 0.0; k < count; k += 1.0) {
      double pick = random.uniform() * total;
      std::size_t source = 0;
      while (source + 1 < sources.size() && pick >= sources[source].mean_per_bin[bin]) {
        pick -= sources[source].mean_per_bin[bin];
        ++source;
      }
      const double time_ns = (static_cast<double>(bin) + random.uniform()) * draw.bin_ns;
      events.push_back(
          {time_ns, sources[source].truth_class, sources[source].order, channel(random)});
    }
  }
  const double window_ns = static_cast<double>(draw.bins) * draw.bin_ns;
  RandomStream random(draw.seed, static_cast<std::uint64_t>(draw.shot),
                      (std::uint64_t{draw.beam} << 24) | ((1u << 24) - 1), RandomPurpose::photons);
  const double count = poisson(random, draw.background_rate_Hz * window_ns * 1e-9);
  for (double k = 0.0; k < count; k += 1.0) {
    const double time_ns = random.uniform() * window_ns;
    events.push_back({time_ns, PhotonTruth::background, 0, channel(random)});
  }
  std::sort(events.begin(), events.end(), [](const PhotonEvent& a, const PhotonEvent& b) {
    return std::tie(a.time_ns, a.truth_class, a.order, a.channel) <
           std::tie(b.time_ns, b.truth_class, b.order, b.channel);
  });
  return events;
}

// draw_photons steps from one bin's stream to the next's (2^32 draws on, one affine step of the
// PCG) instead of keying each afresh: the same events, bit for bit, as each bin's RandomStream
// gives, over runs of consecutive bins, gaps between them, several seeds, shots and beams, and
// bins past 2^16.
TEST(PhotonCounting, BinStreamsAreTheKeyedStreams) {
  const std::size_t bins = 70000;
  std::vector<double> ground(bins, 0.0), canopy(bins, 0.0);
  for (std::size_t bin = 40; bin < 60; ++bin) ground[bin] = 0.5;
  for (std::size_t bin = 10; bin < 30; ++bin) canopy[bin] = 0.3;
  for (std::size_t bin = 100; bin < 400; bin += 3) canopy[bin] = 0.05;  // gaps of two bins
  for (std::size_t bin = 65530; bin < 65545; ++bin) ground[bin] = 2.0;  // across 2^16
  canopy[69999] = 20.0;                                                 // PTRS's means
  const PhotonSource sources[] = {{ground, PhotonTruth::ground, 1},
                                  {canopy, PhotonTruth::canopy, 2}};
  std::size_t photons = 0;
  for (const std::uint64_t seed : {1u, 77u})
    for (const std::int64_t shot : {0, 1, 123456789})
      for (const std::uint32_t beam : {0u, 3u, 255u}) {
        const PhotonDraw draw{seed, shot, beam, 0.5, bins, 1e5, 16};
        const std::vector<PhotonEvent> events = draw_photons(draw, sources);
        EXPECT_EQ(events, keyed_draw(draw, sources)) << seed << " " << shot << " " << beam;
        photons += events.size();
      }
  EXPECT_GT(photons, 1000u);
}

// The signal's bins, when the caller lists those alone (the sources' means at the grid's bins
// signal_bins), give the same events as the whole grid: the bins left out, whose means are all 0,
// draw nothing either way, and each bin keeps its key. Listed bins must increase and match the
// means one for one.
TEST(PhotonCounting, TheSignalsBinsDrawWhatTheWholeGridDraws) {
  std::vector<double> ground(100, 0.0), canopy(100, 0.0);
  for (std::size_t bin = 40; bin < 60; ++bin) ground[bin] = 0.5;
  for (std::size_t bin = 10; bin < 30; ++bin) canopy[bin] = 0.3;
  std::vector<std::uint32_t> listed;
  std::vector<double> listed_ground, listed_canopy;
  for (std::uint32_t bin = 0; bin < 100; ++bin)
    if (ground[bin] > 0.0 || canopy[bin] > 0.0) {
      listed.push_back(bin);
      listed_ground.push_back(ground[bin]);
      listed_canopy.push_back(canopy[bin]);
    }
  ASSERT_EQ(listed.size(), 40u);
  const PhotonSource whole_sources[] = {{ground, PhotonTruth::ground, 1},
                                        {canopy, PhotonTruth::canopy, 2}};
  const PhotonSource listed_sources[] = {{listed_ground, PhotonTruth::ground, 1},
                                         {listed_canopy, PhotonTruth::canopy, 2}};
  for (const std::int64_t shot : {1, 2, 3}) {
    PhotonDraw whole{5, shot, 1, 0.5, 100, 2e8, 16};
    whole.pulse_sigma_ns = 0.6;
    PhotonDraw signal = whole;
    signal.signal_bins = listed;
    const std::vector<PhotonEvent> a = draw_photons(whole, whole_sources);
    ASSERT_FALSE(a.empty());
    EXPECT_EQ(draw_photons(signal, listed_sources), a);
  }
  PhotonDraw unsorted{5, 1, 1, 0.5, 100, 0.0, 16};
  std::vector<std::uint32_t> swapped = listed;
  std::swap(swapped[0], swapped[1]);
  unsorted.signal_bins = swapped;
  EXPECT_THROW(draw_photons(unsorted, listed_sources), std::invalid_argument);
  unsorted.signal_bins = std::span(listed).first(39);
  EXPECT_THROW(draw_photons(unsorted, listed_sources), std::invalid_argument);
}

// PHYSICS.md section 2 (Gardner 1992) with ATLAS's pulse and beam: the ground photons' times on a
// 20 degree slope at nadir spread with the RMS width sqrt(sigma_tx^2 + (2 R sigma_theta tan 20 /
// c)^2 + bin^2 / 12) = 6.71 ns (1.01 m of height), to 2 % (about 27 000 photons: the RMS's
// standard error is 0.4 %).
TEST(PhotonCounting, GroundPhotonsOnASlopeSpreadAsGardner) {
  const double slope_deg = 20.0;
  PlaneTerrain plane{{0.0, 0.0, 0.0, slope_deg, 90.0}};
  LocalFrame frame{{0.0, 0.0, 0.0}};
  RayDevice device;
  Vegetation bare;
  const Scene scene(device, build_ground_mesh(plane, frame, 150.0, 1.0e9), bare);
  ShotGeometry geometry;
  geometry.sensor_m = {0.0, 0.0, kRangeM};
  geometry.axis = {0.0, 0.0, -1.0};
  geometry.range_m = kRangeM;
  SceneOptics optics;
  optics.soil_reflectance = {0.9};
  LidarSettings sensor = atlas_sensor(0.175, 0.64);
  sensor.bins = 1000;
  const CountMoments m =
      signal_counts(scored_photons(scene, geometry, optics, sensor, 20000, 9), 3000, 0, 13);
  const double sigma_tx_ns = 1.5 / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  const double slope_ns =
      2.0 * kRangeM * kSigmaRad * std::tan(slope_deg * std::numbers::pi / 180.0) / 0.299792458;
  const double gardner_ns =
      std::sqrt(sigma_tx_ns * sigma_tx_ns + slope_ns * slope_ns + 0.01 / 12.0);
  EXPECT_NEAR(gardner_ns, 6.71, 0.01);
  EXPECT_GT(m.mean * 3000.0, 20000.0);
  EXPECT_NEAR(m.time_rms_ns / gardner_ns, 1.0, 0.02);
}

// ICESat-2's specification gives about 1.6-12 signal photons a shot for a strong beam and
// 0.4-3 for a weak one over the ice sheet (reflectance 0.9), depending on the atmosphere. With
// the preset's 175 and 45 uJ: a clear atmosphere (one-way 0.8, T = 0.64) and a hazy one (one-way
// 0.5, T = 0.25) both fall in the range, the clear one near its top.
TEST(PhotonCounting, StrongAndWeakBeamsOverIceFallInTheMissionsRange) {
  for (const double t : {0.64, 0.25}) {
    const double strong = signal_counts(flat_ground_photons(0.9, 0.175, t), 4000, 0).mean;
    const double weak = signal_counts(flat_ground_photons(0.9, 0.045, t), 4000, 1).mean;
    EXPECT_GT(strong, 1.6) << "T " << t;
    EXPECT_LT(strong, 12.0) << "T " << t;
    EXPECT_GT(weak, 0.4) << "T " << t;
    EXPECT_LT(weak, 3.0) << "T " << t;
    EXPECT_NEAR(strong / weak, 175.0 / 45.0, 0.35);
  }
}

}  // namespace
}  // namespace glaswave
