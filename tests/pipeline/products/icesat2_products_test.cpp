// The ATL08-style classification on a synthetic photon cloud whose truth is known here (a sloping
// ground, a forest of known height over part of the track, solar noise), and the ATL03/ATL08
// granules read back through the HDF5 C library at the paths ICESat-2's readers use (icepyx,
// SpaceLiDAR.jl, rICESat2Veg): 1-based photon index ranges that cover every photon once, the
// land segments' estimates against the cloud's truth, the same bytes written twice, nothing left
// under a temporary name.
#include "pipeline/products/icesat2_products.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <numbers>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "core/random.hpp"
#include "core/samplers.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

constexpr double kSpacingM = 0.7;
constexpr double kTrackM = 1000.0;
constexpr double kForestFrom = 200.0, kForestTo = 800.0;
constexpr double kCanopyBase = 2.0, kCanopyTop = 25.0;

// 1.5 noise photons a shot over 75 m of height: 1.5 / (75 * 2 / c) photons a second.
constexpr double kNoiseRateHz = 1.5 / (75.0 * 2.0 / 299792458.0);

double ground_truth(double along_m) { return 100.0 + 0.05 * along_m; }

// A strong beam's cloud: per shot Poisson(3) ground photons (0.15 m RMS about the ground),
// Poisson(2) canopy photons uniform between 2 and 25 m above it inside the forest, Poisson(1.5)
// noise photons uniform from 25 m below to 50 m above it.
BeamTrack synthetic_beam(const std::string& name, std::uint64_t seed) {
  BeamTrack beam;
  beam.name = name;
  const int shots = static_cast<int>(kTrackM / kSpacingM);
  for (int k = 0; k < shots; ++k) {
    BeamShot shot;
    shot.along_m = k * kSpacingM;
    shot.lat_deg = 45.0 + shot.along_m / 111000.0;
    shot.lon_deg = 7.0;
    shot.delta_time_s = 2.5e8 + k * 1e-4;
    shot.ground_h_m = ground_truth(shot.along_m);
    const bool forest = shot.along_m >= kForestFrom && shot.along_m < kForestTo;
    shot.canopy_height_m = forest ? kCanopyTop : 0.0;
    shot.canopy_cover = forest ? 0.7 : 0.0;
    shot.pai = forest ? 3.0 : 0.0;
    shot.background_rate_Hz = kNoiseRateHz;
    shot.first_photon = static_cast<std::uint32_t>(beam.photons.size());
    RandomStream random(seed, static_cast<std::uint64_t>(k), 0);
    const auto add = [&](double h, std::uint8_t truth) {
      beam.photons.push_back({h, shot.lat_deg, shot.lon_deg, shot.delta_time_s, truth,
                              static_cast<std::uint8_t>(truth ? 1 : 0)});
    };
    for (double n = poisson(random, 3.0); n > 0; --n)
      add(shot.ground_h_m + 0.15 * standard_normal(random), 1);
    if (forest)
      for (double n = poisson(random, 2.0); n > 0; --n)
        add(shot.ground_h_m + kCanopyBase + (kCanopyTop - kCanopyBase) * random.uniform(), 2);
    for (double n = poisson(random, 1.5); n > 0; --n)
      add(shot.ground_h_m - 25.0 + 75.0 * random.uniform(), 0);
    shot.photon_count = static_cast<std::uint32_t>(beam.photons.size()) - shot.first_photon;
    beam.shots.push_back(shot);
  }
  return beam;
}

TEST(Atl08Classification, SeparatesGroundCanopyAndNoiseWithoutTheTruth) {
  const BeamTrack beam = synthetic_beam("gt1l", 3);
  const Atl08Settings settings;
  const Atl08Classes c = classify_beams({beam}, settings)[0];
  // Noise inside the signal's layers (within the neighbour box of the ground or the canopy) is
  // photons among the signal's, as in ATL08; the noise outside them must be found as noise.
  double hits[4] = {0, 0, 0, 0}, totals[4] = {0, 0, 0, 0};
  for (const BeamShot& shot : beam.shots) {
    const bool forest = shot.along_m >= kForestFrom && shot.along_m < kForestTo;
    const double top = shot.ground_h_m + (forest ? kCanopyTop : 0.0);
    for (std::uint32_t k = 0; k < shot.photon_count; ++k) {
      const std::size_t i = shot.first_photon + k;
      const int truth = beam.photons[i].truth_class;
      const double h = beam.photons[i].h_m;
      if (truth == 0 && h > shot.ground_h_m - 3.5 && h < top + 3.5) continue;
      totals[truth] += 1.0;
      const int got = c.classes[i] == 3 ? 2 : c.classes[i];
      if (got == truth) hits[truth] += 1.0;
    }
  }
  EXPECT_GT(hits[0] / totals[0], 0.95) << "noise kept as noise";
  EXPECT_GT(hits[1] / totals[1], 0.95) << "ground found";
  EXPECT_GT(hits[2] / totals[2], 0.85) << "canopy found";
  // The fitted ground follows the true one to 0.1 m everywhere along the track.
  for (double x = 5.0; x < kTrackM - 5.0; x += 10.0)
    EXPECT_NEAR(c.ground_at(x), ground_truth(x), 0.1) << "at " << x << " m";
}

// A weak beam's 300 m over a slope of `grade` (rise over run): per shot Poisson(0.8) ground
// photons (0.15 m RMS), and over the last `crowns_m` dense crowns: ground Poisson(0.08), canopy
// Poisson(1.2) 12-18 m above it; Poisson(0.3) noise photons over 75 m.
BeamTrack weak_beam_ending_under_crowns(double grade, double crowns_m, std::uint64_t seed) {
  BeamTrack beam;
  beam.name = "gt1r";
  const double track_m = 300.0;
  const int shots = static_cast<int>(track_m / kSpacingM);
  for (int k = 0; k < shots; ++k) {
    BeamShot shot;
    shot.along_m = k * kSpacingM;
    shot.lat_deg = 45.0 + shot.along_m / 111000.0;
    shot.lon_deg = 7.0;
    shot.delta_time_s = 2.5e8 + k * 1e-4;
    shot.ground_h_m = 100.0 + grade * shot.along_m;
    const bool crowns = shot.along_m >= track_m - crowns_m;
    shot.background_rate_Hz = 0.3 / (75.0 * 2.0 / 299792458.0);
    shot.first_photon = static_cast<std::uint32_t>(beam.photons.size());
    RandomStream random(seed, static_cast<std::uint64_t>(k), 0);
    const auto add = [&](double h, std::uint8_t truth) {
      beam.photons.push_back({h, shot.lat_deg, shot.lon_deg, shot.delta_time_s, truth,
                              static_cast<std::uint8_t>(truth ? 1 : 0)});
    };
    for (double n = poisson(random, crowns ? 0.08 : 0.8); n > 0; --n)
      add(shot.ground_h_m + 0.15 * standard_normal(random), 1);
    if (crowns)
      for (double n = poisson(random, 1.2); n > 0; --n)
        add(shot.ground_h_m + 12.0 + 6.0 * random.uniform(), 2);
    for (double n = poisson(random, 0.3); n > 0; --n)
      add(shot.ground_h_m - 25.0 + 75.0 * random.uniform(), 0);
    shot.photon_count = static_cast<std::uint32_t>(beam.photons.size()) - shot.first_photon;
    beam.shots.push_back(shot);
  }
  return beam;
}

// Crowns over a track's last 40 m, under which too few ground photons make a cell's lowest bin:
// those cells' candidates are the crowns, 12 m and more above the ground. The ground fitted there
// stays the ground's line (a median of five cells took the crowns for the ground, 15 m up, where
// they outnumbered the ground's cells; the ground beyond the last found stayed level, 1.6 m low
// at the end), and no crown photon is ground.
TEST(Atl08Classification, CrownsAtATracksEndAreNotItsGround) {
  for (const std::uint64_t seed : {1u, 2u, 3u, 4u}) {
    const BeamTrack beam = weak_beam_ending_under_crowns(0.07, 40.0, seed);
    const Atl08Classes c = classify_beams({beam}, Atl08Settings{})[0];
    for (double x = 5.0; x < 295.0; x += 10.0) {
      // A weak beam's cell holds about 11 ground photons spread 0.7 m by the slope: its ground to
      // about 0.15 m, 0.5 m at most over 4 x 29 cells. Under the crowns the ground is the line
      // through the five cells before them, carried up to 45 m on: its slope's error (0.05 m a
      // cell) grows to about 0.25 m there; 3 of that.
      const double tolerance_m = x < 260.0 ? 0.5 : 0.75;
      EXPECT_NEAR(c.ground_at(x), 100.0 + 0.07 * x, tolerance_m) << "seed " << seed << " at " << x;
    }
    for (std::size_t i = 0; i < beam.photons.size(); ++i) {
      if (beam.photons[i].truth_class == 2) {
        EXPECT_NE(c.classes[i], 1) << "seed " << seed;
      }
    }
  }
}

// Land segments: the terrain at each centre to 0.1 m; in the forest the 98th percentile of canopy
// heights uniform over 2-25 m is 2 + 0.98 * 23 = 24.54 m (to 1 m: noise photons join the canopy)
// and the openness their standard deviation 23 / sqrt(12) = 6.64 m (to 1 m: noise); outside, no
// canopy but the noise within the ground's neighbour box, 0.5-3 m above it (about 143 shots *
// 1.5 * 2.5 / 75 = 7 photons a segment; 3 times that at most), too few for a canopy height.
TEST(Atl08Classification, LandSegmentsMatchTheCloudsTruth) {
  const BeamTrack beam = synthetic_beam("gt1l", 4);
  const Atl08Settings settings;
  const Atl08Classes c = classify_beams({beam}, settings)[0];
  std::vector<CloudPhoton> cloud;
  for (const BeamShot& shot : beam.shots)
    for (std::uint32_t i = 0; i < shot.photon_count; ++i)
      cloud.push_back(
          {shot.along_m, beam.photons[shot.first_photon + i].h_m, 1.5 / 75.0 / kSpacingM});
  const std::vector<LandSegment> segments = land_segments(cloud, c, 0.0, kTrackM, settings);
  ASSERT_EQ(segments.size(), 10u);
  for (const LandSegment& s : segments) {
    const double centre = s.start_m + 50.0;
    EXPECT_NEAR(s.h_te_best_fit, ground_truth(centre), 0.1) << s.start_m;
    EXPECT_GT(s.n_te_photons, 300);
    if (s.start_m >= kForestFrom && s.start_m + 100.0 <= kForestTo) {
      EXPECT_NEAR(s.h_canopy, kCanopyBase + 0.98 * (kCanopyTop - kCanopyBase), 1.0) << s.start_m;
      EXPECT_NEAR(s.canopy_openness, (kCanopyTop - kCanopyBase) / std::sqrt(12.0), 1.0);
      EXPECT_GT(s.n_ca_photons + s.n_toc_photons, 200);
    } else if (s.start_m + 100.0 <= kForestFrom || s.start_m >= kForestTo) {
      EXPECT_LT(s.n_ca_photons + s.n_toc_photons, 21) << s.start_m;
      EXPECT_TRUE(std::isnan(s.h_canopy)) << "under 5 % of the signal: no canopy height";
    }
  }
}

// ---- the granules read back -------------------------------------------------------------

template <typename T>
std::vector<T> read(hid_t file, const std::string& path, hid_t type) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  EXPECT_GE(set, 0) << path;
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  std::vector<T> values(static_cast<std::size_t>(n));
  if (n > 0) H5Dread(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(set);
  return values;
}

std::string bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// A granule's run information: its history, an empty configuration, the rest unknown (fill).
GranuleInfo granule_info(const std::string& history) {
  GranuleInfo info;
  info.history = history;
  info.config_json = "{}";
  return info;
}

TEST(Icesat2Granules, Atl03HasItsPathsAndOneBasedSegmentRanges) {
  const test_support::ScratchDir dir("icesat2_atl03");
  const std::vector<BeamTrack> beams = {synthetic_beam("gt1l", 5), synthetic_beam("gt1r", 6)};
  const std::vector<Atl08Classes> classes = classify_beams(beams, Atl08Settings{});
  write_atl03(dir.path() / "atl03.h5", beams, classes, granule_info("glaswave run test"));
  ASSERT_TRUE(std::filesystem::exists(dir.path() / "atl03.h5"));
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "atl03.h5.part"));
  const hid_t file = H5Fopen((dir.path() / "atl03.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  for (const BeamTrack& beam : beams) {
    const std::string g = "/" + beam.name;
    const auto h = read<float>(file, g + "/heights/h_ph", H5T_NATIVE_FLOAT);
    const auto lat = read<double>(file, g + "/heights/lat_ph", H5T_NATIVE_DOUBLE);
    const auto time = read<double>(file, g + "/heights/delta_time", H5T_NATIVE_DOUBLE);
    const auto conf = read<std::int8_t>(file, g + "/heights/signal_conf_ph", H5T_NATIVE_INT8);
    const auto truth =
        read<std::uint8_t>(file, g + "/heights/glaswave_truth_class", H5T_NATIVE_UINT8);
    ASSERT_EQ(h.size(), beam.photons.size());
    ASSERT_EQ(conf.size(), 5 * h.size());
    ASSERT_EQ(truth.size(), h.size());
    EXPECT_EQ(read<double>(file, g + "/heights/lon_ph", H5T_NATIVE_DOUBLE).size(), h.size());
    for (std::size_t i = 0; i < h.size(); i += 97) {
      EXPECT_FLOAT_EQ(h[i], static_cast<float>(beam.photons[i].h_m));
      EXPECT_EQ(lat[i], beam.photons[i].lat_deg);
      EXPECT_EQ(time[i], beam.photons[i].delta_time_s);
      EXPECT_EQ(truth[i], beam.photons[i].truth_class);
      EXPECT_EQ(conf[5 * i + 1], -1);
    }
    const auto id = read<std::int32_t>(file, g + "/geolocation/segment_id", H5T_NATIVE_INT32);
    const auto beg = read<std::int64_t>(file, g + "/geolocation/ph_index_beg", H5T_NATIVE_INT64);
    const auto cnt = read<std::int32_t>(file, g + "/geolocation/segment_ph_cnt", H5T_NATIVE_INT32);
    // 1000 m of track from 0: segments 1 to 50 of 20 m.
    ASSERT_EQ(id.size(), 50u);
    EXPECT_EQ(id.front(), 1);
    EXPECT_EQ(id.back(), 50);
    std::int64_t next = 1;
    for (std::size_t j = 0; j < id.size(); ++j) {
      ASSERT_GT(cnt[j], 0);
      EXPECT_EQ(beg[j], next) << "segment " << id[j];
      // Every photon of the range belongs to a shot inside the segment's 20 m.
      for (std::int64_t i = beg[j] - 1; i < beg[j] - 1 + cnt[j]; i += 13) {
        const double along = (time[static_cast<std::size_t>(i)] - 2.5e8) / 1e-4 * kSpacingM;
        EXPECT_GE(along, (id[j] - 1) * 20.0 - 1e-3);
        EXPECT_LT(along, id[j] * 20.0 + 1e-3);
      }
      next += cnt[j];
    }
    EXPECT_EQ(next - 1, static_cast<std::int64_t>(h.size()));
  }
  const auto epoch = read<double>(file, "/ancillary_data/atlas_sdp_gps_epoch", H5T_NATIVE_DOUBLE);
  ASSERT_EQ(epoch.size(), 1u);
  EXPECT_EQ(epoch[0], 1198800018.0);
  H5Fclose(file);
}

TEST(Icesat2Granules, Atl08HasItsPathsAndTheSameBytesTwice) {
  const test_support::ScratchDir dir("icesat2_atl08");
  const std::vector<BeamTrack> beams = {synthetic_beam("gt2l", 7)};
  const Atl08Settings settings;
  const std::vector<Atl08Classes> classes = classify_beams(beams, settings);
  write_atl08(dir.path() / "a.h5", beams, classes, settings, granule_info("h"));
  write_atl08(dir.path() / "b.h5", beams, classify_beams(beams, settings), settings,
              granule_info("h"));
  EXPECT_EQ(bytes(dir.path() / "a.h5"), bytes(dir.path() / "b.h5"));
  const hid_t file = H5Fopen((dir.path() / "a.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const std::string g = "/gt2l/land_segments/";
  const auto terrain = read<float>(file, g + "terrain/h_te_best_fit", H5T_NATIVE_FLOAT);
  const auto canopy = read<float>(file, g + "canopy/h_canopy", H5T_NATIVE_FLOAT);
  const auto truth = read<float>(file, g + "glaswave_truth/h_canopy", H5T_NATIVE_FLOAT);
  ASSERT_EQ(terrain.size(), 10u);
  ASSERT_EQ(canopy.size(), 10u);
  for (std::size_t k = 0; k < 10; ++k) EXPECT_NEAR(terrain[k], ground_truth(100.0 * k + 50.0), 0.1);
  EXPECT_NEAR(canopy[4], 24.54, 1.0);
  EXPECT_EQ(truth[4], 25.0f);
  EXPECT_EQ(truth[0], 0.0f);
  for (const char* path : {"latitude", "longitude", "delta_time", "canopy/canopy_openness",
                           "canopy/n_ca_photons", "terrain/n_te_photons"})
    EXPECT_EQ(read<double>(file, g + path, H5T_NATIVE_DOUBLE).size(), 10u) << path;
  const auto flag =
      read<std::int8_t>(file, "/gt2l/signal_photons/classed_pc_flag", H5T_NATIVE_INT8);
  const auto index =
      read<std::int32_t>(file, "/gt2l/signal_photons/classed_pc_indx", H5T_NATIVE_INT32);
  ASSERT_EQ(flag.size(), index.size());
  ASSERT_FALSE(flag.empty());
  for (std::size_t i = 0; i < flag.size(); ++i) {
    EXPECT_GE(flag[i], 1);
    EXPECT_LE(flag[i], 3);
    EXPECT_GE(index[i], 1);
  }
  H5Fclose(file);
}

// The ground photons' statistics against the synthetic cloud's truth: in each 100 m segment
// h_te_mean and h_te_median are those of the photons drawn on the ground (a classification that
// missed ground photons or took noise would show), terrain_slope the line's 0.05, and
// h_te_uncertainty the 0.15 m RMS over sqrt(n_te_photons).
TEST(Icesat2Granules, Atl08TerrainStatisticsMatchTheCloudsTruth) {
  const test_support::ScratchDir dir("icesat2_atl08_terrain");
  const std::vector<BeamTrack> beams = {synthetic_beam("gt2l", 9)};
  const Atl08Settings settings;
  write_atl08(dir.path() / "atl08.h5", beams, classify_beams(beams, settings), settings,
              granule_info("h"));
  const hid_t file = H5Fopen((dir.path() / "atl08.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const std::string g = "/gt2l/land_segments/terrain/";
  const auto mean = read<float>(file, g + "h_te_mean", H5T_NATIVE_FLOAT);
  const auto median = read<float>(file, g + "h_te_median", H5T_NATIVE_FLOAT);
  const auto slope = read<float>(file, g + "terrain_slope", H5T_NATIVE_FLOAT);
  const auto sigma = read<float>(file, g + "h_te_uncertainty", H5T_NATIVE_FLOAT);
  const auto n = read<std::int32_t>(file, g + "n_te_photons", H5T_NATIVE_INT32);
  ASSERT_EQ(mean.size(), 10u);
  std::vector<std::vector<double>> truth(10);
  for (const BeamShot& shot : beams[0].shots)
    for (std::uint32_t i = 0; i < shot.photon_count; ++i)
      if (beams[0].photons[shot.first_photon + i].truth_class == 1)
        truth[static_cast<std::size_t>(shot.along_m / 100.0)].push_back(
            beams[0].photons[shot.first_photon + i].h_m);
  for (std::size_t k = 0; k < 10; ++k) {
    std::vector<double>& h = truth[k];
    std::sort(h.begin(), h.end());
    const double truth_mean = std::accumulate(h.begin(), h.end(), 0.0) / h.size();
    const double truth_median = 0.5 * (h[(h.size() - 1) / 2] + h[h.size() / 2]);
    // The classification keeps about 95 % of the ground photons (the test above), losing those
    // at the edge of its band where its fitted surface strays by a few cm: the statistics move
    // by as much, far less than the 0.15 m scatter or a wrong photon set (5 m across a segment).
    EXPECT_NEAR(mean[k], truth_mean, 0.05) << k;
    EXPECT_NEAR(median[k], truth_median, 0.05) << k;
    EXPECT_NEAR(n[k], static_cast<double>(h.size()), 0.05 * h.size()) << k;
    EXPECT_NEAR(slope[k], 0.05, 0.002) << k;
    const double expected = 0.15 / std::sqrt(static_cast<double>(n[k]));
    EXPECT_NEAR(sigma[k], expected, 0.2 * expected) << k;
  }
  const auto orient = read<std::int8_t>(file, "/orbit_info/sc_orient", H5T_NATIVE_INT8);
  ASSERT_EQ(orient.size(), 1u);
  EXPECT_EQ(orient[0], 0);  // backward: the left beams strong, as footprints/atlas_beams has them
  H5Fclose(file);
}

// ---- the layout the readers open, from the data dictionaries and the readers' sources ----

// Whether `path` is a dataset of exactly `type` (H5Tequal on its stored type).
bool has_type(hid_t file, const std::string& path, hid_t type) {
  if (H5Lexists(file, path.c_str(), H5P_DEFAULT) <= 0) return false;
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (set < 0) return false;
  const hid_t stored = H5Dget_type(set);
  const bool same = H5Tequal(stored, type) > 0;
  H5Tclose(stored);
  H5Dclose(set);
  return same;
}

// A text attribute of the object at `path` ("" when it has none).
std::string text_attribute(hid_t file, const std::string& path, const std::string& name) {
  if (H5Aexists_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT) <= 0) return "";
  const hid_t attribute =
      H5Aopen_by_name(file, path.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
  const hid_t type = H5Aget_type(attribute);
  std::string text(H5Tget_size(type), '\0');
  H5Aread(attribute, type, text.data());
  H5Tclose(type);
  H5Aclose(attribute);
  return text.substr(0, text.find('\0'));
}

// The _FillValue attribute of the dataset at `path`, read as `T` (NaN-free types only).
template <typename T>
std::optional<T> fill_value(hid_t file, const std::string& path, hid_t memory) {
  if (H5Aexists_by_name(file, path.c_str(), "_FillValue", H5P_DEFAULT) <= 0) return std::nullopt;
  const hid_t attribute =
      H5Aopen_by_name(file, path.c_str(), "_FillValue", H5P_DEFAULT, H5P_DEFAULT);
  T value{};
  H5Aread(attribute, memory, &value);
  H5Aclose(attribute);
  return value;
}

// A transmitted pulse of 1.5 ns FWHM sampled every 0.1 ns over +-3 ns about its peak.
GranuleInfo forward_info() {
  GranuleInfo info = granule_info("glaswave run test");
  info.sc_orient = atlas_sc_orient_forward;
  info.dead_time_ns = 3.2;
  const double sigma_ns = 1.5 / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  for (int i = -30; i <= 30; ++i) {
    info.pulse_time_ns.push_back(0.1 * i);
    info.pulse_power.push_back(std::exp(-0.5 * std::pow(0.1 * i / sigma_ns, 2)));
  }
  return info;
}

// A forward granule's beams: gt1l weak (spot 6), gt1r strong (spot 5), as the ATL03 data
// dictionary's table has them (tests/footprints/atlas_beams_test.cpp).
std::vector<BeamTrack> forward_beams() {
  std::vector<BeamTrack> beams = {synthetic_beam("gt1l", 11), synthetic_beam("gt1r", 12)};
  beams[0].strong = false, beams[0].spot_number = 6;
  beams[1].strong = true, beams[1].spot_number = 5;
  return beams;
}

// read-ICESat-2's read_granule (icesat2_toolkit/io/ATL03.py), in its order: a beam is one with
// geolocation/segment_id and heights/delta_time; every dataset of heights/, geolocation/,
// bckgrd_atlas/ and geophys_corr/ read whole; orbit_info/'s; ancillary_data/'s 21 keys (each
// read with [:], so one-element arrays, never scalars); every dataset of ancillary_data/tep/;
// calibrations/{dead_time, first_photon_bias}/gtXY/; atlas_impulse_response/{pce1_spot1,
// pce2_spot3}/tep_histogram/. ICESat2VegR's ATL03_seg_metadata_dt and the join add
// geolocation/reference_photon_index and orbit_info/orbit_number.
TEST(Icesat2Granules, Atl03HasEveryPathReadIcesat2AndIcesat2VegROpen) {
  const test_support::ScratchDir dir("icesat2_atl03_readers");
  const std::vector<BeamTrack> beams = forward_beams();
  write_atl03(dir.path() / "atl03.h5", beams, classify_beams(beams, Atl08Settings{}),
              forward_info());
  const hid_t file = H5Fopen((dir.path() / "atl03.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  for (const BeamTrack& beam : beams) {
    const std::string g = "/" + beam.name;
    EXPECT_TRUE(has_type(file, g + "/geolocation/segment_id", H5T_STD_I32LE));
    EXPECT_TRUE(has_type(file, g + "/heights/delta_time", H5T_IEEE_F64LE));
    for (const char* group : {"heights", "geolocation", "bckgrd_atlas", "geophys_corr"})
      EXPECT_GT(H5Lexists(file, (g + "/" + group).c_str(), H5P_DEFAULT), 0) << group;
    EXPECT_TRUE(has_type(file, g + "/geolocation/reference_photon_index", H5T_STD_I32LE));
    EXPECT_TRUE(has_type(file, g + "/geolocation/ph_index_beg", H5T_STD_I64LE));
    EXPECT_TRUE(has_type(file, g + "/geolocation/segment_ph_cnt", H5T_STD_I32LE));
    EXPECT_TRUE(has_type(file, g + "/geolocation/sigma_h", H5T_IEEE_F32LE));
    EXPECT_TRUE(has_type(file, g + "/geophys_corr/dem_h", H5T_IEEE_F32LE));
    EXPECT_TRUE(has_type(file, g + "/heights/signal_conf_ph", H5T_STD_I8LE));
    // The group's attributes in the forward orientation: gt1l weak on spot 6, gt1r strong on 5.
    EXPECT_EQ(text_attribute(file, g, "atlas_spot_number"), std::to_string(beam.spot_number));
    EXPECT_EQ(text_attribute(file, g, "atlas_beam_type"), beam.strong ? "strong" : "weak");
    EXPECT_EQ(text_attribute(file, g, "sc_orientation"), "Forward");
    // The reference photon: 1-based in its segment, its segment's first (0 for none).
    const auto reference =
        read<std::int32_t>(file, g + "/geolocation/reference_photon_index", H5T_NATIVE_INT32);
    const auto count =
        read<std::int32_t>(file, g + "/geolocation/segment_ph_cnt", H5T_NATIVE_INT32);
    ASSERT_EQ(reference.size(), count.size());
    for (std::size_t j = 0; j < count.size(); ++j) {
      EXPECT_GE(reference[j], count[j] > 0 ? 1 : 0);
      EXPECT_LE(reference[j], count[j]);
    }
    // read-ICESat-2 reads the channels' dead time and the first-photon bias tables per beam.
    const std::string cal = "/ancillary_data/calibrations/";
    const auto dead = read<double>(file, cal + "dead_time" + g + "/dead_time", H5T_NATIVE_DOUBLE);
    ASSERT_EQ(dead.size(), beam.strong ? 16u : 4u);  // ATLAS's detector channels a beam
    for (const double d : dead) EXPECT_DOUBLE_EQ(d, 3.2e-9);
    EXPECT_EQ(read<double>(file, cal + "dead_time" + g + "/sigma", H5T_NATIVE_DOUBLE).size(),
              dead.size());
    for (const char* name : {"dead_time", "strength", "width", "ffb_corr"})
      EXPECT_TRUE(has_type(file, cal + "first_photon_bias" + g + "/" + name, H5T_IEEE_F64LE))
          << name;
  }
  // orbit_info/ as a real granule has it (the ATL03 data dictionary's dtypes).
  EXPECT_TRUE(has_type(file, "/orbit_info/sc_orient", H5T_STD_I8LE));
  EXPECT_EQ(read<std::int8_t>(file, "/orbit_info/sc_orient", H5T_NATIVE_INT8),
            std::vector<std::int8_t>{1});
  EXPECT_TRUE(has_type(file, "/orbit_info/orbit_number", H5T_STD_U16LE));
  EXPECT_EQ(fill_value<std::uint16_t>(file, "/orbit_info/orbit_number", H5T_NATIVE_UINT16),
            std::optional<std::uint16_t>{65535});
  EXPECT_TRUE(has_type(file, "/orbit_info/rgt", H5T_STD_I16LE));
  EXPECT_TRUE(has_type(file, "/orbit_info/cycle_number", H5T_STD_I8LE));
  for (const char* name : {"sc_orient_time", "crossing_time", "lan"})
    EXPECT_TRUE(has_type(file, std::string("/orbit_info/") + name, H5T_IEEE_F64LE)) << name;
  // read_granule's ancillary_keys, in its order, each a one-element array.
  for (const char* key : {"atlas_sdp_gps_epoch",
                          "data_end_utc",
                          "data_start_utc",
                          "end_cycle",
                          "end_geoseg",
                          "end_gpssow",
                          "end_gpsweek",
                          "end_orbit",
                          "end_region",
                          "end_rgt",
                          "granule_end_utc",
                          "granule_start_utc",
                          "release",
                          "start_cycle",
                          "start_geoseg",
                          "start_gpssow",
                          "start_gpsweek",
                          "start_orbit",
                          "start_region",
                          "start_rgt",
                          "version"}) {
    const std::string path = std::string("/ancillary_data/") + key;
    ASSERT_GT(H5Lexists(file, path.c_str(), H5P_DEFAULT), 0) << key;
    const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
    const hid_t space = H5Dget_space(set);
    EXPECT_EQ(H5Sget_simple_extent_ndims(space), 1) << key << ": h5py's [:] needs an array";
    EXPECT_EQ(H5Sget_simple_extent_npoints(space), 1) << key;
    H5Sclose(space);
    H5Dclose(set);
  }
  // The first shot's GPS week and seconds of week, from the ATLAS epoch's GPS seconds.
  const double gps_s = 1198800018.0 + 2.5e8;
  EXPECT_EQ(read<std::int32_t>(file, "/ancillary_data/start_gpsweek", H5T_NATIVE_INT32)[0],
            static_cast<std::int32_t>(gps_s / 604800.0));
  EXPECT_NEAR(read<double>(file, "/ancillary_data/start_gpssow", H5T_NATIVE_DOUBLE)[0],
              gps_s - 604800.0 * std::floor(gps_s / 604800.0), 1e-6);
  EXPECT_EQ(read<std::int32_t>(file, "/ancillary_data/start_geoseg", H5T_NATIVE_INT32)[0], 1);
  EXPECT_EQ(read<std::int32_t>(file, "/ancillary_data/end_geoseg", H5T_NATIVE_INT32)[0], 50);
  EXPECT_EQ(fill_value<std::int32_t>(file, "/ancillary_data/start_rgt", H5T_NATIVE_INT32),
            std::optional<std::int32_t>{2147483647});
  // ancillary_data/tep/: the TEP to use for each spot, the primary TEP's range.
  EXPECT_EQ(read<std::int8_t>(file, "/ancillary_data/tep/tep_valid_spot", H5T_NATIVE_INT8).size(),
            6u);
  EXPECT_EQ(read<double>(file, "/ancillary_data/tep/tep_range_prim", H5T_NATIVE_DOUBLE).size(), 2u);
  // The impulse response: the pulse, normalised, over 6 ns from its first sample.
  for (const char* pce : {"pce1_spot1", "pce2_spot3"}) {
    const std::string t = std::string("/atlas_impulse_response/") + pce + "/tep_histogram/";
    const auto hist = read<double>(file, t + "tep_hist", H5T_NATIVE_DOUBLE);
    const auto time = read<double>(file, t + "tep_hist_time", H5T_NATIVE_DOUBLE);
    ASSERT_EQ(hist.size(), 61u);
    ASSERT_EQ(time.size(), 61u);
    EXPECT_NEAR(std::accumulate(hist.begin(), hist.end(), 0.0), 1.0, 1e-12);
    EXPECT_NEAR(time.back() - time.front(), 6e-9, 1e-15);
    EXPECT_EQ(std::max_element(hist.begin(), hist.end()) - hist.begin(), 30);
    EXPECT_EQ(read<double>(file, t + "tep_tod", H5T_NATIVE_DOUBLE).size(), 1u);
  }
  H5Fclose(file);
}

// The ATL03 attributes as the data dictionary gives them (a real granule's heights/h_ph:
// coordinates "delta_time lat_ph lon_ph"): units "counts" on the photon index and count,
// "1" on signal_conf_ph; _FillValue on ph_index_beg (0, an empty segment's), segment_ph_cnt,
// sigma_h and geophys_corr/dem_h.
TEST(Icesat2Granules, Atl03AttributesAsTheDataDictionaryGivesThem) {
  const test_support::ScratchDir dir("icesat2_atl03_attributes");
  const std::vector<BeamTrack> beams = {synthetic_beam("gt2l", 13)};
  write_atl03(dir.path() / "atl03.h5", beams, classify_beams(beams, Atl08Settings{}),
              granule_info("h"));
  const hid_t file = H5Fopen((dir.path() / "atl03.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const std::string h = "/gt2l/heights/", geo = "/gt2l/geolocation/";
  for (const char* name :
       {"h_ph", "dist_ph_along", "dist_ph_across", "quality_ph", "signal_conf_ph"})
    EXPECT_EQ(text_attribute(file, h + name, "coordinates"), "delta_time lat_ph lon_ph") << name;
  EXPECT_EQ(text_attribute(file, h + "lat_ph", "coordinates"), "delta_time lon_ph");
  EXPECT_EQ(text_attribute(file, h + "lon_ph", "coordinates"), "delta_time lat_ph");
  EXPECT_EQ(text_attribute(file, h + "delta_time", "coordinates"), "lat_ph lon_ph");
  for (const char* name : {"segment_id", "ph_index_beg", "segment_ph_cnt", "sigma_h"})
    EXPECT_EQ(text_attribute(file, geo + name, "coordinates"),
              "delta_time reference_photon_lat reference_photon_lon")
        << name;
  EXPECT_EQ(text_attribute(file, geo + "ph_index_beg", "units"), "counts");
  EXPECT_EQ(text_attribute(file, geo + "segment_ph_cnt", "units"), "counts");
  EXPECT_EQ(text_attribute(file, geo + "reference_photon_index", "units"), "counts");
  EXPECT_EQ(text_attribute(file, h + "signal_conf_ph", "units"), "1");
  EXPECT_EQ(fill_value<std::int64_t>(file, geo + "ph_index_beg", H5T_NATIVE_INT64),
            std::optional<std::int64_t>{0});
  EXPECT_EQ(fill_value<std::int32_t>(file, geo + "segment_ph_cnt", H5T_NATIVE_INT32),
            std::optional<std::int32_t>{2147483647});
  for (const char* path : {"/gt2l/geolocation/sigma_h", "/gt2l/geophys_corr/dem_h"})
    EXPECT_EQ(fill_value<float>(file, path, H5T_NATIVE_FLOAT), std::optional<float>{3.4028235e+38f})
        << path;
  // Backward: the beam group says so, and so does orbit_info.
  EXPECT_EQ(text_attribute(file, "/gt2l", "sc_orientation"), "Backward");
  EXPECT_EQ(read<std::int8_t>(file, "/orbit_info/sc_orient", H5T_NATIVE_INT8),
            std::vector<std::int8_t>{0});
  H5Fclose(file);
}

// ATL08 as ICESat2VegR's ATL08_seg_attributes_dt asks for it: land_segments/night_flag int32,
// terrain/{h_te_mode, h_te_std}, canopy/{toc_roughness, segment_cover, canopy_rh_conf}. h_te_std
// against the cloud's truth: ground photons 0.15 m RMS about a 0.05 slope over 100 m have a
// standard deviation of sqrt(0.15^2 + (0.05 * 100)^2 / 12) = 1.451 m.
TEST(Icesat2Granules, Atl08HasTheSegmentFieldsIcesat2VegRReads) {
  const test_support::ScratchDir dir("icesat2_atl08_vegr");
  const std::vector<BeamTrack> beams = {synthetic_beam("gt2l", 14)};
  const Atl08Settings settings;
  write_atl08(dir.path() / "atl08.h5", beams, classify_beams(beams, settings), settings,
              granule_info("h"));
  const hid_t file = H5Fopen((dir.path() / "atl08.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  const std::string g = "/gt2l/land_segments/";
  EXPECT_TRUE(has_type(file, g + "night_flag", H5T_STD_I32LE));
  for (const char* name : {"terrain/h_te_mode", "terrain/h_te_std", "canopy/toc_roughness"})
    EXPECT_TRUE(has_type(file, g + name, H5T_IEEE_F32LE)) << name;
  EXPECT_TRUE(has_type(file, g + "canopy/segment_cover", H5T_STD_I16LE));
  EXPECT_TRUE(has_type(file, g + "canopy/canopy_rh_conf", H5T_STD_I8LE));
  // int8 (segments), as real ATL08's (issue 38), not segments x 3.
  EXPECT_EQ(read<std::int8_t>(file, g + "canopy/canopy_rh_conf", H5T_NATIVE_INT8).size(), 10u);
  const auto std_h = read<float>(file, g + "terrain/h_te_std", H5T_NATIVE_FLOAT);
  ASSERT_EQ(std_h.size(), 10u);
  // Against the photons drawn on the ground in each segment (the classification keeps about 95 %
  // of them, Atl08Classification above), and against the formula to three times the sampling
  // spread of a standard deviation of about 450 photons (1.45 / sqrt(2 * 450) = 0.05 m).
  std::vector<std::vector<double>> ground(10);
  for (const BeamShot& shot : beams[0].shots)
    for (std::uint32_t i = 0; i < shot.photon_count; ++i)
      if (beams[0].photons[shot.first_photon + i].truth_class == 1)
        ground[static_cast<std::size_t>(shot.along_m / 100.0)].push_back(
            beams[0].photons[shot.first_photon + i].h_m);
  const double expected = std::sqrt(0.15 * 0.15 + 25.0 / 12.0);
  for (std::size_t k = 0; k < 10; ++k) {
    const std::vector<double>& h = ground[k];
    const double mean = std::accumulate(h.begin(), h.end(), 0.0) / h.size();
    double sum2 = 0.0;
    for (const double x : h) sum2 += (x - mean) * (x - mean);
    EXPECT_NEAR(std_h[k], std::sqrt(sum2 / (h.size() - 1.0)), 0.05) << k;
    EXPECT_NEAR(std_h[k], expected, 0.15) << k;
  }
  // The forest's 70 % cover in the segments wholly inside it (300-700 m), none outside.
  const auto cover = read<std::int16_t>(file, g + "canopy/segment_cover", H5T_NATIVE_INT16);
  ASSERT_EQ(cover.size(), 10u);
  EXPECT_EQ(cover[4], 70);
  EXPECT_EQ(cover[0], 0);
  // Top-of-canopy roughness in the forest: a finite spread of a few metres, fill outside.
  const auto roughness = read<float>(file, g + "canopy/toc_roughness", H5T_NATIVE_FLOAT);
  EXPECT_GT(roughness[4], 0.0f);
  EXPECT_LT(roughness[4], 10.0f);
  EXPECT_EQ(roughness[0], 3.4028235e+38f);
  H5Fclose(file);
}

}  // namespace
}  // namespace glaswave
