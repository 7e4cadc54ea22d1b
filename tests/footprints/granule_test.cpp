// Granule tracks: one shot per footprint of a GEDI L2A or GLAH14 granule, at its position, with
// its shot number and time.
#include "footprints/granule.hpp"

#include <gtest/gtest.h>

#include <fstream>

#include "core/error.hpp"
#include "footprints/glas_time.hpp"
#include "footprints/track.hpp"
#include "tests/footprints/granule_files.hpp"
#include "tests/footprints/test_terrains.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using testing::LevelTerrain;

TrackSettings granule_track(const std::filesystem::path& file,
                            std::vector<std::string> beams = {}) {
  TrackSettings t;
  t.type = TrackType::granule;
  t.granule = file.string();
  t.beams = std::move(beams);
  t.altitude_m = 420000.0;
  return t;
}

// The input error that `f` throws, whose place names `place`.
template <typename F>
std::string input_error_of(F f, const std::string& place) {
  try {
    f();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input) << e.what();
    EXPECT_NE(e.place().find(place), std::string::npos) << e.place() << " | " << e.what();
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

TEST(GranuleTrack, GediL2aGivesOneShotPerFootprintAtItsPositionNumberAndTime) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "GEDI02_A_small.h5";
  testing::write_gedi_l2a(file);
  const LevelTerrain terrain(120.0);
  const Track track(granule_track(file), terrain);
  ASSERT_EQ(track.size(), 5);  // 3 + 3 footprints, one with a fill position skipped
  const double gedi_epoch_s = parse_iso8601_utc("2018-01-01T00:00:00Z");
  EXPECT_DOUBLE_EQ(gedi_epoch_s, 568036800.0);
  struct Expected {
    std::int64_t number;
    double lat, lon, delta_time;
  };
  const Expected expected[] = {{11110101000001LL, 34.30, -118.20, 100.0},
                               {11110101000003LL, 34.30050, -118.19990, 100.0166},
                               {11111011000001LL, 34.31, -118.21, 200.0},
                               {11111011000002LL, 34.31050, -118.20990, 200.0083},
                               {11111011000003LL, 34.31100, -118.20980, 200.0166}};
  for (std::int64_t i = 0; i < track.size(); ++i) {
    const Footprint f = track.footprint(i);
    const Expected& e = expected[i];
    EXPECT_EQ(f.shot_number, i);
    EXPECT_EQ(f.source_shot_number, e.number);
    EXPECT_DOUBLE_EQ(f.time_s, gedi_epoch_s + e.delta_time);
    ASSERT_TRUE(f.on_terrain);
    EXPECT_NEAR(f.ground.lat_deg, e.lat, 1e-6);
    EXPECT_NEAR(f.ground.lon_deg, e.lon, 1e-6);
    EXPECT_NEAR(f.ground.h_m, 120.0, 1e-3);
    EXPECT_NEAR(f.spacecraft.h_m, 420000.0, 1e-3);
    EXPECT_NEAR(f.off_nadir_deg, 0.0, 1e-9);
  }
}

TEST(GranuleTrack, BeamsSelectTheGroupsInTheirOrder) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "GEDI02_A_small.h5";
  testing::write_gedi_l2a(file);
  const LevelTerrain terrain;
  const Track only(granule_track(file, {"BEAM1011"}), terrain);
  ASSERT_EQ(only.size(), 3);
  EXPECT_EQ(only.footprint(0).source_shot_number, 11111011000001LL);
  const auto both = read_granule(file, {"BEAM1011", "BEAM0101"});
  ASSERT_EQ(both.size(), 5u);
  EXPECT_EQ(both[0].shot_number, 11111011000001LL);
  EXPECT_EQ(both[3].shot_number, 11110101000001LL);
}

TEST(GranuleTrack, Glah14GivesOneShotPerFootprintNumberedByRecord) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "GLAH14_small.H5";
  testing::write_glah14(file);
  const LevelTerrain terrain(-30.0);
  const Track track(granule_track(file), terrain);
  ASSERT_EQ(track.size(), 4);  // the fourth footprint's fill position skipped
  const std::int64_t numbers[] = {5000 * 40, 5000 * 40 + 1, 5001 * 40, 5001 * 40 + 2};
  const double lat[] = {34.30, 34.3015, 34.3030, 34.3060};
  const double lon[] = {241.80, 241.8002, 241.8004, 241.8008};
  const double time[] = {181000000.0, 181000000.025, 181000000.050, 181000000.100};
  for (std::int64_t i = 0; i < track.size(); ++i) {
    const Footprint f = track.footprint(i);
    EXPECT_EQ(f.shot_number, i);
    EXPECT_EQ(f.source_shot_number, numbers[i]);
    EXPECT_DOUBLE_EQ(f.time_s, time[i]);  // d_UTCTime_40 is already on the GLAS epoch
    ASSERT_TRUE(f.on_terrain);
    EXPECT_NEAR(f.ground.lat_deg, lat[i], 1e-6);
    EXPECT_NEAR(f.ground.lon_deg, lon[i] - 360.0, 1e-6);
    EXPECT_NEAR(f.ground.h_m, -30.0, 1e-3);
  }
  EXPECT_EQ(read_granule(file, {"Data_40HZ"}).size(), 4u);
}

TEST(GranuleTrack, FaultsAreInputErrorsNamingTheFileAndGroup) {
  test_support::ScratchDir dir;
  const auto gedi = dir.path() / "gedi.h5";
  const auto glah14 = dir.path() / "glah14.h5";
  testing::write_gedi_l2a(gedi);
  testing::write_glah14(glah14);
  const std::string missing = (dir.path() / "missing.h5").string();
  input_error_of([&] { read_granule(missing, {}); }, missing);

  const auto text = dir.path() / "not.h5";
  std::ofstream(text) << "not HDF5\n";
  input_error_of([&] { read_granule(text, {}); }, text.string());

  const auto other = dir.path() / "other.h5";
  {
    testing::Hdf5Writer h5(other);
    h5.doubles("science/lat", {1.0});
  }
  const std::string neither = input_error_of([&] { read_granule(other, {}); }, other.string());
  EXPECT_NE(neither.find("neither"), std::string::npos) << neither;

  const std::string beam =
      input_error_of([&] { read_granule(gedi, {"BEAM0110"}); }, gedi.string() + ": BEAM0110");
  EXPECT_NE(beam.find("no such beam"), std::string::npos) << beam;
  input_error_of([&] { read_granule(glah14, {"BEAM0101"}); }, glah14.string() + ": BEAM0101");

  const auto broken = dir.path() / "broken.h5";
  {
    testing::Hdf5Writer h5(broken);
    h5.doubles("BEAM0000/lat_lowestmode", {1.0});
    h5.doubles("BEAM0000/lon_lowestmode", {1.0});
  }
  const std::string absent =
      input_error_of([&] { read_granule(broken, {}); }, broken.string() + ": BEAM0000");
  EXPECT_NE(absent.find("shot_number"), std::string::npos) << absent;

  const LevelTerrain terrain;
  input_error_of([&] { Track(granule_track(missing), terrain); }, missing);
}

}  // namespace
}  // namespace glaswave
