// ALS -> DEM and voxels. The ground: ground points on a level and on a tilted plane gridded back
// within 2 cm. The canopy: discrete returns cast here through a known plant area profile
// (Beer-Lambert with G = 1/2 along slanted pulses, four independent beamlets a pulse, each giving
// one return), written as a LAS 1.4 file, then voxelised by the code under test: the plot's mean
// profile comes back within 10 % a layer and its plant area index within 5 %. A dense canopy
// shows the method's known bias: occlusion, the lowest layers underestimated.
#include "canopy/gap_fraction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/error.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

const char* utm33 =
    "PROJCS[\"WGS 84 / UTM zone 33N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS "
    "84\",6378137,298.257223563]],PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]],"
    "PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],PARAMETER[\"central_"
    "meridian\",15],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],"
    "PARAMETER[\"false_northing\",0],UNIT[\"metre\",1]]";

double plane(double x, double y) { return 250.0 + 0.1 * (x - 500000.0) - 0.05 * (y - 4000000.0); }

TEST(GroundGrid, LevelAndTiltedGroundCloudsGiveTheDemWithin2cm) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 60.0);
  for (bool tilted : {false, true}) {
    std::vector<std::array<double, 3>> points;
    for (int n = 0; n < 3000; ++n) {
      const double x = 500000.0 + u(rng), y = 4000000.0 + u(rng);
      points.push_back({x, y, tilted ? plane(x, y) : 250.0});
    }
    const GroundGrid g = grid_ground(points, 500000.0, 4000000.0, 60, 60, 1.0, "test");
    // Inside the ground points' hull (2 m from the cloud's edge) the DEM interpolates linearly;
    // beyond it, a node takes its nearest point's height (GDAL's linear gridding), off by the
    // slope times the distance there.
    double worst = 0.0;
    for (int j = 2; j < 58; ++j)
      for (int i = 2; i < 58; ++i) {
        const double x = 500000.0 + i + 0.5, y = 4000000.0 + j + 0.5;
        worst = std::max(worst, std::abs(g.height_m[j * 60 + i] - (tilted ? plane(x, y) : 250.0)));
        // between nodes too
        worst = std::max(worst, std::abs(g.height_at(x + 0.3, y + 0.2) -
                                         (tilted ? plane(x + 0.3, y + 0.2) : 250.0)));
      }
    EXPECT_LT(worst, 0.02) << (tilted ? "tilted" : "level");
  }
  EXPECT_THROW(grid_ground({}, 0.0, 0.0, 4, 4, 1.0, "test"), Error);
}

// PAD by 5 m layer: empty trunk space, then a crown.
const double profile[] = {0.0, 0.1, 0.3, 0.2, 0.05, 0.0};

struct Cast {
  std::vector<test::LasFixturePoint> points;
};

// Pulses over a 40 m square, scan angles within +-15 degrees across track (x), four beamlets
// each; a beamlet's first interception at optical depth -ln(U) along its path, G = 1/2.
Cast cast_returns(double scale, int pulses, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Cast cast;
  for (int n = 0; n < pulses; ++n) {
    const double x = 500000.0 + 40.0 * u(rng), y = 4000000.0 + 40.0 * u(rng);
    const double angle = (u(rng) - 0.5) * 30.0, theta = angle * std::numbers::pi / 180.0;
    for (int b = 0; b < 4; ++b) {
      double target = -std::log(1.0 - u(rng)), h = 30.0;
      // Down through the layers: optical depth per metre of height G PAD / cos(theta).
      for (int k = 5; k >= 0 && h > 0.0; --k) {
        const double rate = 0.5 * scale * profile[k] / std::cos(theta);
        const double top = 5.0 * (k + 1) > 30.0 ? 30.0 : 5.0 * (k + 1);
        if (rate * 5.0 >= target) {
          h = top - target / rate;
          break;
        }
        target -= rate * 5.0;
        h = 5.0 * k;
      }
      test::LasFixturePoint p;
      // Along the slanted path from the point above (x, y): the ground plane is nearly level.
      p.x = x + (30.0 - h) * std::tan(theta);
      p.y = y;
      p.z = plane(p.x, p.y) + h;
      p.return_number = b + 1;
      p.number_of_returns = 4;
      p.classification = h > 0.0 ? 5 : 2;
      p.scan_angle_deg = angle;
      cast.points.push_back(p);
    }
  }
  return cast;
}

VoxelizeResult voxelize_cast(const Cast& cast, const std::filesystem::path& file) {
  test::LasFixture f;
  f.version_minor = 4;
  f.point_format = 6;
  f.wkt = utm33;
  f.points = cast.points;
  test::write_las(file, f);
  GapFractionSettings settings;
  settings.voxel_size_m = 5.0;
  return voxelize_point_cloud(LasFile(file), "", "/crs", settings);
}

// The plot's mean PAD in layer k, over the columns fully inside the cast square.
double plot_mean(const VoxelBlock& v, int k) {
  double sum = 0.0;
  int n = 0;
  for (int j = 0; j < v.ny; ++j)
    for (int i = 0; i < v.nx; ++i) {
      const double x = v.x0 + (i + 0.5) * v.dx, y = v.y0 + (j + 0.5) * v.dy;
      if (x < 500000.0 || x > 500040.0 || y < 4000000.0 || y > 4000040.0) continue;
      if (k < v.nz) sum += v.at(i, j, k);
      ++n;
    }
  return sum / n;
}

TEST(GapFraction, CastReturnsGiveBackTheProfile) {
  test_support::ScratchDir dir;
  const VoxelizeResult r = voxelize_cast(cast_returns(1.0, 8000, 7), dir.path() / "cloud.las");
  EXPECT_NE(r.voxels.crs_wkt.find("UTM zone 33N"), std::string::npos);
  EXPECT_EQ(r.report.points, 32000u);
  double pai = 0.0, truth = 0.0;
  for (int k = 0; k < 6; ++k) {
    const double got = plot_mean(r.voxels, k);
    if (profile[k] >= 0.1)
      EXPECT_NEAR(got / profile[k], 1.0, 0.10) << "layer " << k;
    else
      EXPECT_NEAR(got, profile[k], 0.015) << "layer " << k;
    pai += 5.0 * got;
    truth += 5.0 * profile[k];
  }
  EXPECT_NEAR(pai / truth, 1.0, 0.05) << pai;
  // The DEM from the cast's ground returns: the plane, within 2 cm inside the plot.
  for (double x : {500005.3, 500021.1, 500033.7})
    for (double y : {4000004.2, 4000019.9, 4000036.4})
      EXPECT_NEAR(r.ground.height_at(x, y), plane(x, y), 0.02);
}

TEST(GapFraction, DenseCanopiesAreUnderestimatedBelowTheOcclusion) {
  test_support::ScratchDir dir;
  // PAI 13: the lowest crown layers are seen through a gap fraction of e^-3 or less.
  const VoxelizeResult r = voxelize_cast(cast_returns(4.0, 8000, 9), dir.path() / "dense.las");
  const double top = plot_mean(r.voxels, 3) / (4.0 * profile[3]);
  const double bottom = plot_mean(r.voxels, 1) / (4.0 * profile[1]);
  EXPECT_GT(r.report.occluded_layers, 0u);
  EXPECT_NEAR(top, 1.0, 0.15);  // the upper crown is still seen
  EXPECT_LT(bottom, 0.9);       // the lowest is not: biased low
}

// One ground point 800 m from an 80 m plot (issue 42) would have the ground gridded and the
// voxels made over the 800 m between (45 s): refused, naming it. The plot alone, and the plot as
// two flight lines 15 m apart or as a diagonal strip, are one patch each and voxelised.
TEST(GapFraction, APatchFarFromTheRestIsRefusedNotGridded) {
  test_support::ScratchDir dir;
  const auto voxelize = [&](const std::vector<test::LasFixturePoint>& points) {
    test::LasFixture f;
    f.version_minor = 4;
    f.point_format = 6;
    f.wkt = utm33;
    f.points = points;
    test::write_las(dir.path() / "cloud.las", f);
    GapFractionSettings settings;
    settings.voxel_size_m = 1.0;
    return voxelize_point_cloud(LasFile(dir.path() / "cloud.las"), "", "/crs", settings);
  };
  const auto point = [](double x, double y, int classification) {
    test::LasFixturePoint p;
    p.x = 500000.0 + x;
    p.y = 4000000.0 + y;
    p.z = 250.0 + (classification == 2 ? 0.0 : 10.0);
    p.classification = classification;
    return p;
  };
  std::vector<test::LasFixturePoint> plot;
  for (int j = 0; j < 80; ++j)
    for (int i = 0; i < 80; ++i) plot.push_back(point(i + 0.5, j + 0.5, (i + j) % 2 ? 5 : 2));
  EXPECT_EQ(voxelize(plot).voxels.nx, 80);
  for (const double far_m : {800.0, 1450.0}) {
    auto stray = plot;
    stray.push_back(point(far_m, 40.0, 2));
    try {
      voxelize(stray);
      ADD_FAILURE() << "a point " << far_m << " m away was gridded";
    } catch (const Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(e.kind(), ErrorKind::input);
      EXPECT_NE(message.find("cloud.las: the cloud's points lie in separate patches"),
                std::string::npos)
          << message;
      EXPECT_NE(message.find("x " + std::to_string(500000 + int(far_m / 10) * 10 + 5)),
                std::string::npos)
          << message;
    }
  }
  // Two flight lines with 15 m between them; a strip along the diagonal of its 200 m square.
  std::vector<test::LasFixturePoint> lines, strip;
  for (int j = 0; j < 80; ++j)
    for (int i = 0; i < 30; ++i) {
      lines.push_back(point(i + 0.5, j + 0.5, 2));
      lines.push_back(point(i + 45.5, j + 0.5, 2));
    }
  EXPECT_EQ(voxelize(lines).voxels.nx, 75);
  for (int t = 0; t < 200; ++t)
    for (int w = -8; w <= 8; ++w) strip.push_back(point(t + w + 10.0, t - w + 10.0, 2));
  EXPECT_GT(voxelize(strip).voxels.nx, 200);
}

}  // namespace
}  // namespace glaswave
