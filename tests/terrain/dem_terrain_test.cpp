// DEM terrain against rasters the tests write with GDAL: planes in UTM and geographic coordinates
// against the plane they sample, meshes against height queries, nodata and edges, EGM96 against
// the geoid grid read by hand, bad files, and the tile cache's bound under threads.
#include "terrain/dem_terrain.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <random>
#include <thread>

#include "core/error.hpp"
#include "terrain/ground_mesh.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

using ::testing::HasSubstr;
using testing::RasterSpec;
using testing::TempFolder;
using testing::write_raster;

TerrainSettings dem_settings(const std::filesystem::path& file,
                             const std::string& vertical_datum = "ellipsoid", int band = 0) {
  TerrainSettings settings;
  settings.dem = file.string();
  settings.vertical_datum = vertical_datum;
  settings.dem_band = band;
  return settings;
}

// A random point within `half_m` of a frame's origin, on the ellipsoid.
Geodetic random_point(const LocalFrame& frame, double half_m, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-half_m, half_m);
  const Geodetic p = frame.to_geodetic({u(rng), u(rng), 0.0});
  return {p.lat_deg, p.lon_deg, 0.0};
}

// A plane tilted 20 degrees toward the south-east, sampled every 30 m in UTM zone 11 and every
// arc-second in geographic coordinates: both interpolate the plane (heights above the ellipsoid
// are linear along a 30 m cell to micrometres), and fit the same slope.
TEST(DemTerrain, PlaneInUtmAndInGeographicCoordinatesIsThePlane) {
  const TempFolder dir;
  const double lat = 34.30, lon = -118.20;
  const PlaneTerrain plane({lat, lon, 1200.0, 20.0, 135.0});
  testing::utm_raster_of(plane, dir / "utm.tif", lat, lon, 11, 3000.0, 30.0);
  testing::geographic_raster_of(plane, dir / "geographic.tif", lat, lon, 0.03, 1.0 / 3600.0);
  const DemTerrain utm(dem_settings(dir / "utm.tif"));
  const DemTerrain geographic(dem_settings(dir / "geographic.tif"));
  EXPECT_NEAR(utm.detail_m(), 30.0, 0.05);
  EXPECT_NEAR(geographic.detail_m(),
              1.0 / 3600.0 * std::numbers::pi / 180.0 * 6371000.0 *
                  std::cos(lat * std::numbers::pi / 180.0),
              1.0);
  EXPECT_EQ(utm.vertical_datum().key, "ellipsoid");

  const LocalFrame origin({lat, lon, 1200.0});
  std::mt19937_64 rng(11);
  double worst_m = 0.0;
  for (int k = 0; k < 500; ++k) {
    const Geodetic p = random_point(origin, 2000.0, rng);
    const double expected_m = plane.height_m(p.lat_deg, p.lon_deg);
    worst_m = std::max({worst_m, std::abs(utm.height_m(p.lat_deg, p.lon_deg) - expected_m),
                        std::abs(geographic.height_m(p.lat_deg, p.lon_deg) - expected_m)});
  }
  EXPECT_LT(worst_m, 1e-3);

  // Slopes: the plane is defined in the origin's tangent frame; 1.5 km away the vertical has
  // turned by 0.013 degrees.
  for (int k = 0; k < 6; ++k) {
    const Geodetic p = random_point(origin, 1500.0, rng);
    const LocalFrame frame({p.lat_deg, p.lon_deg, plane.height_m(p.lat_deg, p.lon_deg)});
    const SurfaceOrientation a = fit_surface_orientation(utm, frame, 17.5);
    const SurfaceOrientation b = fit_surface_orientation(geographic, frame, 17.5);
    EXPECT_NEAR(a.slope_deg, b.slope_deg, 0.01);
    EXPECT_NEAR(a.aspect_deg, b.aspect_deg, 0.05);
    EXPECT_NEAR(a.slope_deg, 20.0, 0.03);
    EXPECT_NEAR(a.aspect_deg, 135.0, 0.05);
    // A beam far narrower than the cells (0.5 m against 30 m): the weights of a cell's far
    // corners are below what a double holds, its centre's are not.
    const SurfaceOrientation narrow = fit_surface_orientation(utm, frame, 0.5);
    EXPECT_NEAR(narrow.slope_deg, 20.0, 0.03);
    EXPECT_NEAR(narrow.aspect_deg, 135.0, 0.05);
  }
}

// The mesh of a DEM is its own nodes, triangulated as height_m interpolates: every point of the
// mesh lies at the height height_m gives under it. On rough random heights a resampled grid
// misses by metres, so the agreement cannot be luck.
TEST(DemTerrain, MeshAndHeightQueriesAgreeEverywhere) {
  const TempFolder dir;
  const double lat = 46.0, lon = 8.0;
  std::mt19937_64 noise(5);
  std::uniform_real_distribution<double> relief(0.0, 20.0);
  RasterSpec spec;
  spec.crs = "EPSG:32632";
  spec.width = spec.height = 60;
  int zone = 0;
  bool north = true;
  double x = 0, y = 0;
  GeographicLib::UTMUPS::Forward(lat, lon, zone, north, x, y, 32);
  spec.geotransform = {std::floor(x) - 300.0, 10.0, 0.0, std::floor(y) + 300.0, 0.0, -10.0};
  write_raster(dir / "rough.tif", spec, [&](int, int, int) { return 800.0 + relief(noise); });
  const DemTerrain dem(dem_settings(dir / "rough.tif"));

  const LocalFrame frame({lat, lon, dem.height_m(lat, lon)});
  const GroundMesh mesh = dem.mesh(frame, 80.0, 1.0);
  // The nodes of the square and a ring of one node about it: about 18 x 18 of them.
  EXPECT_GE(mesh.vertices_m.size() / 3, 17u * 17u);
  EXPECT_LE(mesh.vertices_m.size() / 3, 21u * 21u);
  const GroundMesh resampled = sample_ground_mesh(dem, frame, 80.0, 7.0);

  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(-70.0, 70.0);
  // The height of a mesh at (x, y): the triangle under it, found by brute force.
  auto mesh_height = [](const GroundMesh& m, double px, double py) {
    for (std::size_t t = 0; t < m.triangles.size(); t += 3) {
      const float* a = &m.vertices_m[3 * m.triangles[t]];
      const float* b = &m.vertices_m[3 * m.triangles[t + 1]];
      const float* c = &m.vertices_m[3 * m.triangles[t + 2]];
      const double d = (b[1] - c[1]) * (a[0] - c[0]) + (c[0] - b[0]) * (a[1] - c[1]);
      const double l0 = ((b[1] - c[1]) * (px - c[0]) + (c[0] - b[0]) * (py - c[1])) / d;
      const double l1 = ((c[1] - a[1]) * (px - c[0]) + (a[0] - c[0]) * (py - c[1])) / d;
      if (l0 >= -1e-9 && l1 >= -1e-9 && l0 + l1 <= 1.0 + 1e-9)
        return l0 * a[2] + l1 * b[2] + (1.0 - l0 - l1) * c[2];
    }
    return std::numeric_limits<double>::quiet_NaN();
  };
  double worst_own_m = 0.0, worst_resampled_m = 0.0;
  for (int k = 0; k < 400; ++k) {
    const double px = u(rng), py = u(rng);
    for (const GroundMesh* m : {&mesh, &resampled}) {
      const double z = mesh_height(*m, px, py);
      ASSERT_TRUE(std::isfinite(z));
      const Geodetic on_mesh = frame.to_geodetic({px, py, z});
      const double miss_m = std::abs(on_mesh.h_m - dem.height_m(on_mesh.lat_deg, on_mesh.lon_deg));
      (m == &mesh ? worst_own_m : worst_resampled_m) =
          std::max(m == &mesh ? worst_own_m : worst_resampled_m, miss_m);
    }
  }
  // Float vertices 100 m from the origin carry 4 micrometres.
  EXPECT_LT(worst_own_m, 1e-3);
  EXPECT_GT(worst_resampled_m, 1.0);
}

TEST(DemTerrain, NodataAndTheEdgeAreHolesAndFlagged) {
  const TempFolder dir;
  const double lat = 10.0, lon = 20.0;
  RasterSpec spec;
  spec.crs = "EPSG:4326";
  spec.width = spec.height = 100;
  const double cell = 1.0 / 1200.0;  // 3 arc-seconds, ~90 m
  spec.geotransform = {lon - 50 * cell, cell, 0.0, lat + 50 * cell, 0.0, -cell};
  spec.type = GDT_Int16;
  spec.nodata = -32768;
  // A 10 x 10 hole north-east of the centre.
  write_raster(dir / "holes.tif", spec, [](int c, int r, int) {
    return (c >= 60 && c < 70 && r >= 30 && r < 40) ? -32768 : 250;
  });
  const DemTerrain dem(dem_settings(dir / "holes.tif"));
  auto centre_of = [&](int c, int r) {
    return std::array<double, 2>{lat + (50 - r - 0.5) * cell, lon + (c - 50 + 0.5) * cell};
  };
  const auto hole = centre_of(65, 35), clear = centre_of(30, 70), edge = centre_of(2, 50);
  EXPECT_TRUE(std::isnan(dem.height_m(hole[0], hole[1])));
  EXPECT_NEAR(dem.height_m(clear[0], clear[1]), 250.0, 1e-6);
  EXPECT_TRUE(std::isnan(dem.height_m(lat, lon + 0.1)));  // off the raster
  EXPECT_TRUE(dem.has_data(LocalFrame({clear[0], clear[1], 250.0}), 500.0));
  EXPECT_FALSE(dem.has_data(LocalFrame({hole[0], hole[1], 250.0}), 100.0));
  const auto near_hole = centre_of(55, 35);  // 5 cells (460 m) west of the hole's edge
  EXPECT_FALSE(dem.has_data(LocalFrame({near_hole[0], near_hole[1], 250.0}), 500.0));
  EXPECT_TRUE(dem.has_data(LocalFrame({near_hole[0], near_hole[1], 250.0}), 200.0));
  EXPECT_FALSE(dem.has_data(LocalFrame({edge[0], edge[1], 250.0}), 300.0));  // over the edge

  // The mesh over the hole leaves out exactly the triangles touching a hole node.
  const LocalFrame frame({hole[0], hole[1], 250.0});
  const GroundMesh mesh = dem.mesh(frame, 1500.0, 1.0);
  for (std::size_t t = 0; t < mesh.triangles.size(); t += 3) {
    for (int k = 0; k < 3; ++k) {
      const float* v = &mesh.vertices_m[3 * mesh.triangles[t + k]];
      EXPECT_NEAR(v[2], 0.0, 0.5);  // level ground at 250 m; the frame sits on it
    }
  }
  const std::size_t nodes = mesh.vertices_m.size() / 3;
  const std::size_t side =
      static_cast<std::size_t>(std::lround(std::sqrt(static_cast<double>(nodes))));
  ASSERT_EQ(side * side, nodes);
  // Cells of the window, two triangles each, less those touching the 100 hole nodes: each
  // interior hole node touches 6 triangles, a hole 10 x 10 removes 2 * 11 * 11 - 2 (corners).
  EXPECT_EQ(mesh.triangles.size() / 3, 2 * (side - 1) * (side - 1) - (2 * 11 * 11 - 2));
}

// PHYSICS.md section 0 wants heights above WGS84: a DEM of orthometric heights in EGM96 is
// raised by the geoid undulation N. N is read here from PROJ's grid by hand, and that reading
// checked against the published EGM96 value at 0 N 0 E (17.16 m, NGA).
TEST(DemTerrain, Egm96HeightsAreRaisedByTheGeoid) {
  testing::Egm96Grid grid;
  if (!grid.load())
    GTEST_SKIP() << testing::Egm96Grid::file << " is not installed (Debian proj-data)";
  EXPECT_NEAR(grid.undulation_m(0.0, 0.0), 17.16, 0.01);

  const TempFolder dir;
  const double lat = 34.30, lon = -118.20;
  const PlaneTerrain level({lat, lon, 500.0, 0.0, 0.0});
  testing::geographic_raster_of(level, dir / "geographic.tif", lat, lon, 0.2, 1.0 / 1200.0);
  testing::geographic_raster_of(level, dir / "compound.tif", lat, lon, 0.2, 1.0 / 1200.0,
                                "EPSG:4326+5773");
  testing::utm_raster_of(level, dir / "utm.tif", lat, lon, 11, 5000.0, 90.0);
  const DemTerrain from_config(dem_settings(dir / "geographic.tif", "egm96"));
  const DemTerrain own(
      dem_settings(dir / "compound.tif", "ellipsoid"));  // its own vertical CRS wins
  const DemTerrain utm(dem_settings(dir / "utm.tif", "egm96"));
  const DemTerrain ellipsoid(dem_settings(dir / "geographic.tif"));
  EXPECT_EQ(from_config.vertical_datum().key, "egm96");
  EXPECT_EQ(own.vertical_datum().key, "EPSG:5773");
  EXPECT_THAT(own.vertical_datum().description, HasSubstr("EGM96"));

  // The plane is level at 500 m above the ellipsoid; read as orthometric, it is 500 + N.
  const LocalFrame origin({lat, lon, 0.0});
  std::mt19937_64 rng(3);
  for (int k = 0; k < 50; ++k) {
    const Geodetic p = random_point(origin, 4000.0, rng);
    const double n_m = grid.undulation_m(p.lat_deg, p.lon_deg);
    EXPECT_NEAR(from_config.height_m(p.lat_deg, p.lon_deg), 500.0 + n_m, 0.005);
    EXPECT_NEAR(own.height_m(p.lat_deg, p.lon_deg), 500.0 + n_m, 0.005);
    EXPECT_NEAR(utm.height_m(p.lat_deg, p.lon_deg), 500.0 + n_m, 0.005);
    EXPECT_NEAR(ellipsoid.height_m(p.lat_deg, p.lon_deg), 500.0, 1e-6);
  }
  EXPECT_NEAR(grid.undulation_m(lat, lon), -34.5,
              2.0);  // the geoid is below the ellipsoid in California
}

// Each unusable DEM is an input error (exit status 3) naming the file and the cause.
TEST(DemTerrain, BadFilesAreInputErrorsNamingFileAndCause) {
  const TempFolder dir;
  RasterSpec good;
  good.crs = "EPSG:32611";
  good.width = good.height = 300;
  good.geotransform = {400000.0, 30.0, 0.0, 3800000.0, 0.0, -30.0};
  write_raster(dir / "good.tif", good, [](int c, int r, int) { return 100.0 + c + r; });
  RasterSpec no_crs = good;
  no_crs.crs.clear();
  write_raster(dir / "no_crs.tif", no_crs, [](int, int, int) { return 1.0; });
  RasterSpec three = good;
  three.bands = 3;
  write_raster(dir / "three.tif", three, [](int, int, int band) { return band; });
  std::ofstream(dir / "garbage.tif") << std::string(5000, 'x');
  {
    // The first half of a good file: the header opens, the data are gone.
    std::ifstream in(dir / "good.tif", std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream(dir / "truncated.tif", std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  std::filesystem::create_directories(dir / "folder.tif");

  struct Case {
    std::filesystem::path file;
    int band;
    std::string cause;
  };
  const std::vector<Case> cases = {
      {dir / "missing.tif", 0, "no such file"},
      {dir / "folder.tif", 0, "directory"},
      {dir / "no_crs.tif", 0, "no coordinate reference system"},
      {dir / "garbage.tif", 0, "cannot read the DEM"},
      {dir / "truncated.tif", 0, "cannot read the DEM"},
      {dir / "three.tif", 0, "has 3 bands: choose"},
      {dir / "three.tif", 4, "asks for band 4"},
      {dir / "good.tif", 2, "asks for band 2"},
  };
  for (const Case& c : cases) {
    try {
      DemTerrain dem(dem_settings(c.file, "ellipsoid", c.band));
      ADD_FAILURE() << c.file << " was accepted";
    } catch (const Error& e) {
      EXPECT_EQ(e.exit_status(), 3) << e.what();
      EXPECT_EQ(e.place(), c.file.string());
      EXPECT_THAT(e.what(), HasSubstr(c.cause));
      EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
    }
  }
  // The band of a multi-band raster, when chosen, is read.
  const DemTerrain second(dem_settings(dir / "three.tif", "ellipsoid", 2));
  const auto p = testing::utm_pixel_lat_lon(three, 11, 150, 150);
  EXPECT_NEAR(second.height_m(p[0], p[1]), 2.0, 1e-9);
  // A vertical datum that is no vertical CRS is the configuration's fault (exit status 2).
  try {
    DemTerrain dem(dem_settings(dir / "good.tif", "EPSG:4326"));
    ADD_FAILURE() << "EPSG:4326 was taken for a vertical datum";
  } catch (const Error& e) {
    EXPECT_EQ(e.exit_status(), 2);
    EXPECT_EQ(e.place(), "vertical_datum");
    EXPECT_TRUE(e.names_setting());
    EXPECT_EQ(e.in_section("/terrain").place(), "/terrain/vertical_datum");
  }
}

// A long pass over a raster much larger than the cache: memory stays within the budget, and
// threads reading at once get the answers one thread gets.
TEST(DemTerrain, TileCacheStaysWithinItsBudgetAndThreadsAgree) {
  const TempFolder dir;
  RasterSpec spec;
  spec.crs = "EPSG:32611";
  spec.width = spec.height = 512;
  spec.geotransform = {400000.0, 10.0, 0.0, 3805120.0, 0.0, -10.0};
  write_raster(dir / "big.tif", spec, [](int c, int r, int) {
    return 1000.0 + 50.0 * std::sin(c * 0.05) * std::cos(r * 0.03);
  });
  DemTerrain::Options options;
  options.tile_pixels = 32;
  options.cache_bytes = 256 << 10;  // 10 tiles of 32 x 32 nodes (24 bytes a node)
  const DemTerrain dem(dem_settings(dir / "big.tif"), options);
  const std::size_t after_open = dem.tiles_read();  // it checks a few tiles on opening

  std::vector<std::array<double, 2>> points;
  for (int k = 0; k < 2000; ++k) {  // a pass across the raster, diagonally, there and back
    const int c = (k * 5) % 510 + 1, r = (k * 2) % 510 + 1;
    points.push_back(testing::utm_pixel_lat_lon(spec, 11, c, r));
  }
  std::vector<double> serial(points.size());
  std::size_t most_bytes = 0;
  for (std::size_t k = 0; k < points.size(); ++k) {
    serial[k] = dem.height_m(points[k][0], points[k][1]);
    most_bytes = std::max(most_bytes, dem.cached_bytes());
  }
  EXPECT_LE(most_bytes, std::size_t{256} << 10);
  EXPECT_GT(dem.tiles_read() - after_open, 60u);  // the pass crosses 16 x 16 tiles more than once
  for (double h : serial) EXPECT_TRUE(std::isfinite(h));

  std::vector<double> parallel(points.size());
  std::vector<std::thread> threads;
  for (int t = 0; t < 8; ++t) {
    threads.emplace_back([&, t] {
      for (std::size_t k = t; k < points.size(); k += 8)
        parallel[k] = dem.height_m(points[k][0], points[k][1]);
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(serial, parallel);
  EXPECT_LE(dem.cached_bytes(), std::size_t{256} << 10);
}

}  // namespace
}  // namespace glaswave
