// Explicit crowns (crowns_file) and stands (vector polygons overriding canopy keys): their
// trees where the files put them, with the optics the stands give, and bad files named.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <numbers>
#include <sstream>
#include <vector>

#include "core/error.hpp"
#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"
#include "tests/pipeline/engine/engine_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

class Forests : public ::testing::Test {
 protected:
  std::string write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
    return (dir_ / name).string();
  }
  Config load(const nlohmann::json& document) {
    std::ofstream(dir_ / "config.json") << document.dump();
    return load_config(dir_ / "config.json", {});
  }
  test_support::ScratchDir dir_{"glaswave_forest"};
};

using Ring = std::vector<std::array<double, 2>>;

// A file of one polygon feature with a real field `pai`, written by GDAL's `driver` in `crs`
// (empty: none, so a Shapefile gets no .prj).
void write_stand(const fs::path& file, const char* driver_name, const std::string& crs,
                 const Ring& ring, double pai) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name);
  ASSERT_NE(driver, nullptr) << driver_name;
  GDALDataset* dataset = driver->Create(file.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
  ASSERT_NE(dataset, nullptr) << file;
  std::unique_ptr<OGRSpatialReference> srs;
  if (!crs.empty()) {
    srs = std::make_unique<OGRSpatialReference>();
    ASSERT_EQ(srs->SetFromUserInput(crs.c_str()), OGRERR_NONE) << crs;
  }
  OGRLayer* layer = dataset->CreateLayer("stands", srs.get(), wkbPolygon, nullptr);
  ASSERT_NE(layer, nullptr);
  OGRFieldDefn field("pai", OFTReal);
  ASSERT_EQ(layer->CreateField(&field), OGRERR_NONE);
  OGRFeature feature(layer->GetLayerDefn());
  feature.SetField("pai", pai);
  OGRLinearRing outline;
  for (const auto& [x, y] : ring) outline.addPoint(x, y);
  OGRPolygon polygon;
  polygon.addRing(&outline);
  feature.SetGeometry(&polygon);
  ASSERT_EQ(layer->CreateFeature(&feature), OGRERR_NONE);
  GDALClose(dataset);
}

// Longitude and latitude -> x, y in `crs`, and back, by GDAL (as a user's GIS would).
Ring transform(const Ring& ring, const std::string& from, const std::string& to) {
  OGRSpatialReference source, target;
  source.SetFromUserInput(from.c_str());
  target.SetFromUserInput(to.c_str());
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  target.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  const std::unique_ptr<OGRCoordinateTransformation> t(
      OGRCreateCoordinateTransformation(&source, &target));
  Ring out = ring;
  for (auto& [x, y] : out) EXPECT_TRUE(t && t->Transform(1, &x, &y));
  return out;
}

std::vector<ShotRecord> simulate(const Config& config) {
  return test_support::simulate_track(config).records;
}

// One ellipsoid (radius 8 m, half height 8 m, PAI 1 over its 16 m x 16 m bounding box) under
// a beam much narrower than the crown: the vertical path through its centre crosses 16 m of
// foliage of density u = 256 / (4/3 pi 8^2 8), optical depth tau = G u 16 with G = 1/2, so the
// single scattering is (2 rho / 3)(1 - e^-tau) from the crown and rho_s e^-tau from the soil.
TEST_F(Forests, ExplicitCrownAtNadirMatchesItsOpticalDepth) {
  const std::string crowns =
      write("crowns.csv", "x,y,base_m,radius_m,half_height_m\n# one tree\n0,0,5,8,8\n");
  const double sigma = 2e-7, ifov = 8 * sigma;
  const Config config = load({
      {"sensor", {{"preset", "north2010"}, {"divergence_sigma_rad", sigma}, {"ifov_rad", ifov}}},
      {"simulation", {{"rays_per_shot", 20000}, {"max_order", 1}}},
      {"terrain", {{"plane", {{"elevation_m", 0.0}}}, {"soil_reflectance", 0.3}}},
      {"canopy",
       {{"crowns_file", crowns},
        {"pai", 1.0},
        {"green_fraction", 1.0},
        {"leaf_reflectance", 0.45},
        {"leaf_transmittance", 0.45},
        {"dbh_m", 0.0},
        {"leaf_size_m", 0.05}}},
      {"track", {{"type", "points"}, {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}}}},
  });
  const ShotRecord shot = simulate(config).at(0);
  const double u = 256.0 / (4.0 / 3.0 * std::numbers::pi * 64.0 * 8.0), tau = 0.5 * u * 16.0;
  const double f_fov = 1.0 - std::exp(-ifov * ifov / (8 * sigma * sigma));
  const double normalisation =
      72e-3 * 0.9 * 0.709 * f_fov / (std::numbers::pi * shot.range_m * shot.range_m);
  EXPECT_NEAR(shot.rx_energy_canopy_J[1] / normalisation / (2 * 0.45 / 3 * (1 - std::exp(-tau))),
              1.0, 0.02);
  EXPECT_NEAR(shot.rx_energy_ground_J[1] / normalisation / (0.3 * std::exp(-tau)), 1.0, 0.02);
}

// The same crown given its own leaf area, crown_lai 2 (one-sided leaf area over pi r^2), whatever
// `pai` says: u = 2 pi 8^2 / (4/3 pi 8^2 8) = 3/16 m2/m3, tau = G u 16 = 1.5 along the axis.
TEST_F(Forests, CrownLaiGivesTheCrownItsOwnLeafArea) {
  const std::string crowns =
      write("crowns.csv", "x,y,base_m,radius_m,half_height_m,crown_lai\n0,0,5,8,8,2\n");
  const double sigma = 2e-7, ifov = 8 * sigma;
  const Config config = load({
      {"sensor", {{"preset", "north2010"}, {"divergence_sigma_rad", sigma}, {"ifov_rad", ifov}}},
      {"simulation", {{"rays_per_shot", 20000}, {"max_order", 1}}},
      {"terrain", {{"plane", {{"elevation_m", 0.0}}}, {"soil_reflectance", 0.3}}},
      {"canopy",
       {{"crowns_file", crowns},
        {"pai", 7.0},
        {"green_fraction", 1.0},
        {"leaf_reflectance", 0.45},
        {"leaf_transmittance", 0.45},
        {"dbh_m", 0.0},
        {"leaf_size_m", 0.05}}},
      {"track", {{"type", "points"}, {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}}}},
  });
  const ShotRecord shot = simulate(config).at(0);
  const double tau = 1.5;
  const double f_fov = 1.0 - std::exp(-ifov * ifov / (8 * sigma * sigma));
  const double normalisation =
      72e-3 * 0.9 * 0.709 * f_fov / (std::numbers::pi * shot.range_m * shot.range_m);
  EXPECT_NEAR(shot.rx_energy_canopy_J[1] / normalisation / (2 * 0.45 / 3 * (1 - std::exp(-tau))),
              1.0, 0.02);
  EXPECT_NEAR(shot.rx_energy_ground_J[1] / normalisation / (0.3 * std::exp(-tau)), 1.0, 0.02);

  const std::string bad =
      write("bad.csv", "x,y,base_m,radius_m,half_height_m,crown_lai\n0,0,5,8,8,0\n");
  const Config refused = load(
      {{"terrain", {{"plane", nlohmann::json::object()}}}, {"canopy", {{"crowns_file", bad}}}});
  const auto terrain = make_terrain(refused.terrain);
  try {
    make_shot_simulator(refused, *terrain);
    FAIL() << "a crown_lai of 0 was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_EQ(std::string(e.what()), bad + ":2: crown_lai must be in (0, 100]");
  }
}

// A stand east of the meridian with no plants: shots there see bare ground, shots west of it
// the scene's forest.
TEST_F(Forests, StandsOverrideTheCanopyInsideTheirPolygons) {
  const std::string stands = write("stands.geojson", R"({"type": "FeatureCollection", "features": [
    {"type": "Feature", "properties": {"pai": 0.0},
     "geometry": {"type": "Polygon", "coordinates": [[[0, -1], [1, -1], [1, 1], [0, 1], [0, -1]]]}}]})");
  const Config config = load({
      {"sensor", {{"preset", "glas"}}},
      {"simulation", {{"rays_per_shot", 3000}}},
      {"terrain", {{"plane", {{"elevation_m", 0.0}}}}},
      {"canopy", {{"stands", stands}, {"cover", 0.9}}},
      {"track",
       {{"type", "points"},
        {"points",
         {{{"lat_deg", 0.0}, {"lon_deg", -0.002}}, {{"lat_deg", 0.0}, {"lon_deg", 0.002}}}}}},
  });
  ASSERT_EQ(config.canopy->stand_areas.size(), 1u);
  EXPECT_EQ(config.canopy->stand_areas[0].canopy.pai, 0.0);
  EXPECT_EQ(config.canopy->stand_areas[0].canopy.cover, 0.9);  // the rest is the scene's
  const auto shots = simulate(config);
  EXPECT_GT(shots[0].rx_energy_canopy_J[0], 0.2 * shots[0].rx_energy_J[0]);
  EXPECT_EQ(shots[1].rx_energy_canopy_J[0], 0.0);
  EXPECT_GT(shots[1].rx_energy_ground_J[0], 0.0);
}

// A UTM (zone 11, EPSG:32611) GeoPackage stand with no plants east of the central meridian,
// over a plane there: the shot inside sees bare ground, the one outside the scene's forest; the
// same stand as a GeoJSON in longitude and latitude gives the same shots.
TEST_F(Forests, AUtmGeoPackageStandChangesTheCanopyUnderIt) {
  const std::array<double, 2> origin =
      transform({{-117.0, 34.0}}, "EPSG:4326", "EPSG:32611").at(0);  // easting 500 km
  const double x0 = origin[0], y0 = origin[1];
  const Ring utm = {{x0, y0 - 2000},
                    {x0 + 2000, y0 - 2000},
                    {x0 + 2000, y0 + 2000},
                    {x0, y0 + 2000},
                    {x0, y0 - 2000}};
  const fs::path gpkg = dir_ / "stands.gpkg";
  write_stand(gpkg, "GPKG", "EPSG:32611", utm, 0.0);
  std::ostringstream geojson;
  geojson << std::setprecision(17)
          << R"({"type": "FeatureCollection", "features": [{"type": "Feature", )"
          << R"("properties": {"pai": 0.0}, "geometry": {"type": "Polygon", "coordinates": [[)";
  const Ring lon_lat = transform(utm, "EPSG:32611", "EPSG:4326");
  for (std::size_t i = 0; i < lon_lat.size(); ++i)
    geojson << (i ? ", " : "") << "[" << lon_lat[i][0] << ", " << lon_lat[i][1] << "]";
  geojson << "]]}}]}";
  const std::string json_stands = write("stands.geojson", geojson.str());
  const auto config_of = [&](const std::string& stands) {
    return load({
        {"sensor", {{"preset", "glas"}}},
        {"simulation", {{"rays_per_shot", 3000}}},
        {"terrain", {{"plane", {{"origin_lat_deg", 34.0}, {"origin_lon_deg", -117.0}}}}},
        {"canopy", {{"stands", stands}, {"cover", 0.9}}},
        {"track",
         {{"type", "points"},
          {"points",
           {{{"lat_deg", 34.0}, {"lon_deg", -117.002}},
            {{"lat_deg", 34.0}, {"lon_deg", -116.998}}}}}},
    });
  };
  const Config config = config_of(gpkg.string());
  ASSERT_EQ(config.canopy->stand_areas.size(), 1u);
  EXPECT_EQ(config.canopy->stand_areas[0].canopy.pai, 0.0);
  EXPECT_EQ(config.canopy->stand_areas[0].canopy.cover, 0.9);
  const auto& ring = config.canopy->stand_areas[0].rings.at(0);
  ASSERT_EQ(ring.size(), 5u);
  EXPECT_NEAR(ring[0][0], -117.0, 1e-9);  // the central meridian: in longitude, not metres
  EXPECT_NEAR(ring[0][1], 34.0 - 2000 / 111000.0, 1e-3);
  const auto shots = simulate(config);
  EXPECT_GT(shots[0].rx_energy_canopy_J[0], 0.2 * shots[0].rx_energy_J[0]);
  EXPECT_EQ(shots[1].rx_energy_canopy_J[0], 0.0);
  EXPECT_GT(shots[1].rx_energy_ground_J[0], 0.0);

  const auto same = simulate(config_of(json_stands));
  ASSERT_EQ(same.size(), shots.size());
  for (std::size_t i = 0; i < shots.size(); ++i) {
    EXPECT_EQ(same[i].rx_energy_canopy_J[0], shots[i].rx_energy_canopy_J[0]) << i;
    EXPECT_EQ(same[i].rx_energy_ground_J[0], shots[i].rx_energy_ground_J[0]) << i;
  }
}

// A Shapefile without its .prj whose coordinates are metres: it cannot be placed, and says so.
TEST_F(Forests, AStandFileWithoutACrsInMetresIsAnInputError) {
  const fs::path shp = dir_ / "stands.shp";
  write_stand(shp, "ESRI Shapefile", "",
              {{500000, 3760000}, {502000, 3760000}, {502000, 3762000}, {500000, 3760000}}, 1.0);
  ASSERT_FALSE(fs::exists(dir_ / "stands.prj"));
  try {
    load({{"terrain", {{"plane", nlohmann::json::object()}}},
          {"canopy", {{"stands", shp.string()}}}});
    FAIL() << "a stands file in metres with no CRS was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_NE(std::string(e.what()).find(shp.string() + ": feature 0: "), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("has no CRS"), std::string::npos) << e.what();
  }
}

TEST_F(Forests, BadFilesAreNamedWithTheirPlace) {
  const std::string stands = write("stands.geojson", R"({"type": "FeatureCollection", "features": [
    {"type": "Feature", "properties": {"pai": -2},
     "geometry": {"type": "Polygon", "coordinates": [[[0, -1], [1, -1], [1, 1], [0, -1]]]}}]})");
  try {
    load({{"terrain", {{"plane", nlohmann::json::object()}}}, {"canopy", {{"stands", stands}}}});
    FAIL() << "a negative PAI in a stand was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_EQ(std::string(e.what()), stands + ": feature 0: property pai: must be >= 0, got -2");
  }
  const std::string crowns =
      write("crowns.csv", "lon,lat,base_m,radius_m,half_height_m\n0,0,5,8,8\n0,0,5,eight,8\n");
  const Config config = load(
      {{"terrain", {{"plane", nlohmann::json::object()}}}, {"canopy", {{"crowns_file", crowns}}}});
  const auto terrain = make_terrain(config.terrain);
  try {
    make_shot_simulator(config, *terrain);
    FAIL() << "a bad crowns file was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_EQ(std::string(e.what()),
              crowns + ":3: radius_m: expected a finite number, got \"eight\"");
  }
}

}  // namespace
}  // namespace glaswave
