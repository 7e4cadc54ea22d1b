// `glaswave retrieve` on GLAS granules in the real layout: a hand-made GLAH01 (its waveforms,
// noise, sample-location index and ANCILLARY_DATA's table) beside a GLAH14 (d_elev, d_ldRngOff,
// d_lat, d_lon), the L2B closed form through the whole chain, and malformed granules refused with
// one line naming the file and the dataset. glaswave's own granules: retrieve_cli_test.cpp.
#include <gtest/gtest.h>
#include <netcdf.h>
#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

#include "core/hdf5_file.hpp"
#include "core/netcdf_lock.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/pipeline/retrieval/shot_variable.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using test_support::CommandOutcome;
using test_support::run_glaswave;
using test_support::ScratchDir;
namespace fs = std::filesystem;

const auto& nc_variable = test_support::shot_variable;

// GLAS's 544 samples 1 ns apart, each waveform 200 counts of noise mean under a canopy of area
// 12000 (counts x samples) 150 samples above a ground of area 8000: L2B's Pgap = 1 - 12000 /
// (12000 + 1.5 x 8000) = 0.5, cover 0.5 and, at nadir, PAI -2 ln 0.5. The ground's sample lies
// 143 samples before the last, c/2 x 143 ns above d_elev + d_ldRngOff: at 100 m.
constexpr int kSamples = 544, kGroundSample = 400;
constexpr double kGroundElevation = 100.0, kHalfC_m_per_ns = 0.149896229;
constexpr double kCentroid = 110.0;  // d_elev: any elevation; d_ldRngOff places the samples

struct GlasFiles {
  bool compressed_row = false;   // the shots use the table's second, uneven row
  bool short_waveforms = false;  // r_rng_wf has a row fewer than the shots
  bool no_land_offset = false;   // GLAH14 without d_ldRngOff
  bool shot_count_41 = false;    // a shot numbered past a record's 40
  bool no_table = false;         // no ANCILLARY_DATA table
  bool fill_rows = false;        // every shot's row index GLAS's fill, 127: no sample times
};

// Three shots: records 1000 (shots 1 and 2) and 1001 (shot 40), numbers 40000, 40001 and 40079;
// GLAH14 holds the first two only.
void write_glas(const fs::path& glah01, const fs::path& glah14, const GlasFiles& spec) {
  std::lock_guard lock(netcdf_library_mutex());
  const std::string d = "Data_40HZ/";
  {
    Hdf5Writer f(glah01);
    const std::size_t n = 3, rows = spec.short_waveforms ? n - 1 : n;
    std::vector<float> rx;
    for (std::size_t i = 0; i < rows; ++i)
      for (int k = 0; k < kSamples; ++k) {
        const auto gauss = [&](double area, double mu, double sigma) {
          return area / (sigma * std::sqrt(2 * std::numbers::pi)) *
                 std::exp(-0.5 * std::pow((k - mu) / sigma, 2));
        };
        rx.push_back(static_cast<float>(200.0 + gauss(12000.0, kGroundSample - 150, 8.0) +
                                        gauss(8000.0, kGroundSample, 6.0)));
      }
    f.write(d + "Time/i_rec_ndx", std::vector<std::int32_t>{1000, 1000, 1001});
    f.write(
        d + "Time/i_shot_count",
        std::vector<std::int16_t>{1, 2, static_cast<std::int16_t>(spec.shot_count_41 ? 41 : 40)});
    f.write(d + "Waveform/RecWaveform/r_rng_wf", rx, {},
            {rows, static_cast<std::uint64_t>(kSamples)});
    f.write(d + "Waveform/Characteristics/d_4nsBgMean", std::vector<double>(n, 200.0));
    f.write(d + "Waveform/Characteristics/d_4nsBgSDEV", std::vector<double>(n, 2.0));
    f.write(d + "Waveform/RecWaveform/i_rec_wf_location_index",
            std::vector<std::int8_t>(n, spec.fill_rows        ? 127
                                        : spec.compressed_row ? 2
                                                              : 1));
    if (!spec.no_table) {
      // Row 1: 1 ns apart, ending at 0; row 2: 4 ns apart over the first samples (compressed).
      std::vector<double> table;
      for (int k = 0; k < kSamples; ++k) table.push_back(k - (kSamples - 1.0));
      for (int k = 0; k < kSamples; ++k)
        table.push_back(k < 100 ? 4.0 * k - 4.0 * 99 - (kSamples - 100.0) : k - (kSamples - 1.0));
      f.group("ANCILLARY_DATA");
      f.double_array_attribute("ANCILLARY_DATA", "rec_wf_sample_location_table", table,
                               {2, static_cast<std::uint64_t>(kSamples)});
    }
    f.close();
  }
  Hdf5Writer f(glah14);
  f.write(d + "Time/i_rec_ndx", std::vector<std::int32_t>{1000, 1000});
  f.write(d + "Time/i_shot_count", std::vector<std::int16_t>{1, 2});
  f.write(d + "Geolocation/d_lat", std::vector<double>(2, 1.0));
  f.write(d + "Geolocation/d_lon", std::vector<double>(2, 358.0));
  f.write(d + "Elevation_Surfaces/d_elev", std::vector<double>(2, kCentroid));
  const double last = kGroundElevation - (kSamples - 1 - kGroundSample) * kHalfC_m_per_ns;
  if (!spec.no_land_offset)
    f.write(d + "Elevation_Offsets/d_ldRngOff", std::vector<double>(2, last - kCentroid));
  f.write(d + "Elevation_Surfaces/d_refRng", std::vector<double>(2, 600000.0));
  f.close();
}

TEST(RetrieveGlas, RealLayoutGlah01BesideItsGlah14GivesTheClosedForm) {
  const ScratchDir dir("glaswave_retrieve_glas_real");
  const fs::path glah01 = dir.path() / "GLAH01_033_minimal.H5";
  const fs::path glah14 = dir.path() / "GLAH14_634_minimal.H5";
  write_glas(glah01, glah14, {});
  const fs::path out = dir.path() / "out";
  const CommandOutcome retrieved = run_glaswave("retrieve " + glah01.string() + " " +
                                                glah14.string() + " --quiet --out " + out.string());
  ASSERT_EQ(retrieved.status, 0) << retrieved.output;
  EXPECT_FALSE(fs::exists(out / "gedi_l2b.h5"));  // GEDI L1B input only
  const fs::path nc = out / "retrieval.nc";
  EXPECT_EQ(nc_variable(nc, "shot_number"), (std::vector<double>{40000, 40001, 40079}));
  const std::vector<double> cover = nc_variable(nc, "cover_gedi_l2b");
  const std::vector<double> pai = nc_variable(nc, "pai_gedi_l2b");
  const std::vector<double> ground = nc_variable(nc, "ground_elevation_gedi_l2a");
  const std::vector<double> lon = nc_variable(nc, "lon");
  ASSERT_EQ(cover.size(), 3u);
  for (int i = 0; i < 2; ++i) {
    EXPECT_NEAR(cover[i], 0.5, 0.01) << i;
    EXPECT_NEAR(pai[i], -2.0 * std::log(0.5), 0.04) << i;
    EXPECT_NEAR(ground[i], kGroundElevation, 0.05) << i;
    EXPECT_EQ(lon[i], -2.0) << i;  // GLAS's 358 east
  }
  // The shot GLAH14 does not hold cannot be placed: kept, with no estimates.
  EXPECT_TRUE(std::isnan(cover[2]));
  EXPECT_TRUE(std::isnan(ground[2]));
  // No truth in a real granule.
  EXPECT_TRUE(nc_variable(nc, "cover_true").empty());
  // Shots whose sample-location row is fill have no sample times: kept, with no estimates.
  GlasFiles rowless;
  rowless.fill_rows = true;
  write_glas(glah01, glah14, rowless);
  const CommandOutcome kept = run_glaswave("retrieve " + glah01.string() + " " + glah14.string() +
                                           " --quiet --out " + (dir.path() / "rowless").string());
  ASSERT_EQ(kept.status, 0) << kept.output;
  const std::vector<double> no_cover =
      nc_variable(dir.path() / "rowless" / "retrieval.nc", "cover_gedi_l2b");
  ASSERT_EQ(no_cover.size(), 3u);
  for (double c : no_cover) EXPECT_TRUE(std::isnan(c));
}

// Each defect refused with status 3, one line naming the file and the dataset, nothing written.
TEST(RetrieveGlas, MalformedGranulesAreRefusedInOneLine) {
  const ScratchDir dir("glaswave_retrieve_glas_malformed");
  struct Case {
    const char* name;
    GlasFiles spec;
    const char* dataset;
    bool in_glah14;
  };
  GlasFiles compressed, short_rx, no_offset, count_41, no_table;
  compressed.compressed_row = true;
  short_rx.short_waveforms = true;
  no_offset.no_land_offset = true;
  count_41.shot_count_41 = true;
  no_table.no_table = true;
  const std::vector<Case> cases = {
      {"compressed", compressed, "rec_wf_sample_location_table", false},
      {"short", short_rx, "Data_40HZ/Waveform/RecWaveform/r_rng_wf", false},
      {"no_offset", no_offset, "Data_40HZ/Elevation_Offsets/d_ldRngOff", true},
      {"count_41", count_41, "Data_40HZ/Time/i_shot_count", false},
      {"no_table", no_table, "rec_wf_sample_location_table", false},
  };
  for (const Case& c : cases) {
    const fs::path glah01 = dir.path() / (std::string(c.name) + "_01.h5");
    const fs::path glah14 = dir.path() / (std::string(c.name) + "_14.h5");
    write_glas(glah01, glah14, c.spec);
    const fs::path out = dir.path() / c.name;
    const CommandOutcome refused = run_glaswave("retrieve " + glah01.string() + " " +
                                                glah14.string() + " --quiet --out " + out.string());
    EXPECT_EQ(refused.status, 3) << c.name << ": " << refused.output;
    EXPECT_NE(refused.output.find((c.in_glah14 ? glah14 : glah01).string()), std::string::npos)
        << c.name << ": " << refused.output;
    EXPECT_NE(refused.output.find(c.dataset), std::string::npos)
        << c.name << ": " << refused.output;
    EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;
    EXPECT_FALSE(fs::exists(out / "retrieval.nc")) << c.name;
  }
}

// A GLAH01 whose i_shot_count declares an integer of 1,951,616,514 bytes (found by fuzzing): HDF5
// would convert each value through a buffer that size (1.95 GB of memory held, then "cannot be
// read"). The one HDF5 layer takes no number of more than 16 bytes for numeric, so the file is
// refused at once, without the memory.
TEST(RetrieveGlas, ANumberOfTwoGigabytesIsRefusedUnread) {
  const ScratchDir dir("glaswave_retrieve_glas_huge_type");
  const fs::path corpus = fs::path(GLASWAVE_SOURCE_DIR) / "tests/fuzz/corpus/retrieval";
  const CommandOutcome refused =
      run_glaswave("retrieve " + (corpus / "regression-hdf5-type-of-2e9-bytes.h5").string() + " " +
                   (corpus / "glah14.h5").string() + " --quiet --out " + dir.path().string());
  EXPECT_EQ(refused.status, 3) << refused.output;
  EXPECT_NE(refused.output.find("Data_40HZ/Time/i_shot_count: not numeric"), std::string::npos)
      << refused.output;
  rusage children{};
  getrusage(RUSAGE_CHILDREN, &children);
  EXPECT_LT(children.ru_maxrss, 500 * 1024) << "kB";  // the largest child's peak
}

// A GLAH01 on which HDF5 1.10.8 allocates without end (a group's local heap, found by fuzzing:
// 24 GB and 95 s in glaswave's own process before): read first by glaswave-read-retrieval-input,
// which the kernel ends at its CPU budget, it is refused in one line, its memory bounded by that
// budget.
TEST(RetrieveGlas, AGranuleOnWhichHdf5AllocatesWithoutEndIsRefusedAtTheReadersBudget) {
  const ScratchDir dir("glaswave_retrieve_glas_endless");
  const fs::path corpus = fs::path(GLASWAVE_SOURCE_DIR) / "tests/fuzz/corpus/retrieval";
  const CommandOutcome refused = run_glaswave(
      "retrieve " + (corpus / "regression-hdf5-local-heap-allocates-without-end.h5").string() +
      " " + (corpus / "glah14.h5").string() + " --quiet --out " + dir.path().string());
  EXPECT_EQ(refused.status, 3) << refused.output;
  EXPECT_NE(refused.output.find("glaswave-read-retrieval-input, past its CPU budget"),
            std::string::npos)
      << refused.output;
  EXPECT_EQ(std::count(refused.output.begin(), refused.output.end(), '\n'), 1) << refused.output;
  rusage children{};
  getrusage(RUSAGE_CHILDREN, &children);
  EXPECT_LT(children.ru_maxrss, 4L * 1024 * 1024) << "kB";  // the reader's peak, of any child
  EXPECT_FALSE(fs::exists(dir.path() / "retrieval.nc"));
}

}  // namespace
}  // namespace glaswave
