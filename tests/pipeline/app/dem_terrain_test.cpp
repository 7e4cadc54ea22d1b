// Shots over DEMs the tests write with GDAL: footprints on a plane in UTM and in geographic
// coordinates, a DEM plane against terrain.plane, roughness against Gardner's term (PHYSICS.md
// section 2), and through the built command: bad DEMs (exit status 3, one line), shots over
// nodata or off the raster (flagged, the run goes on), the vertical datum in summary and products.
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <netcdf.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>

#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using namespace test_support;
using nlohmann::json;
using ::testing::HasSubstr;
using testing::RasterSpec;
using testing::TempFolder;

constexpr double c_m_s = 299792458.0;
constexpr double origin_lat = 34.30, origin_lon = -118.20;

json plane_terrain(double slope_deg, double aspect_deg) {
  return {{"plane",
           {{"origin_lat_deg", origin_lat},
            {"origin_lon_deg", origin_lon},
            {"elevation_m", 1200.0},
            {"slope_deg", slope_deg},
            {"aspect_deg", aspect_deg}}}};
}

// One shot of the seed's Table 2 sensor aiming at `points` (lat, lon) from 600 km.
json shots_at(const json& terrain, const std::vector<std::array<double, 2>>& points,
              std::int64_t rays, double off_nadir_deg = 0.0) {
  json targets = json::array();
  for (const auto& p : points) targets.push_back({{"lat_deg", p[0]}, {"lon_deg", p[1]}});
  return {
      {"seed", 5},
      {"sensor", {{"preset", "north2010"}}},
      {"simulation", {{"rays_per_shot", rays}}},
      {"terrain", terrain},
      {"track",
       {{"type", "points"},
        {"points", targets},
        {"altitude_m", 600000.0},
        {"off_nadir_deg", off_nadir_deg},
        {"pointing_azimuth_deg", 60.0}}},
      {"output", {{"netcdf", false}, {"footprints", false}}},
  };
}

// Points about the origin, some off nadir-level ground.
std::vector<std::array<double, 2>> targets_about_origin() {
  return {{origin_lat, origin_lon},
          {origin_lat + 0.006, origin_lon - 0.004},
          {origin_lat - 0.008, origin_lon + 0.009}};
}

// Where the shots land and the slope the record gets, without simulating waveforms: the
// footprint, and fit_surface_orientation as ShotSimulator calls it (beam RMS width at the
// ground, beam axis in the footprint's frame).
struct Located {
  std::vector<Footprint> footprints;
  std::vector<SurfaceOrientation> orientations;
};

Located locate(const json& document) {
  const Config config = parse_config(document);
  const auto terrain = make_terrain(config.terrain);
  Located out;
  const Track track(config.track, *terrain);
  out.footprints = track.footprints(0, track.size());
  for (const Footprint& footprint : out.footprints) {
    const LocalFrame frame(footprint.ground);
    out.orientations.push_back(fit_surface_orientation(
        *terrain, frame, footprint.range_m * config.sensor.divergence_sigma_rad,
        frame.local_direction(footprint.beam_ecef)));
  }
  return out;
}

// The same tilted plane as terrain.plane, as a 30 m UTM raster and a 1" geographic raster: the
// footprints land at the same heights (1 cm) with the same slopes (0.1 degrees), and those of
// the plane itself.
TEST(DemShots, FootprintsOnUtmAndGeographicPlanesAgree) {
  const TempFolder dir;
  const PlaneTerrain plane({origin_lat, origin_lon, 1200.0, 25.0, 300.0});
  testing::utm_raster_of(plane, dir / "utm.tif", origin_lat, origin_lon, 11, 2500.0, 30.0);
  testing::geographic_raster_of(plane, dir / "geographic.tif", origin_lat, origin_lon, 0.025,
                                1.0 / 3600.0);
  const auto points = targets_about_origin();
  for (double off_nadir_deg : {0.0, 4.0}) {
    const Located reference =
        locate(shots_at(plane_terrain(25.0, 300.0), points, 200, off_nadir_deg));
    const Located utm =
        locate(shots_at({{"dem", (dir / "utm.tif").string()}}, points, 200, off_nadir_deg));
    const Located geographic =
        locate(shots_at({{"dem", (dir / "geographic.tif").string()}}, points, 200, off_nadir_deg));
    for (std::size_t k = 0; k < points.size(); ++k) {
      for (const Located* dem : {&utm, &geographic}) {
        ASSERT_TRUE(dem->footprints[k].on_terrain);
        EXPECT_NEAR(dem->footprints[k].ground.h_m, reference.footprints[k].ground.h_m, 0.01);
        EXPECT_NEAR(dem->footprints[k].ground.lat_deg, reference.footprints[k].ground.lat_deg,
                    1e-7);
        EXPECT_NEAR(dem->orientations[k].slope_deg, reference.orientations[k].slope_deg, 0.1);
        EXPECT_NEAR(dem->orientations[k].aspect_deg, reference.orientations[k].aspect_deg, 0.1);
      }
      EXPECT_NEAR(utm.footprints[k].ground.h_m, geographic.footprints[k].ground.h_m, 0.01);
      EXPECT_NEAR(utm.orientations[k].slope_deg, geographic.orientations[k].slope_deg, 0.1);
      EXPECT_NEAR(reference.orientations[k].slope_deg, 25.0, 0.05);
    }
  }
  // The record of a shot carries them (and a good quality flag).
  const SimulatedTrack shot =
      simulate_track(shots_at({{"dem", (dir / "utm.tif").string()}}, {points[1]}, 200, 4.0));
  const Located where =
      locate(shots_at({{"dem", (dir / "utm.tif").string()}}, {points[1]}, 200, 4.0));
  EXPECT_EQ(shot.records[0].quality_flag, quality_good);
  EXPECT_EQ(shot.records[0].elev_m, where.footprints[0].ground.h_m);
  EXPECT_EQ(shot.records[0].slope_deg, where.orientations[0].slope_deg);
}

// A shot over a DEM of a plane is the shot over the plane: the same energy (0.5 %) and the same
// RMS width (1 %), which is Gardner's for that slope (2 %).
TEST(DemShots, WaveformOverADemPlaneIsThePlanes) {
  const TempFolder dir;
  const double slope_deg = 10.0;
  const PlaneTerrain plane({origin_lat, origin_lon, 1200.0, slope_deg, 90.0});
  testing::utm_raster_of(plane, dir / "plane.tif", origin_lat, origin_lon, 11, 1500.0, 30.0);
  auto widen = [](json document) {  // a field of view that does not clip the beam (PHYSICS.md 2)
    document["sensor"]["divergence_sigma_rad"] = 27.5e-6;
    document["sensor"]["ifov_rad"] = 0.002;
    document["sensor"]["bins"] = 1200;
    return document;
  };
  const std::vector<std::array<double, 2>> origin = {{origin_lat, origin_lon}};
  const SimulatedTrack over_plane =
      simulate_track(widen(shots_at(plane_terrain(slope_deg, 90.0), origin, 40000)));
  const SimulatedTrack over_dem =
      simulate_track(widen(shots_at({{"dem", (dir / "plane.tif").string()}}, origin, 40000)));
  const double range_m = over_dem.records[0].range_m;
  const double slope_term_ns =
      2.0 * range_m * 27.5e-6 * std::tan(slope_deg * std::numbers::pi / 180.0) / c_m_s * 1e9;
  const double gardner_ns = std::sqrt(25.0 + slope_term_ns * slope_term_ns + 1.0 / 12.0);
  for (int band = 0; band < 2; ++band) {
    EXPECT_NEAR(over_dem.records[0].rx_energy_J[band] / over_plane.records[0].rx_energy_J[band],
                1.0, 0.005);
    const double dem_ns =
        waveform_moments(over_dem.records[0].rx_waveform_W[band], over_dem.bin_time_ns).rms_ns;
    const double plane_ns =
        waveform_moments(over_plane.records[0].rx_waveform_W[band], over_plane.bin_time_ns).rms_ns;
    EXPECT_NEAR(dem_ns / plane_ns, 1.0, 0.01);
    EXPECT_NEAR(dem_ns / gardner_ns, 1.0, 0.02);
  }
}

// PHYSICS.md section 2: sigma_p^2 = sigma_tx^2 + (2 R sigma_theta tan(alpha) / c)^2
// + (2 sigma_xi cos(S) / (c cos(alpha)))^2 + bin^2 / 12. At nadir on level ground only the
// roughness term changes: (2 sigma_xi / c)^2, 3.3 ns for 0.5 m and 6.7 ns for 1 m against the
// pulse's 5 ns. The beam (66 m RMS) holds some 6000 correlation cells of 2 m, so one field's
// own variance under it is within 2 % of the setting's (1 sigma): the width within 0.6 %.
// Gardner's is a single-scattering formula: light that a rough surface's facets pass to one
// another returns later (about 1 % of the energy, delayed tens of ns), a tail that the RMS width
// weighs heavily (+12 % for 1 m of relief 6 m across), so the test keeps to the first order.
TEST(DemShots, RoughnessBroadensThePulseAsGardner) {
  const TempFolder dir;
  const PlaneTerrain level({origin_lat, origin_lon, 1200.0, 0.0, 0.0});
  testing::utm_raster_of(level, dir / "level.tif", origin_lat, origin_lon, 11, 1000.0, 30.0);
  const std::vector<std::array<double, 2>> origin = {{origin_lat, origin_lon}};
  struct Case {
    json terrain;
    double rms_m;
    double correlation_m = 2.0;
  };
  // Correlations of 0.5 m and 1 m: the relief's region under the field of view (292 m across)
  // would need 1750 and 880 nodes a side at L/3; the first is meshed at L (585 a side).
  const std::vector<Case> cases = {
      {plane_terrain(0.0, 0.0), 0.0},       {plane_terrain(0.0, 0.0), 0.5},
      {plane_terrain(0.0, 0.0), 1.0},       {{{"dem", (dir / "level.tif").string()}}, 1.0},
      {plane_terrain(0.0, 0.0), 0.45, 0.5}, {plane_terrain(0.0, 0.0), 0.45, 1.0},
  };
  for (const Case& c : cases) {
    json document = shots_at(c.terrain, origin, 40000);
    document["terrain"]["roughness"] = {{"rms_m", c.rms_m}, {"correlation_m", c.correlation_m}};
    document["simulation"]["max_order"] = 1;
    const SimulatedTrack shot = simulate_track(document);
    const double roughness_term_ns = 2.0 * c.rms_m / c_m_s * 1e9;
    const double expected_ns = std::sqrt(25.0 + roughness_term_ns * roughness_term_ns + 1.0 / 12.0);
    for (int band = 0; band < 2; ++band) {
      const double width_ns =
          waveform_moments(shot.records[0].rx_waveform_W[band], shot.bin_time_ns).rms_ns;
      EXPECT_NEAR(width_ns / expected_ns, 1.0, 0.02)
          << c.terrain.dump() << " rms " << c.rms_m << " correlation " << c.correlation_m;
    }
    // The footprint's height is the terrain's, not the relief's.
    EXPECT_NEAR(shot.records[0].elev_m, 1200.0, 0.01);
  }
}

// ---- through the built command ---------------------------------------------------------------

// A short pass of the glas sensor heading north over a DEM.
fs::path write_pass(const fs::path& dir, const json& terrain, std::int64_t shots = 3) {
  const json config = {
      {"seed", 3},
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", 2000}}},
      {"terrain", terrain},
      {"canopy", nullptr},
      {"track",
       {{"type", "pass"},
        {"start_lat_deg", origin_lat},
        {"start_lon_deg", origin_lon},
        {"heading_deg", 0.0},
        {"shots", shots},
        {"spacing_m", 172.0}}},
  };
  const fs::path file = dir / "pass.json";
  std::ofstream(file) << config.dump(2);
  return file;
}

TEST(DemCommand, BadDemsExitWithStatus3AndOneLine) {
  const TempFolder dir;
  RasterSpec good;
  good.crs = "EPSG:32611";
  good.width = good.height = 200;
  good.geotransform = {390000.0, 30.0, 0.0, 3800000.0, 0.0, -30.0};
  testing::write_raster(dir / "good.tif", good, [](int c, int r, int) { return 100.0 + c + r; });
  RasterSpec no_crs = good;
  no_crs.crs.clear();
  testing::write_raster(dir / "no_crs.tif", no_crs, [](int, int, int) { return 1.0; });
  RasterSpec two = good;
  two.bands = 2;
  testing::write_raster(dir / "two.tif", two, [](int, int, int band) { return band; });
  std::ofstream(dir / "garbage.tif") << "II*\0 not really a TIFF";
  {
    std::ifstream in(dir / "good.tif", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir / "truncated.tif", std::ios::binary) << bytes.substr(0, bytes.size() / 3);
  }
  struct Case {
    std::string file, cause;
  };
  const std::vector<Case> cases = {
      {(dir / "missing.tif").string(), "no such file"},
      {(dir / "no_crs.tif").string(), "no coordinate reference system"},
      {(dir / "garbage.tif").string(), "cannot read the DEM"},
      {(dir / "truncated.tif").string(), "cannot read the DEM"},
      {(dir / "two.tif").string(), "has 2 bands: choose"},
  };
  for (const Case& c : cases) {
    const fs::path config = write_pass(dir.path(), {{"dem", c.file}});
    for (const std::string command : {"run", "check"}) {
      const std::string out = command == "run" ? " --quiet --out " + (dir / "out").string() : "";
      const CommandOutcome result = run_glaswave(command + " " + config.string() + out);
      EXPECT_EQ(result.status, 3) << c.file << ": " << result.output;
      // One line of ours, GDAL's own chatter kept off the terminal.
      EXPECT_EQ(result.output.rfind("glaswave: error: " + c.file + ": ", 0), 0u) << result.output;
      EXPECT_THAT(result.output, HasSubstr(c.cause));
      EXPECT_EQ(std::count(result.output.begin(), result.output.end(), '\n'), 1) << result.output;
      EXPECT_FALSE(fs::exists(dir / "out")) << c.file;
    }
  }
}

// Shots whose beam falls over a hole or off the raster are flagged and filled; the run goes on
// and its summary counts them.
TEST(DemCommand, ShotsOverNodataOrOffTheRasterAreFlagged) {
  const TempFolder dir;
  // 40 m cells from 400 m south of the start to about 1.4 km north: shot 3 (516 m) over a hole,
  // shots 8 and 9 (1376 m, 1548 m) off the northern edge.
  int zone = 0;
  bool north = true;
  double x = 0, y = 0;
  GeographicLib::UTMUPS::Forward(origin_lat, origin_lon, zone, north, x, y, 11);
  RasterSpec spec;
  spec.crs = "EPSG:32611";
  spec.width = 40;
  spec.height = 45;
  spec.geotransform = {x - 800.0, 40.0, 0.0, y + 1400.0, 0.0, -40.0};
  spec.nodata = -9999.0;
  const double hole_y = y + 516.0;
  testing::write_raster(dir / "holes.tif", spec, [&](int c, int r, int) {
    const double px = spec.geotransform[0] + (c + 0.5) * 40.0,
                 py = spec.geotransform[3] - (r + 0.5) * 40.0;
    return std::hypot(px - x, py - hole_y) < 60.0 ? -9999.0 : 700.0 + 0.05 * (py - y);
  });
  const fs::path config = write_pass(dir.path(), {{"dem", (dir / "holes.tif").string()}}, 10);
  const CommandOutcome run =
      run_glaswave("run " + config.string() + " --quiet --out " + (dir / "out").string());
  ASSERT_EQ(run.status, 0) << run.output;
  EXPECT_THAT(run.output, HasSubstr("10 shots in"));
  EXPECT_THAT(run.output, HasSubstr("3 flagged"));

  int nc = -1, var = -1;
  ASSERT_EQ(nc_open((dir / "out" / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  unsigned char flags[10];
  ASSERT_EQ(nc_inq_varid(nc, "quality_flag", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_uchar(nc, var, flags), NC_NOERR);
  unsigned char reasons[10];
  ASSERT_EQ(nc_inq_varid(nc, "quality_reason", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_uchar(nc, var, reasons), NC_NOERR);
  double energy[20], elev[10];
  ASSERT_EQ(nc_inq_varid(nc, "rx_energy", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_double(nc, var, energy), NC_NOERR);
  ASSERT_EQ(nc_inq_varid(nc, "elev", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_double(nc, var, elev), NC_NOERR);
  nc_close(nc);
  for (int shot = 0; shot < 10; ++shot) {
    const bool flagged = shot == 3 || shot >= 8;
    EXPECT_EQ(flags[shot], flagged ? 0 : 1) << shot << ": 1 is valid, as in GEDI L2A";
    // Shots 3 (the hole's centre) and 9 (past the raster) meet no terrain on the beam's axis;
    // shot 8 meets it, with the raster's edge within 3 sigma of the beam.
    const int reason = shot == 8 ? reason_nodata : flagged ? reason_off_terrain : reason_none;
    EXPECT_EQ(reasons[shot], reason) << shot;
    EXPECT_EQ(std::isfinite(energy[2 * shot]), !flagged) << shot;
    if (!flagged) {
      EXPECT_NEAR(elev[shot], 700.0 + 0.05 * 172.0 * shot, 0.5) << shot;
    }
  }
}

// The vertical datum chosen is said in the summary and recorded in the products: in their
// configuration and in a global attribute `vertical_datum`.
TEST(DemCommand, VerticalDatumIsInTheSummaryAndTheProducts) {
  const TempFolder dir;
  const PlaneTerrain level({origin_lat, origin_lon, 300.0, 0.0, 0.0});
  testing::utm_raster_of(level, dir / "plain.tif", origin_lat, origin_lon, 11, 1500.0, 30.0);
  RasterSpec compound =
      testing::utm_raster_of(level, dir / "unused.tif", origin_lat, origin_lon, 11, 1500.0, 30.0);
  compound.crs = "EPSG:32611+5773";
  testing::write_raster(dir / "compound.tif", compound, [](int, int, int) { return 300.0; });
  struct Case {
    json terrain;
    std::string summary, recorded;
  };
  const std::vector<Case> cases = {
      {{{"dem", (dir / "plain.tif").string()}}, "above the WGS 84 ellipsoid", "ellipsoid"},
      {{{"dem", (dir / "plain.tif").string()}, {"vertical_datum", "egm96"}},
       "EGM96 height (EPSG:5773), from terrain.vertical_datum",
       "egm96"},
      {{{"dem", (dir / "compound.tif").string()}}, "the DEM's own vertical CRS", "EPSG:5773"},
  };
  int n = 0;
  for (const Case& c : cases) {
    const fs::path out = dir / ("out" + std::to_string(n++));
    const CommandOutcome run = run_glaswave("run " + write_pass(dir.path(), c.terrain, 1).string() +
                                            " --quiet --out " + out.string());
    ASSERT_EQ(run.status, 0) << run.output;
    EXPECT_THAT(run.output, HasSubstr(c.summary));
    int nc = -1;
    ASSERT_EQ(nc_open((out / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
    std::size_t length = 0;
    ASSERT_EQ(nc_inq_attlen(nc, NC_GLOBAL, "config", &length), NC_NOERR);
    std::string text(length, '\0');
    nc_get_att_text(nc, NC_GLOBAL, "config", text.data());
    // And in words, as an attribute of its own.
    ASSERT_EQ(nc_inq_attlen(nc, NC_GLOBAL, "vertical_datum", &length), NC_NOERR);
    std::string words(length, '\0');
    nc_get_att_text(nc, NC_GLOBAL, "vertical_datum", words.data());
    nc_close(nc);
    EXPECT_EQ(json::parse(text)["terrain"]["vertical_datum"], c.recorded) << text;
    EXPECT_THAT(words, HasSubstr(c.summary));
  }
}

// The demo's terrain: the script writes a GeoTIFF that GDAL reads back with its CRS, and every
// shot of the demo pass lands on it.
TEST(DemCommand, DemoTerrainIsWrittenAndTheDemoPassLiesOnIt) {
  const std::string python = fs::exists("/usr/bin/python3") ? "/usr/bin/python3" : "python3";
  if (std::system((python + " -c 'import numpy, osgeo.gdal' 2>/dev/null").c_str()) != 0)
    GTEST_SKIP() << "no python3 with numpy and GDAL (scripts/setup installs python3-gdal)";
  const TempFolder dir;
  const fs::path dem = dir / "demo_dem.tif";
  const int written =
      std::system((python + " " GLASWAVE_SOURCE_DIR "/share/demo/make_demo_dem.py " + dem.string() +
                   " >/dev/null")
                      .c_str());
  ASSERT_EQ(written, 0);
  ASSERT_TRUE(fs::exists(dem));
  EXPECT_FALSE(fs::exists(dem.string() + ".part"));
  const CommandOutcome check = run_glaswave(
      "check " GLASWAVE_SOURCE_DIR "/share/demo/demo.json --set terrain.dem=" + dem.string());
  EXPECT_EQ(check.status, 0) << check.output;
  EXPECT_THAT(check.output, HasSubstr("40 shots, 0 off the terrain"));
}

}  // namespace
}  // namespace glaswave
