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
#include <numeric>
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

TEST(Icesat2Granules, Atl03HasItsPathsAndOneBasedSegmentRanges) {
  const test_support::ScratchDir dir("icesat2_atl03");
  const std::vector<BeamTrack> beams = {synthetic_beam("gt1l", 5), synthetic_beam("gt1r", 6)};
  const std::vector<Atl08Classes> classes = classify_beams(beams, Atl08Settings{});
  write_atl03(dir.path() / "atl03.h5", beams, classes, {"glaswave run test", "{}"});
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
  write_atl08(dir.path() / "a.h5", beams, classes, settings, {"h", "{}"});
  write_atl08(dir.path() / "b.h5", beams, classify_beams(beams, settings), settings, {"h", "{}"});
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
              {"h", "{}"});
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

}  // namespace
}  // namespace glaswave
