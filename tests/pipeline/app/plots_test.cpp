// Tests of write_plots: a tiny product (three shots, one flagged) written with the product
// writers into a temporary folder, drawn by share/plots/plot_products.py, and the three PNGs
// checked for existence, signature and size; the footprint map over a hillshade of a DEM the
// test writes with GDAL, and the plain map when that DEM is gone; and the script's failure on a
// folder without shots.nc turned into an Error. Missing matplotlib fails the test (scripts/setup
// installs it).
#include "pipeline/app/plots.hpp"

#include <fcntl.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <GeographicLib/UTMUPS.hpp>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "pipeline/products/netcdf_writer.hpp"
#include "pipeline/products/ogr_writer.hpp"
#include "pipeline/products/waveform_metrics.hpp"
#include "tests/scratch_dir.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr int kShots = 3;
constexpr int kBins = 120;
constexpr double kBinNs = 1.0;
constexpr double kBinM = 0.15;  // c * 1 ns / 2

RunInfo make_info(const std::string& config_json, std::vector<ProductBand> bands) {
  RunInfo info;
  info.command_line = "plots_test";
  info.config_json = config_json;
  info.seed = 1;
  info.shots = kShots;
  info.bands = std::move(bands);
  for (int b = 0; b < kBins; ++b) info.bin_time_ns.push_back(kBinNs * (b - kBins / 2));
  info.tx_time_ns = {-1.0, 0.0, 1.0};
  info.tx_waveform_W = {{1.0e6, 2.0e6, 1.0e6}, {3.0e6, 4.0e6, 3.0e6}};
  return info;
}

double gaussian(double x, double mean, double sigma) {
  return std::exp(-0.5 * (x - mean) * (x - mean) / (sigma * sigma));
}

// A canopy return above a ground return, in W, as a waveform of a few hundred nW.
ShotRecord make_shot(int record) {
  ShotRecord shot;
  shot.shot_number = 10 + record;
  shot.time_s = 183254400.0 + 0.025 * record;
  shot.lat_deg = 34.30 + 0.0015 * record;
  shot.lon_deg = -118.20 + 0.0003 * record;
  shot.elev_m = 1200.0 + 5.0 * record;
  shot.sc_lat_deg = shot.lat_deg;
  shot.sc_lon_deg = shot.lon_deg;
  shot.sc_alt_m = 600000.0;
  shot.range_m = shot.sc_alt_m - shot.elev_m;
  shot.slope_deg = 5.0;
  shot.aspect_deg = 90.0;
  shot.elev_bin0_m = shot.elev_m + kBinM * kBins / 2;
  shot.elev_lastbin_m = shot.elev_bin0_m - kBinM * (kBins - 1);
  for (int band = 0; band < 2; ++band) {
    std::vector<double> total, canopy, ground;
    for (int bin = 0; bin < kBins; ++bin) {
      const double c = 1e-7 * (band + 1) * gaussian(bin, 30.0, 6.0);
      const double g = 2e-7 * (band + 1) * gaussian(bin, kBins / 2.0, 3.0);
      canopy.push_back(c);
      ground.push_back(g);
      total.push_back(c + g);
    }
    shot.rx_waveform_W.push_back(total);
    shot.rx_waveform_canopy_W.push_back(canopy);
    shot.rx_waveform_ground_W.push_back(ground);
    shot.rx_energy_J.push_back(1e-15 * (band + 1));
    shot.rx_energy_canopy_J.push_back(0.4e-15 * (band + 1));
    shot.rx_energy_ground_J.push_back(0.6e-15 * (band + 1));
    shot.reflectance.push_back(0.1 + 0.05 * record + 0.1 * band);
  }
  // A 35 m circle, counter-clockwise and closed.
  const double lat_per_m = 1.0 / 111195.0;
  const double lon_per_m = lat_per_m / std::cos(shot.lat_deg * std::numbers::pi / 180.0);
  for (int k = 0; k < 24; ++k) {
    const double a = 2.0 * std::numbers::pi * k / 24;
    shot.footprint_lonlat.push_back({shot.lon_deg + 35.0 * std::cos(a) * lon_per_m,
                                     shot.lat_deg + 35.0 * std::sin(a) * lat_per_m});
  }
  shot.footprint_lonlat.push_back(shot.footprint_lonlat.front());
  process_shot_waveforms(shot, kBinNs, WaveformProcessing{});  // the metrics the products hold
  return shot;
}

// Off the terrain: no arrays, no footprint.
ShotRecord make_flagged_shot(int record) {
  ShotRecord shot;
  shot.shot_number = 10 + record;
  shot.time_s = 183254400.0 + 0.025 * record;
  shot.lat_deg = shot.lon_deg = shot.elev_m = std::nan("");
  shot.quality_flag = quality_invalid;
  return shot;
}

const std::vector<ProductBand> kBands = {{"532", 532.0}, {"1064", 1064.0}};

void write_products(const fs::path& dir, bool all_flagged, const std::string& config_json = "{}",
                    const std::vector<ProductBand>& bands = kBands) {
  const RunInfo info = make_info(config_json, bands);
  NetcdfWriter netcdf(dir / "shots.nc", info);
  OgrWriter geojson(dir / "footprints.geojson", FootprintsFormat::geojson, info);
  for (int i = 0; i < kShots; ++i) {
    const ShotRecord shot = all_flagged || i == 1 ? make_flagged_shot(i) : make_shot(i);
    netcdf.write(i, shot);
    geojson.write(i, shot);
  }
  netcdf.finish({});
  geojson.finish({});
}

class PlotsTest : public ::testing::Test {
 protected:
  // Each plot exists, is a PNG, and holds more than axes alone would; no .part is left.
  void expect_plots() const {
    for (const char* name : {"waveforms.png", "track_profile.png", "footprints_map.png"}) {
      SCOPED_TRACE(name);
      const fs::path path = dir_ / "plots" / name;
      ASSERT_TRUE(fs::is_regular_file(path));
      EXPECT_GT(fs::file_size(path), 5000u);
      std::ifstream in(path, std::ios::binary);
      std::array<char, 8> head{};
      in.read(head.data(), head.size());
      EXPECT_EQ(std::string(head.data(), head.size()), std::string("\x89PNG\r\n\x1a\n", 8));
    }
    for (const auto& entry : fs::directory_iterator(dir_ / "plots")) {
      EXPECT_NE(entry.path().extension(), ".part") << entry.path();
    }
  }

  test_support::ScratchDir dir_{"glaswave plots"};  // a space, as no shell must see the path
};

TEST_F(PlotsTest, WritesThreePngsOfATinyProduct) {
  write_products(dir_.path(), false);
  ASSERT_NO_THROW(write_plots(dir_.path()));
  expect_plots();
}

TEST_F(PlotsTest, DrawsAProductWhoseShotsAreAllFlagged) {
  write_products(dir_.path(), true);
  ASSERT_NO_THROW(write_plots(dir_.path()));
  expect_plots();
}

// Band names are the user's text: matplotlib's mathtext in one ($\frac{1}{$, which its parser
// refused) and 5,000 characters in the other (which failed the figure) are drawn as plain text.
TEST_F(PlotsTest, DrawsBandNamesAsPlainTextWhateverTheyHold) {
  write_products(dir_.path(), false, "{}",
                 {ProductBand{"$\\frac{1}{$", 532.0}, ProductBand{std::string(5000, 'b'), 1064.0}});
  ASSERT_NO_THROW(write_plots(dir_.path()));
  expect_plots();
}

// Hills in UTM zone 11N, 10 m cells, 2 km about the tiny product's footprints.
void write_hills(const fs::path& file) {
  int zone = 0;
  bool north = true;
  double x = 0, y = 0;
  GeographicLib::UTMUPS::Forward(34.3015, -118.1997, zone, north, x, y, 11);
  testing::RasterSpec spec;
  spec.crs = "EPSG:32611";
  spec.width = spec.height = 400;
  spec.geotransform = {std::floor(x - 2000.0), 10.0, 0.0, std::floor(y + 2000.0), 0.0, -10.0};
  spec.nodata = -9999.0;
  testing::write_raster(file, spec, [](int col, int row, int) {
    if (col < 170 && row < 170) return -9999.0;  // nodata in the map's corner: left blank
    return 1200.0 + 30.0 * std::sin(col / 25.0) * std::cos(row / 40.0) + 0.5 * row;
  });
}

// The map's PNG says in its Description text chunk (tEXt, uncompressed) how it was drawn.
std::string png_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

TEST_F(PlotsTest, DrawsTheFootprintsOverAHillshadeOfTheDemAndWithoutItWhenItIsGone) {
  const fs::path dem = dir_ / "hills.tif";
  const fs::path map = dir_ / "plots" / "footprints_map.png";
  write_hills(dem);
  write_products(dir_.path(), false, nlohmann::json{{"terrain", {{"dem", dem.string()}}}}.dump());
  ASSERT_NO_THROW(write_plots(dir_.path()));
  expect_plots();
  EXPECT_NE(
      png_bytes(map).find("over a hillshade of the DEM; CRS WGS 84 / UTM zone 11N (EPSG:32611)"),
      std::string::npos);

  fs::remove(dem);  // the products moved away from their DEM: the plain map, no error
  ASSERT_NO_THROW(write_plots(dir_.path()));
  expect_plots();
  EXPECT_EQ(png_bytes(map).find("hillshade"), std::string::npos);
  EXPECT_NE(png_bytes(map).find("longitude and latitude (WGS 84)"), std::string::npos);
}

TEST_F(PlotsTest, FolderWithoutShotsThrowsWithTheScriptsMessage) {
  try {
    write_plots(dir_.path());
    FAIL() << "no error";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::run);
    EXPECT_EQ(error.place(), "plots");
    EXPECT_NE(std::string(error.what()).find("plot_products: error: cannot read"),
              std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("shots.nc"), std::string::npos) << error.what();
  }
  EXPECT_FALSE(fs::exists(dir_ / "plots"));
}

// The script's process holds none of the caller's descriptors but its standard input, output and
// error (issue 42): a descriptor the caller left open across exec (no O_CLOEXEC), numbered 100 or
// more, is not open in a script that lists its own (/proc/self/fd) into the folder. Before, it was.
TEST(PlotsChild, HoldsNoneOfTheCallersDescriptors) {
  test_support::ScratchDir share, out;
  fs::create_directories(share.path() / "plots");
  std::ofstream(share.path() / "plots" / "list_fds.py")
      << "import os, sys\n"
         "fds = sorted(int(fd) for fd in os.listdir('/proc/self/fd'))\n"
         "open(os.path.join(sys.argv[1], 'fds.txt'), 'w').write(' '.join(map(str, fds)))\n";
  const int opened = ::open("/dev/null", O_RDONLY);
  ASSERT_GE(opened, 0);
  const int inherited = ::fcntl(opened, F_DUPFD, 100);  // F_DUPFD leaves FD_CLOEXEC off
  ::close(opened);
  ASSERT_GE(inherited, 100);
  const char* before = std::getenv("GLASWAVE_SHARE");
  const std::string kept = before ? before : "";
  ::setenv("GLASWAVE_SHARE", share.path().c_str(), 1);
  EXPECT_NO_THROW(write_plots(out.path(), "list_fds.py"));
  if (before)
    ::setenv("GLASWAVE_SHARE", kept.c_str(), 1);
  else
    ::unsetenv("GLASWAVE_SHARE");
  ::close(inherited);
  std::ifstream listed(out.path() / "fds.txt");
  std::vector<int> fds;
  for (int fd; listed >> fd;) fds.push_back(fd);
  ASSERT_FALSE(fds.empty());
  // 0, 1, 2 and the listing's own descriptor of /proc/self/fd.
  EXPECT_LE(fds.size(), 4u);
  for (int fd : fds) EXPECT_NE(fd, inherited);
}

}  // namespace
}  // namespace glaswave
