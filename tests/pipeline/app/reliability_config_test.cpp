// Issue 28, the configuration's and the input files' share: each cause refused at its root, by
// `check` and `run` alike, with one line naming the place. Quoted input is a bounded excerpt; a
// stand without area, a GeoJSON CRS GDAL does not know and a Shapefile's cut field names are
// refused; a time outside the years a track may have is refused; crowns far from every
// footprint are a warning.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <netcdf.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using namespace test_support;

class Refused : public ::testing::Test {
 protected:
  // One shot over a plane, with `changes` merged in.
  std::string write_config(const json& changes, const std::string& name = "config.json") {
    json config = one_glas_shot();
    config.merge_patch(changes);
    const fs::path file = dir_ / name;
    std::ofstream(file) << config.dump(2);
    return file.string();
  }

  std::string write(const std::string& name, const std::string& text) {
    const fs::path file = dir_ / name;
    std::ofstream(file) << text;
    return file.string();
  }

  // A GeoJSON stands file of one feature with `ring` and `members` beside its features.
  std::string stands(const std::string& name, const json& ring, const json& members = {}) {
    json document = {{"type", "FeatureCollection"},
                     {"features",
                      {{{"type", "Feature"},
                        {"properties", {{"pai", 1}}},
                        {"geometry", {{"type", "Polygon"}, {"coordinates", {ring}}}}}}}};
    if (!members.is_null()) document.update(members);
    return write(name, document.dump());
  }

  // check and run refuse `arguments` alike: `status`, one line starting with `message`, and
  // nothing written. The line is returned.
  std::string expect_refused(const std::string& config, const std::string& extra, int status,
                             const std::string& message) {
    const CommandOutcome check = run_glaswave("check " + config + extra);
    const CommandOutcome run =
        run_glaswave("run " + config + extra + " --quiet --out " + (dir_ / "out").string());
    EXPECT_EQ(check.status, status) << check.output;
    EXPECT_EQ(run.status, check.status) << run.output;
    EXPECT_EQ(run.output, check.output);
    EXPECT_EQ(check.output.rfind("glaswave: error: " + message, 0), 0u) << check.output;
    EXPECT_EQ(std::count(check.output.begin(), check.output.end(), '\n'), 1) << check.output;
    EXPECT_FALSE(fs::exists(dir_ / "out"));
    return check.output;
  }

  ScratchDir dir_{"glaswave_refused"};
};

const json square = {{7.99, 45.99}, {8.01, 45.99}, {8.01, 46.01}, {7.99, 46.01}, {7.99, 45.99}};

// A 200,000-character key, a 1 MB string and a 100 KB --set value were echoed whole.
TEST_F(Refused, QuotedInputIsABoundedExcerpt) {
  const std::string key(200000, 'k'), string(1000000, 's'), value(100000, 'v');
  std::string line = expect_refused(write_config({{"canopy", {{key, 1}}}}), "", 2,
                                    "/canopy/" + std::string(60, 'k') + "... (200000 characters)");
  EXPECT_LT(line.size(), 600u);
  EXPECT_NE(line.find("unknown key \"" + std::string(60, 'k') + "...\" (200000 characters)"),
            std::string::npos)
      << line.substr(0, 300);
  line = expect_refused(write_config({{"canopy", {{"crown_shape", string}}}}), "", 2,
                        "/canopy/crown_shape: must be one of ellipsoid, cone, layer, got \"" +
                            std::string(60, 's') + "...\" (1000000 characters)");
  EXPECT_LT(line.size(), 200u);
  const std::string dem = (dir_ / string).string();  // a path beyond any the system opens
  line = expect_refused(write_config({{"terrain", {{"plane", nullptr}, {"dem", string}}}}), "", 3,
                        dem.substr(0, 60) + "... (" + std::to_string(dem.size()) +
                            " characters): cannot read the DEM");
  EXPECT_LT(line.size(), 200u);
  line = expect_refused(write_config(json::object()), " --set canopy.lad=" + value, 2,
                        "/canopy/lad: must be one of");
  EXPECT_LT(line.size(), 300u);
}

// --set's own messages quoted the whole assignment: 100 KB without '=', in a key's part, as an
// array index, as a number beyond a double.
TEST_F(Refused, SetQuotesItsAssignmentAsABoundedExcerpt) {
  const std::string value(100000, 'v');
  const std::string config = write_config(json::object());
  const std::string cut = "\"" + std::string(60, 'v') + "...\" (";
  std::string line =
      expect_refused(config, " --set " + value, 2, "--set: expected KEY=VALUE, got " + cut);
  EXPECT_LT(line.size(), 300u);
  line = expect_refused(config, " --set canopy." + value + "..pai=1", 2,
                        "--set: empty part in the key \"canopy.vvv");
  EXPECT_LT(line.size(), 300u);
  const json band = {{"name", "1064"},
                     {"wavelength_nm", 1064},
                     {"pulse_energy_mJ", 70},
                     {"atmos_transmission_roundtrip", 0.9}};
  line = expect_refused(write_config({{"sensor", {{"bands", {band}}}}}, "bands.json"),
                        " --set sensor.bands." + value + "=1", 2,
                        "--set: cannot set \"sensor.bands.vvv");
  EXPECT_NE(line.find("is not an index of an array of 1"), std::string::npos) << line;
  EXPECT_LT(line.size(), 300u);
  line = expect_refused(config, " --set canopy.pai=1" + std::string(100000, '0'), 2,
                        "/canopy/pai: must be a finite number, got 1" + std::string(59, '0') +
                            "... (100001 characters) (from --set canopy.pai)");
  EXPECT_LT(line.size(), 300u);
}

// A seed of 2^64 is an integer, too large; keys of another type of track, which it ignored, two
// bands of one wavelength (a band coordinate not unique) and GeoPackage properties differing only
// in case (which failed inside SQLite with its CREATE TABLE) are refused before anything runs.
TEST_F(Refused, MessagesSayWhatIsWrong) {
  expect_refused(
      write_config({{"seed", 18446744073709551615.0 * 2.0}}), "", 2,
      "/seed: is too large: must be <= 18446744073709551615, got 3.6893488147419103e+19");
  expect_refused(write_config(json::object()), " --set seed=18446744073709551616", 2,
                 "/seed: is too large: must be <= 18446744073709551615, got ");
  expect_refused(write_config({{"track", {{"points", {{{"lat_deg", 46}, {"lon_deg", 8}}}}}}}), "",
                 2,
                 "/track/points: is a key of a track of type \"points\", which this track (type "
                 "\"pass\") would ignore");
  for (const char* type : {"orbit", "granule"}) {
    expect_refused(write_config({{"track", {{"type", type}, {"file", "g.h5"}}}}), "", 2,
                   "/track/start_lat_deg: is a key of a track of type \"pass\", which this "
                   "track (type \"" +
                       std::string(type) + "\") would ignore");
  }
  const json band = {
      {"wavelength_nm", 1064}, {"pulse_energy_mJ", 70}, {"atmos_transmission_roundtrip", 0.9}};
  json a = band, b = band;
  a["name"] = "x";
  b["name"] = "X";
  expect_refused(write_config({{"sensor", {{"bands", {a, b}}}}}), "", 2,
                 "/sensor/bands/1/wavelength_nm: is also that of band \"x\" (1064 nm)");
  b["wavelength_nm"] = 532;
  const std::string gpkg =
      write_config({{"sensor", {{"bands", {a, b}}}}, {"output", {{"footprints_format", "GPKG"}}}});
  const std::string line =
      expect_refused(gpkg, "", 2, "/sensor/bands/1/name: the footprint properties \"");
  EXPECT_EQ(line.find("CREATE"), std::string::npos) << line;
  // GeoJSON keeps them apart.
  const CommandOutcome geojson =
      run_glaswave("check " + write_config({{"sensor", {{"bands", {a, b}}}}}, "geojson.json"));
  EXPECT_EQ(geojson.status, 0) << geojson.output;
}

TEST_F(Refused, AStandWithoutAreaIsRefusedNamingTheFeature) {
  const std::string file =
      stands("line.geojson", {{7.99, 45.99}, {8.0, 46.0}, {8.01, 46.01}, {7.99, 45.99}});
  expect_refused(write_config({{"canopy", {{"stands", file}}}}), "", 3,
                 file + ": feature 0: a ring encloses no area");
  // A bow-tie encloses two triangles (the even-odd rule): a stand.
  const std::string bow_tie =
      stands("bow_tie.geojson",
             {{7.99, 45.99}, {8.01, 46.01}, {8.01, 45.99}, {7.99, 46.01}, {7.99, 45.99}});
  EXPECT_EQ(run_glaswave("check " + write_config({{"canopy", {{"stands", bow_tie}}}})).status, 0);
}

TEST_F(Refused, AGeoJsonCrsGdalDoesNotKnowIsRefused) {
  for (const std::string name : {"EPSG:999999", "FOO:bar"}) {
    const std::string file = stands(
        "crs.geojson", square, {{"crs", {{"type", "name"}, {"properties", {{"name", name}}}}}});
    expect_refused(write_config({{"canopy", {{"stands", file}}}}), "", 3,
                   file + ": its crs member \"" + name + "\" is not a CRS GDAL knows");
  }
  // A CRS it knows is used (CRS84 is longitude and latitude).
  const std::string known = stands(
      "crs84.geojson", square,
      {{"crs", {{"type", "name"}, {"properties", {{"name", "urn:ogc:def:crs:OGC:1.3:CRS84"}}}}}});
  EXPECT_EQ(run_glaswave("check " + write_config({{"canopy", {{"stands", known}}}})).status, 0);
}

TEST_F(Refused, AShapefilesCutFieldNameIsToldAsSuch) {
  GDALAllRegister();
  const std::string file = (dir_ / "stands.shp").string();
  {
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("ESRI Shapefile");
    ASSERT_NE(driver, nullptr);
    std::unique_ptr<GDALDataset> dataset(
        driver->Create(file.c_str(), 0, 0, 0, GDT_Unknown, nullptr));
    OGRSpatialReference wgs84;
    wgs84.SetWellKnownGeogCS("WGS84");
    OGRLayer* layer = dataset->CreateLayer("stands", &wgs84, wkbPolygon, nullptr);
    OGRFieldDefn field("leaf_reflectance", OFTReal);  // the driver cuts it to "leaf_refle"
    CPLPushErrorHandler(CPLQuietErrorHandler);
    ASSERT_EQ(layer->CreateField(&field), OGRERR_NONE);
    CPLPopErrorHandler();
    OGRFeature feature(layer->GetLayerDefn());
    feature.SetField(0, 0.3);
    OGRPolygon polygon;
    OGRLinearRing ring;
    for (const auto& point : square) ring.addPoint(point[0].get<double>(), point[1].get<double>());
    polygon.addRing(&ring);
    feature.SetGeometry(&polygon);
    ASSERT_EQ(layer->CreateFeature(&feature), OGRERR_NONE);
  }
  expect_refused(write_config({{"canopy", {{"stands", file}}}}), "", 3,
                 file +
                     ": field \"leaf_refle\" (\"leaf_reflectance\" cut short?): a Shapefile "
                     "cuts field names to 10 characters");
}

TEST_F(Refused, TimesOutsideTheYearsOfATrack) {
  expect_refused(write_config({{"track", {{"start_time", "2999-01-01T00:00:00Z"}}}}), "", 2,
                 "/track/start_time: \"2999-01-01T00:00:00Z\" is outside the years 1900 to 2199");
  expect_refused(write_config({{"track", {{"shots", 2}, {"rate_hz", 1e-300}}}}), "", 2,
                 "/track/rate_hz: too low: the last of the 2 shots from start_time comes at a "
                 "time that must be from 1900-01-01T00:00:00Z to 2200-01-01T00:00:00Z");
  const std::string ephemeris =
      write("eph.csv", "time,x_m,y_m,z_m\n1e300,4436000,623000,5170000\n");
  expect_refused(write_config({{"track",
                                {{"type", "ephemeris"},
                                 {"ephemeris", ephemeris},
                                 {"start_lat_deg", nullptr},
                                 {"start_lon_deg", nullptr}}}}),
                 "", 3, ephemeris + ":2: time must be from 1900-01-01T00:00:00Z");
}

// Crowns 900 km from the track were simulated as bare ground without a word.
TEST_F(Refused, CrownsFarFromEveryFootprintAreAWarning) {
  const std::string far = write("far.csv", "lon,lat,base_m,radius_m,half_height_m\n8,54.1,5,3,3\n");
  const std::string config = write_config({{"canopy", {{"crowns_file", far}}}});
  const std::string warning = "glaswave: warning: /canopy/crowns_file: none of the 1 crowns of " +
                              far +
                              " lies within 100 m of any of the 1 footprints (the nearest "
                              "is 902 km away)";
  const CommandOutcome check = run_glaswave("check " + config);
  EXPECT_EQ(check.status, 0) << check.output;
  EXPECT_NE(check.output.find(warning), std::string::npos) << check.output;
  const CommandOutcome run =
      run_glaswave("run " + config + " --quiet --out " + (dir_ / "far").string());
  EXPECT_EQ(run.status, 0) << run.output;
  EXPECT_NE(run.output.find(warning), std::string::npos) << run.output;
  const std::string near =
      write("near.csv", "lon,lat,base_m,radius_m,half_height_m\n8.0005,46,5,3,3\n");
  const CommandOutcome quiet =
      run_glaswave("check " + write_config({{"canopy", {{"crowns_file", near}}}}));
  EXPECT_EQ(quiet.status, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("warning"), std::string::npos) << quiet.output;
}

// check accepted telescope_area_m2 1e308, pulse_energy_mJ 1e308, pulse_sigma_ns 1e-300, a
// detector gain or noise of 1e300 and crown_radius_m 1e6, and run then failed after simulating
// (exit 4 naming a NetCDF variable) or ran for minutes. Each key has a physical bound, refused by
// both; the bounds' extremes together run one shot to finite waveforms.
TEST_F(Refused, PhysicalKeysHaveBoundsAndTheirExtremesGiveFiniteProducts) {
  const std::string config = write_config(json::object());
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"sensor.telescope_area_m2=1e308", "/sensor/telescope_area_m2: must be in (0, 100]"},
      {"'sensor.bands=[{\"name\": \"a\", \"wavelength_nm\": 532, \"pulse_energy_mJ\": 1e308, "
       "\"atmos_transmission_roundtrip\": 0.8}]'",
       "/sensor/bands/0/pulse_energy_mJ: must be in (0, 10000000]"},
      {"sensor.pulse_sigma_ns=1e-300", "/sensor/pulse_sigma_ns: must be in [0.001, 1000]"},
      {"detector.gain=1e300", "/detector/gain: must be in (0, 1e+12]"},
      {"detector.noise_rms_W=1e300", "/detector/noise_rms_W: must be in [0, 1]"},
      {"canopy.crown_radius_m=1e6", "/canopy/crown_radius_m: must be in (0, 100]"}};
  for (const auto& [assignment, message] : cases)
    expect_refused(config, " --set " + assignment, 2, message);
  const std::string extremes = write_config(
      {{"sensor",
        {{"telescope_area_m2", 100},
         {"pulse_sigma_ns", 0.001},
         {"bands",
          {{{"name", "a"},
            {"wavelength_nm", 100000},
            {"pulse_energy_mJ", 1e7},
            {"atmos_transmission_roundtrip", 1}}}}}},
       {"canopy", {{"crown_radius_m", 100}, {"crown_half_height_m", 100}}},
       {"detector", {{"enabled", true}, {"gain", 1e12}, {"noise_rms_W", 1}, {"background_W", 1}}}},
      "extremes.json");
  const fs::path out = dir_ / "extremes";
  const CommandOutcome run = run_glaswave("run " + extremes + " --quiet --out " + out.string());
  ASSERT_EQ(run.status, 0) << run.output;
  int nc = 0, variable = 0;
  ASSERT_EQ(nc_open((out / "shots.nc").c_str(), NC_NOWRITE, &nc), NC_NOERR);
  ASSERT_EQ(nc_inq_varid(nc, "rx_waveform", &variable), NC_NOERR);
  int dims[NC_MAX_VAR_DIMS], rank = 0;
  nc_inq_varndims(nc, variable, &rank);
  nc_inq_vardimid(nc, variable, dims);
  std::size_t count = 1;
  for (int d = 0; d < rank; ++d) {
    std::size_t length = 0;
    nc_inq_dimlen(nc, dims[d], &length);
    count *= length;
  }
  std::vector<float> values(count);
  ASSERT_EQ(nc_get_var_float(nc, variable, values.data()), NC_NOERR);
  nc_close(nc);
  EXPECT_TRUE(std::all_of(values.begin(), values.end(), [](float v) { return std::isfinite(v); }));
}

}  // namespace
}  // namespace glaswave
