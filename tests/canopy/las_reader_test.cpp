// The LAS reader against files written byte by byte by tests/canopy/las_fixture.hpp: every
// version and point format read back, the CRS from each kind of record, and malformed files
// (truncated, a header size that lies, point counts beyond the file, an unknown point format,
// LAZ) refused with an input error naming the cause, never a crash.
#include "canopy/las_reader.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/error.hpp"
#include "tests/canopy/las_fixture.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using test::LasFixture;
using test::LasFixturePoint;

LasFixture three_points(int version_minor, int format) {
  LasFixture f;
  f.version_minor = version_minor;
  f.point_format = format;
  f.points = {{500010.5, 4000020.25, 101.125, 1, 2, 5, 12.5},
              {500011.0, 4000021.0, 99.5, 2, 2, 2, 13.0},
              {499990.001, 3999999.999, -3.0, 1, 1, 2, 14.0}};
  return f;
}

// The message of the input error `file` is refused with ("" when it is read).
std::string refusal(const std::filesystem::path& file) {
  try {
    LasFile las(file);
    std::vector<LasPoint> points;
    las.read_points(0, las.header().point_count, points);
    las.crs_wkt();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input) << e.what();
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    return e.what();
  }
  return "";
}

TEST(LasReader, ReadsEveryVersionAndPointFormat) {
  test_support::ScratchDir dir;
  for (int minor = 0; minor <= 4; ++minor) {
    for (int format = 0; format <= 10; ++format) {
      if (format > 5 && minor < 4) continue;
      if (format > 1 && minor < 2 && format <= 5 && format > 1) continue;  // 1.0-1.1: 0 and 1
      for (int extra : {0, 7}) {
        LasFixture f = three_points(minor, format);
        f.extra_bytes = extra;
        const auto file =
            dir.path() / ("v" + std::to_string(minor) + "f" + std::to_string(format) + ".las");
        test::write_las(file, f);
        const LasFile las(file);
        EXPECT_EQ(las.header().point_format, format);
        EXPECT_EQ(las.header().version_minor, minor);
        ASSERT_EQ(las.header().point_count, 3u);
        std::vector<LasPoint> points;
        las.read_points(0, 10, points);
        ASSERT_EQ(points.size(), 3u);
        for (std::size_t i = 0; i < 3; ++i) {
          const LasFixturePoint& want = f.points[i];
          EXPECT_NEAR(points[i].x, want.x, 0.0005);
          EXPECT_NEAR(points[i].y, want.y, 0.0005);
          EXPECT_NEAR(points[i].z, want.z, 0.0005);
          EXPECT_EQ(points[i].return_number, want.return_number);
          EXPECT_EQ(points[i].number_of_returns, want.number_of_returns);
          EXPECT_EQ(points[i].classification, want.classification);
          const bool timed = format != 0 && format != 2;
          EXPECT_EQ(points[i].gps_time, timed ? want.gps_time : 0.0);
        }
        points.clear();
        las.read_points(1, 1, points);  // a window of the points
        ASSERT_EQ(points.size(), 1u);
        EXPECT_NEAR(points[0].z, 99.5, 0.0005);
      }
    }
  }
}

TEST(LasReader, CrsFromWktGeoKeysOrFallback) {
  test_support::ScratchDir dir;
  LasFixture f = three_points(4, 6);
  f.wkt =
      R"(PROJCS["WGS 84 / UTM zone 33N",GEOGCS["WGS 84",DATUM["WGS_1984",SPHEROID["WGS 84",6378137,298.257223563]],PRIMEM["Greenwich",0],UNIT["degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],PARAMETER["latitude_of_origin",0],PARAMETER["central_meridian",15],PARAMETER["scale_factor",0.9996],PARAMETER["false_easting",500000],PARAMETER["false_northing",0],UNIT["metre",1],AUTHORITY["EPSG","32633"]])";
  test::write_las(dir.path() / "wkt.las", f);
  const std::string wkt = LasFile(dir.path() / "wkt.las").crs_wkt();
  EXPECT_NE(wkt.find("UTM zone 33N"), std::string::npos) << wkt;

  LasFixture g = three_points(2, 1);
  g.geo_keys = {1024, 1, 3072, 32618};  // projected, WGS 84 / UTM zone 18N
  test::write_las(dir.path() / "keys.las", g);
  EXPECT_NE(LasFile(dir.path() / "keys.las").crs_wkt().find("UTM zone 18N"), std::string::npos);

  g.geo_keys = {1024, 2, 2048, 4326};  // geographic
  test::write_las(dir.path() / "geo.las", g);
  EXPECT_NE(LasFile(dir.path() / "geo.las").crs_wkt().find("WGS 84"), std::string::npos);

  LasFixture none = three_points(2, 0);
  test::write_las(dir.path() / "none.las", none);
  const LasFile bare(dir.path() / "none.las");
  EXPECT_EQ(bare.crs_wkt(), "");
  EXPECT_NE(las_crs(bare, "EPSG:32633", "/canopy/point_cloud/crs").find("UTM zone 33N"),
            std::string::npos);
  try {
    las_crs(bare, "", "/canopy/point_cloud/crs");
    FAIL() << "a cloud without a CRS was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    EXPECT_NE(std::string(e.what()).find("no CRS"), std::string::npos) << e.what();
  }
  try {
    las_crs(bare, "EPSG:nonsense", "/canopy/point_cloud/crs");
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::config);
    EXPECT_EQ(e.place(), "/canopy/point_cloud/crs");
  }
  g.geo_keys = {1024, 1, 3072, 32767};  // user-defined: not read
  test::write_las(dir.path() / "user.las", g);
  EXPECT_NE(refusal(dir.path() / "user.las").find("user-defined"), std::string::npos);
}

// Issue 42: scan angles beyond 90 degrees gave every voxel a density of 0; a cloud in a
// geographic CRS was voxelised in degrees, one in US survey feet read as metres.
TEST(LasReader, ScanAnglesBeyondNadirsQuarterTurnAndCrsNotInMetresAreRefused) {
  test_support::ScratchDir dir;
  LasFixture wide = three_points(4, 6);
  wide.points[1].scan_angle_deg = 120.0;
  test::write_las(dir.path() / "wide.las", wide);
  EXPECT_NE(refusal(dir.path() / "wide.las")
                .find("point 1 has a scan angle of 120 degrees, beyond the LAS specification's"),
            std::string::npos)
      << refusal(dir.path() / "wide.las");
  LasFixture legacy = three_points(2, 1);
  legacy.points[2].scan_angle_deg = -100.0;  // an int8 holds it; the specification does not
  test::write_las(dir.path() / "legacy.las", legacy);
  EXPECT_NE(refusal(dir.path() / "legacy.las").find("scan angle of -100 degrees"),
            std::string::npos);
  legacy.points[2].scan_angle_deg = -90.0;
  test::write_las(dir.path() / "edge.las", legacy);
  EXPECT_EQ(refusal(dir.path() / "edge.las"), "");

  auto crs_refusal = [](const LasFile& cloud, const std::string& fallback) -> std::string {
    try {
      las_crs(cloud, fallback, "/canopy/point_cloud/crs");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  LasFixture g = three_points(2, 1);
  g.geo_keys = {1024, 2, 2048, 4326};  // geographic, from the file
  test::write_las(dir.path() / "geo.las", g);
  EXPECT_NE(crs_refusal(LasFile(dir.path() / "geo.las"), "")
                .find("the point cloud's CRS is "
                      "geographic (x and y in degrees)"),
            std::string::npos);
  test::write_las(dir.path() / "none.las", three_points(2, 0));
  const LasFile bare(dir.path() / "none.las");
  EXPECT_EQ(crs_refusal(bare, "EPSG:4326")
                .rfind("/canopy/point_cloud/crs: \"EPSG:4326\" is "
                       "geographic",
                       0),
            0u);
  // NAD83 / New York Long Island (ftUS): x and y in US survey feet, 1200/3937 m.
  EXPECT_NE(
      crs_refusal(bare, "EPSG:2263").find("measures x and y in US survey foot (0.3048006096 m)"),
      std::string::npos)
      << crs_refusal(bare, "EPSG:2263");
  // UTM in metres over NAVD88 heights in US survey feet (EPSG:6360).
  EXPECT_NE(crs_refusal(bare, "EPSG:32618+6360").find("measures heights in US survey foot"),
            std::string::npos)
      << crs_refusal(bare, "EPSG:32618+6360");
  EXPECT_EQ(crs_refusal(bare, "EPSG:32618+5703"), "");  // NAVD88 in metres
}

TEST(LasReader, RefusesMalformedFiles) {
  test_support::ScratchDir dir;
  LasFixture f = three_points(4, 7);
  f.wkt =
      "GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\",SPHEROID[\"WGS 84\",6378137,298.257223563]],"
      "PRIMEM[\"Greenwich\",0],UNIT[\"degree\",0.0174532925199433]]";
  const std::vector<std::uint8_t> good = test::las_bytes(f);
  test::write_bytes(dir.path() / "good.las", good);
  EXPECT_EQ(refusal(dir.path() / "good.las"), "");

  // Truncated at every length: never read, never a crash.
  for (std::size_t n = 0; n < good.size(); ++n) {
    const auto file = dir.path() / "cut.las";
    test::write_bytes(file, std::vector<std::uint8_t>(good.begin(), good.begin() + n));
    EXPECT_NE(refusal(file), "") << n << " bytes";
  }
  const auto edit = [&](const std::string& name, auto change) {
    std::vector<std::uint8_t> bad = good;
    change(bad);
    test::write_bytes(dir.path() / name, bad);
    return refusal(dir.path() / name);
  };
  // A header size that lies: smaller than 1.4's 375 bytes, or larger than the file.
  EXPECT_NE(edit("small_header.las", [](auto& b) { test::put_value<std::uint16_t>(b, 94, 227); })
                .find("header size 227"),
            std::string::npos);
  EXPECT_NE(edit("big_header.las", [](auto& b) { test::put_value<std::uint16_t>(b, 94, 60000); }),
            "");
  // Points starting inside the header or beyond the file.
  EXPECT_NE(edit("offset_in.las", [](auto& b) { test::put_value<std::uint32_t>(b, 96, 100); }), "");
  EXPECT_NE(
      edit("offset_out.las", [](auto& b) { test::put_value<std::uint32_t>(b, 96, 1u << 30); }), "");
  // Point counts beyond the file, 64-bit and legacy.
  EXPECT_NE(edit("count64.las", [](auto& b) { test::put_value<std::uint64_t>(b, 247, 4); })
                .find("4 points"),
            std::string::npos);
  EXPECT_NE(edit("count_huge.las",
                 [](auto& b) { test::put_value<std::uint64_t>(b, 247, ~std::uint64_t{0}); }),
            "");
  // A record length that runs into the points.
  EXPECT_NE(edit("vlr.las", [](auto& b) { test::put_value<std::uint16_t>(b, 375 + 20, 65535); })
                .find("runs into the points"),
            std::string::npos);
  // Unknown point formats, a record length shorter than the format's.
  EXPECT_NE(edit("format11.las", [](auto& b) { b[104] = 11; }).find("format 11"),
            std::string::npos);
  EXPECT_NE(edit("format63.las", [](auto& b) { b[104] = 63; }), "");
  EXPECT_NE(edit("short.las", [](auto& b) { test::put_value<std::uint16_t>(b, 105, 20); })
                .find("shorter"),
            std::string::npos);
  // Versions glaswave does not know; signature.
  EXPECT_NE(edit("v15.las", [](auto& b) { b[25] = 5; }).find("1.5"), std::string::npos);
  EXPECT_NE(edit("v2.las", [](auto& b) { b[24] = 2; }), "");
  EXPECT_NE(edit("sig.las", [](auto& b) { b[0] = 'X'; }).find("LASF"), std::string::npos);
  // Non-finite or zero scale.
  EXPECT_NE(edit("scale.las", [](auto& b) { test::put_value<double>(b, 131, 0.0); }), "");
  // EVLRs that start inside the points or past the end.
  EXPECT_NE(edit("evlr.las",
                 [](auto& b) {
                   test::put_value<std::uint32_t>(b, 243, 1);
                   test::put_value<std::uint64_t>(b, 235, 380);
                 }),
            "");
  EXPECT_NE(edit("evlr_end.las",
                 [&](auto& b) {
                   test::put_value<std::uint32_t>(b, 243, 1);
                   test::put_value<std::uint64_t>(b, 235, good.size());
                 }),
            "");
  // A WKT record that is not a CRS.
  EXPECT_NE(edit("wkt.las", [](auto& b) { b[375 + 54] = 'Q'; }).find("WKT"), std::string::npos);
}

TEST(LasReader, RefusesLazNamingHowToDecompress) {
  test_support::ScratchDir dir;
  std::vector<std::uint8_t> b = test::las_bytes(three_points(2, 1));
  b[104] |= 0x80;  // LASzip's compressed-format bit
  test::write_bytes(dir.path() / "cloud.las", b);
  const std::string message = refusal(dir.path() / "cloud.las");
  EXPECT_NE(message.find("laszip"), std::string::npos) << message;
  EXPECT_NE(message.find("pdal translate"), std::string::npos) << message;
  EXPECT_EQ(message.find('\n'), std::string::npos);
  test::write_las(dir.path() / "cloud.laz", three_points(2, 1));
  EXPECT_NE(refusal(dir.path() / "cloud.laz").find("laszip"), std::string::npos);
  EXPECT_NE(refusal(dir.path() / "missing.las").find("no such"), std::string::npos);
}

}  // namespace
}  // namespace glaswave
