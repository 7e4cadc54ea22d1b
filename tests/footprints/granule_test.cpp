// Granule tracks: one shot per footprint of a GEDI L2A or GLAH14 granule, at its position, with
// its shot number and time.
#include "footprints/granule.hpp"

#include <gtest/gtest.h>
#include <pthread.h>

#include <atomic>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>

#include "core/error.hpp"
#include "core/glas_time.hpp"
#include "footprints/track.hpp"
#include "tests/cpu_time.hpp"
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
    // Both are full-power beams: the sensor's pulse energy as it is.
    EXPECT_EQ(f.beam, i < 2 ? 5 : 11);
    EXPECT_DOUBLE_EQ(f.pulse_energy_scale, 1.0);
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

// A record missing its first shots keeps its shots' true numbers: i_rec_ndx * 40 +
// i_shot_count - 1, not their places in the file.
TEST(GranuleTrack, Glah14GivesOneShotPerFootprintNumberedByRecordAndShotCount) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "GLAH14_small.H5";
  testing::write_glah14(file);
  const LevelTerrain terrain(-30.0);
  const Track track(granule_track(file), terrain);
  ASSERT_EQ(track.size(), 4);  // the fourth footprint's fill position skipped
  const std::int64_t numbers[] = {5000 * 40 + 38, 5000 * 40 + 39, 5001 * 40, 5001 * 40 + 2};
  const std::int64_t records[] = {5000, 5000, 5001, 5001};
  const int counts[] = {39, 40, 1, 3};
  const double lat[] = {34.30, 34.3015, 34.3030, 34.3060};
  ASSERT_EQ(track.warnings().size(), 1u);
  EXPECT_NE(track.warnings()[0].find("1 footprints with a fill latitude"), std::string::npos)
      << track.warnings()[0];
  EXPECT_NE(track.warnings()[0].find("i_rec_ndx 5001 i_shot_count 2"), std::string::npos)
      << track.warnings()[0];
  const double lon[] = {241.80, 241.8002, 241.8004, 241.8008};
  const double time[] = {181000000.0, 181000000.025, 181000000.050, 181000000.100};
  for (std::int64_t i = 0; i < track.size(); ++i) {
    const Footprint f = track.footprint(i);
    EXPECT_EQ(f.shot_number, i);
    EXPECT_EQ(f.source_shot_number, numbers[i]);
    EXPECT_EQ(f.record_index, records[i]);
    EXPECT_EQ(f.shot_count, counts[i]);
    EXPECT_EQ(f.beam, -1);
    EXPECT_DOUBLE_EQ(f.pulse_energy_scale, 1.0);
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

// Issue 28: integers read exactly or refused, sizes checked before allocating, no shot lost or
// doubled without a word.
TEST(GranuleTrack, IntegersSizesAndBeamsAreCheckedNotReinterpreted) {
  test_support::ScratchDir dir;
  auto gedi_with = [&](const std::string& name, auto write_numbers) {
    const auto file = dir.path() / name;
    testing::Hdf5Writer h5(file);
    write_numbers(h5);
    h5.doubles("BEAM0000/lat_lowestmode", {1.0});
    h5.doubles("BEAM0000/lon_lowestmode", {1.0});
    h5.doubles("BEAM0000/delta_time", {1.0});
    return file;
  };
  // A uint64 shot number above 2^63 - 1 would come out negative.
  const auto huge = gedi_with("huge.h5", [](testing::Hdf5Writer& h5) {
    h5.uint64s("BEAM0000/shot_number", {(1ULL << 63) + 5});
  });
  std::string message = input_error_of([&] { read_granule(huge, {}); }, "huge.h5: BEAM0000");
  EXPECT_NE(message.find("9223372036854775813"), std::string::npos) << message;
  // Shot numbers stored as floating point would be truncated.
  const auto floats = gedi_with(
      "floats.h5", [](testing::Hdf5Writer& h5) { h5.doubles("BEAM0000/shot_number", {12.5}); });
  message = input_error_of([&] { read_granule(floats, {}); }, "floats.h5: BEAM0000");
  EXPECT_NE(message.find("floating point"), std::string::npos) << message;
  // A signed shot number below 0.
  const auto negative = gedi_with(
      "negative.h5", [](testing::Hdf5Writer& h5) { h5.int64s("BEAM0000/shot_number", {-3}); });
  input_error_of([&] { read_granule(negative, {}); }, "negative.h5: BEAM0000");
  // The largest exact number comes through.
  const auto largest = gedi_with("largest.h5", [](testing::Hdf5Writer& h5) {
    h5.uint64s("BEAM0000/shot_number", {(1ULL << 63) - 1});
  });
  EXPECT_EQ(read_granule(largest, {})[0].shot_number, std::numeric_limits<std::int64_t>::max());

  // i_rec_ndx * 40 would overflow; i_shot_count outside 1..40.
  auto glah14_with = [&](const std::string& name, std::int64_t record, std::int32_t count) {
    const auto file = dir.path() / name;
    testing::Hdf5Writer h5(file);
    h5.doubles("Data_40HZ/Geolocation/d_lat", {1.0});
    h5.doubles("Data_40HZ/Geolocation/d_lon", {1.0});
    h5.doubles("Data_40HZ/Time/d_UTCTime_40", {1.0});
    h5.int64s("Data_40HZ/Time/i_rec_ndx", {record});
    h5.int32s("Data_40HZ/Time/i_shot_count", {count});
    return file;
  };
  message = input_error_of(
      [&] { read_granule(glah14_with("overflow.h5", std::int64_t{1} << 62, 1), {}); },
      "overflow.h5: Data_40HZ");
  EXPECT_NE(message.find("i_rec_ndx"), std::string::npos) << message;
  message = input_error_of([&] { read_granule(glah14_with("count.h5", 7, 41), {}); },
                           "count.h5: Data_40HZ");
  EXPECT_NE(message.find("i_shot_count"), std::string::npos) << message;
  EXPECT_EQ(read_granule(glah14_with("good.h5", 7, 40), {})[0].shot_number, 7 * 40 + 39);

  // A beam named twice would simulate its shots twice.
  const auto two = dir.path() / "two.h5";
  testing::write_gedi_l2a(two);
  message = input_error_of(
      [&] {
        read_granule(two, {"BEAM0101", "BEAM1011", "BEAM0101"});
      },
      "two.h5: BEAM0101");
  EXPECT_NE(message.find("named twice"), std::string::npos) << message;

  // 10^7 and 10^11 declared shots are refused from the declaration, at once, naming the path.
  for (const hsize_t declared : {hsize_t{10'000'000}, hsize_t{100'000'000'000}}) {
    const auto big = dir.path() / ("big" + std::to_string(declared) + ".h5");
    {
      testing::Hdf5Writer h5(big);
      h5.uint64s("BEAM0000/shot_number", {1});
      h5.declared_doubles("BEAM0000/lat_lowestmode", declared);
    }
    const double cpu_before_s = test_support::cpu_used_s();  // the reader program's with ours
    message = input_error_of([&] { read_granule(big, {}); }, big.string() + ": BEAM0000");
    EXPECT_LT(test_support::cpu_used_s() - cpu_before_s, 1.0);
    EXPECT_NE(message.find(std::to_string(declared)), std::string::npos) << message;
  }
}

// GEDI's coverage beams carry half a laser's pulse, the full-power beams a whole one; the
// beam's number is its name's digits in binary, and degrade_flag comes through.
TEST(GranuleTrack, GediBeamsCarryTheirNumberTypeAndDegradeFlag) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "beams.h5";
  {
    testing::Hdf5Writer h5(file);
    for (const std::string beam : {"BEAM0011", "BEAM0110"}) {
      h5.uint64s(beam + "/shot_number", {1, 2});
      h5.doubles(beam + "/lat_lowestmode", {1.0, 1.001});
      h5.doubles(beam + "/lon_lowestmode", {1.0, 1.0});
      h5.doubles(beam + "/delta_time", {1.0, 1.1});
      h5.uint8s(beam + "/degrade_flag", {0, 3});
    }
  }
  const LevelTerrain terrain;
  const Track track(granule_track(file), terrain);
  ASSERT_EQ(track.size(), 4);
  EXPECT_TRUE(track.warnings().empty());
  const int beams[] = {3, 3, 6, 6};
  const double scales[] = {0.5, 0.5, 1.0, 1.0};
  const std::uint8_t degrade[] = {0, 3, 0, 3};
  for (std::int64_t i = 0; i < 4; ++i) {
    const Footprint f = track.footprint(i);
    EXPECT_EQ(f.beam, beams[i]);
    EXPECT_DOUBLE_EQ(f.pulse_energy_scale, scales[i]);
    EXPECT_EQ(f.degrade_flag, degrade[i]);
  }
}

}  // namespace
}  // namespace glaswave

namespace glaswave {
namespace {

// The fuzz target's seed corpus (tests/fuzz/make_corpus.py): every `broken-*` granule, cut or
// malformed, is refused as an input error naming the file; the others are read.
TEST(GranuleTrack, TheFuzzCorpusIsReadOrRefusedAsInputErrors) {
  const std::filesystem::path corpus =
      std::filesystem::path(GLASWAVE_SOURCE_DIR) / "tests/fuzz/corpus/granule";
  int refused = 0, read = 0;
  for (const auto& entry : std::filesystem::directory_iterator(corpus)) {
    const std::string name = entry.path().filename().string();
    std::vector<std::string> warnings;
    if (name.rfind("broken-gedi-fill", 0) == 0) {  // read, with a word about the skipped shot
      EXPECT_EQ(read_granule(entry.path(), {}, &warnings).size(), 2u);
      EXPECT_EQ(warnings.size(), 1u);
      ++read;
    } else if (name.rfind("broken-", 0) == 0) {
      input_error_of([&] { read_granule(entry.path(), {}); }, entry.path().string());
      ++refused;
    } else {
      EXPECT_FALSE(read_granule(entry.path(), {}, &warnings).empty()) << name;
      EXPECT_TRUE(warnings.empty()) << name;
      ++read;
    }
  }
  EXPECT_GE(refused, 6);
  EXPECT_GE(read, 3);
}

}  // namespace
}  // namespace glaswave

namespace glaswave {
namespace {

// Issue 42: any root group whose name began with BEAM was read as a GEDI beam (BEAM2222,
// BEAMXXXX); only the L2A dictionary's eight names are beams now.
TEST(GranuleTrack, OnlyGedisEightBeamNamesAreBeams) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "beams.h5";
  {
    testing::Hdf5Writer h5(file);
    for (const char* beam : {"BEAM0101", "BEAM2222", "BEAMXXXX"}) {
      const std::string group(beam);
      h5.uint64s(group + "/shot_number", {7});
      h5.doubles(group + "/lat_lowestmode", {1.0});
      h5.doubles(group + "/lon_lowestmode", {1.0});
      h5.doubles(group + "/delta_time", {1.0});
    }
  }
  const std::vector<GranuleShot> shots = read_granule(file, {});
  ASSERT_EQ(shots.size(), 1u);
  EXPECT_EQ(shots[0].beam, 5);  // BEAM0101
  const std::string message =
      input_error_of([&] { read_granule(file, {"BEAM2222"}); }, file.string() + ": BEAM2222");
  EXPECT_NE(message.find("the 8 are BEAM0000"), std::string::npos) << message;
}

// The file HDF5 1.10.8 crashes on (its root group's symbol table of undefined addresses) is
// refused on its bytes, before HDF5 reads it.
TEST(GranuleTrack, ARootGroupOfUndefinedAddressesIsRefusedBeforeHdf5ReadsIt) {
  const std::filesystem::path crashes =
      std::filesystem::path(GLASWAVE_SOURCE_DIR) /
      "tests/fuzz/corpus/granule/broken-hdf5-crashes-h5literate.h5";
  const std::string refused = input_error_of([&] { read_granule(crashes, {}); }, crashes.string());
  EXPECT_NE(refused.find("the HDF5 file is corrupt: its root group's symbol table names an "
                         "address beyond the file's end"),
            std::string::npos)
      << refused;
}

// A library must not fork (issue 42): a fork waits in every library's fork handler, and one whose
// lock another thread holds (PROJ's) hangs it. The granule is read by a program of its own started
// with posix_spawn, which runs no fork handler: a handler counting forks sees none. Before, the
// reader forked and the count was 1.
std::atomic<int> forks{0};

TEST(GranuleTrack, TheGranuleIsReadWithoutAFork) {
  static const bool registered = pthread_atfork([] { forks.fetch_add(1); }, nullptr, nullptr) == 0;
  ASSERT_TRUE(registered);
  test_support::ScratchDir dir;
  const auto file = dir.path() / "GEDI02_A_small.h5";
  testing::write_gedi_l2a(file);
  const int before = forks.load();
  EXPECT_EQ(read_granule(file, {}).size(), 5u);
  EXPECT_EQ(forks.load() - before, 0);
}

}  // namespace
}  // namespace glaswave
