// DEMs that were read silently wrong or waited on, each found by tests/reliability/inputs_tried.py:
// heights in an unknown unit (read as metres) or in centimetres, complex and paletted bands (read
// as heights), an explicit terrain.vertical_datum overridden by the DEM's own, a scale of 1e308
// (blamed on PROJ), a BigTIFF cut short (reported as without a CRS), a path with a NUL byte (cut
// there), and inputs that are no regular file: a VRT whose source is a FIFO, /vsistdin/,
// /proc/self/mem (all refused before GDAL opens them, not waited on).
#include <gdal_priv.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <fstream>
#include <string>

#include "core/error.hpp"
#include "terrain/dem_terrain.hpp"
#include "tests/terrain/dem_fixture.hpp"

namespace glaswave {
namespace {

using ::testing::HasSubstr;
using testing::RasterSpec;
using testing::TempFolder;

constexpr double kLat = 46.0, kLon = 8.0;

RasterSpec geographic(GDALDataType type = GDT_Float32, const std::string& crs = "EPSG:4326") {
  RasterSpec spec;
  spec.crs = crs;
  spec.geotransform = {kLon - 0.005, 0.0005, 0.0, kLat + 0.005, 0.0, -0.0005};
  spec.width = spec.height = 20;
  spec.type = type;
  return spec;
}

// A raster of `value` everywhere, then `edit` applied to its first band.
std::string write_dem(const TempFolder& dir, const std::string& name, double value,
                      const std::function<void(GDALRasterBand*)>& edit = {},
                      const RasterSpec& spec = geographic()) {
  const std::string file = (dir / name).string();
  testing::write_raster(file, spec, [&](int, int, int) { return value; });
  if (edit) {
    GDALDataset* dataset = GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_UPDATE);
    edit(dataset->GetRasterBand(1));
    GDALClose(dataset);
  }
  return file;
}

TerrainSettings settings_of(const std::string& file, const std::string& datum = "ellipsoid",
                            bool datum_given = false) {
  TerrainSettings settings;
  settings.dem = file;
  settings.vertical_datum = datum;
  settings.vertical_datum_given = datum_given;
  return settings;
}

// The error opening `settings` gives (its kind and message), or "" when it opens.
std::string refusal(const TerrainSettings& settings, ErrorKind expected = ErrorKind::input) {
  try {
    const DemTerrain dem(settings);
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), expected) << e.what();
    return e.what();
  }
  return "";
}

TEST(DemInputs, HeightsInKnownUnitsAreConvertedAndUnknownUnitsRefused) {
  const TempFolder dir;
  const DemTerrain metres(settings_of(write_dem(dir, "m.tif", 900.0)));
  const DemTerrain cm(settings_of(
      write_dem(dir, "cm.tif", 90000.0, [](GDALRasterBand* b) { b->SetUnitType("cm"); })));
  const DemTerrain feet(settings_of(
      write_dem(dir, "ft.tif", 900.0 / 0.3048, [](GDALRasterBand* b) { b->SetUnitType("ft"); })));
  const double h = metres.height_m(kLat, kLon);
  EXPECT_NEAR(h, 900.0, 1e-6);
  EXPECT_NEAR(cm.height_m(kLat, kLon), h, 1e-6);
  EXPECT_NEAR(feet.height_m(kLat, kLon), h, 1e-3);  // 900 m in feet stored in float32
  const std::string furlong =
      write_dem(dir, "furlong.tif", 4.5, [](GDALRasterBand* b) { b->SetUnitType("furlong"); });
  EXPECT_EQ(refusal(settings_of(furlong)),
            furlong +
                ": the DEM's heights are in \"furlong\", a unit glaswave does not know (it "
                "converts m, dm, cm, mm, km, ft and US survey ft); set the band's unit "
                "with gdal_edit.py -units");
}

TEST(DemInputs, ComplexAndPalettedBandsAreNoHeights) {
  const TempFolder dir;
  const std::string complex = write_dem(dir, "complex.tif", 900.0, {}, geographic(GDT_CFloat32));
  EXPECT_EQ(refusal(settings_of(complex)),
            complex + ": band 1 of the DEM holds complex numbers (CFloat32), not heights");
  const std::string paletted = write_dem(
      dir, "paletted.tif", 3.0,
      [](GDALRasterBand* b) {
        GDALColorTable table;
        for (int i = 0; i < 4; ++i) {
          const GDALColorEntry entry{static_cast<short>(60 * i), 0, 0, 255};
          table.SetColorEntry(i, &entry);
        }
        b->SetColorTable(&table);
      },
      geographic(GDT_Byte));
  EXPECT_EQ(refusal(settings_of(paletted)),
            paletted + ": band 1 of the DEM is paletted (colour indices, not heights)");
}

TEST(DemInputs, AScaleOrOffsetOffTheEarthIsRefusedAsSuch) {
  const TempFolder dir;
  const std::string huge =
      write_dem(dir, "scale.tif", 1.0, [](GDALRasterBand* b) { b->SetScale(1e308); });
  EXPECT_EQ(refusal(settings_of(huge)),
            huge +
                ": the DEM's scale gives 1e+308 m per stored unit, outside (0, 10000] m: no "
                "height on the Earth");
  const std::string offset =
      write_dem(dir, "offset.tif", 1.0, [](GDALRasterBand* b) { b->SetOffset(-1e9); });
  EXPECT_THAT(refusal(settings_of(offset)), HasSubstr("the DEM's offset is -1e+09 m"));
}

TEST(DemInputs, AnExplicitVerticalDatumIsNotOverriddenByTheDemsOwn) {
  const TempFolder dir;
  const std::string compound =
      write_dem(dir, "compound.tif", 500.0, {}, geographic(GDT_Float32, "EPSG:4326+5773"));
  // Not given: the DEM's own; given as the DEM's own: the same; given as another: refused.
  EXPECT_EQ(DemTerrain(settings_of(compound)).vertical_datum().key, "EPSG:5773");
  EXPECT_EQ(DemTerrain(settings_of(compound, "egm96", true)).vertical_datum().key, "EPSG:5773");
  const std::string conflict = refusal(settings_of(compound, "ellipsoid", true), ErrorKind::config);
  EXPECT_EQ(conflict, "vertical_datum: is \"ellipsoid\", but the DEM " + compound +
                          " has its own vertical CRS, EGM96 height (EPSG:5773): remove "
                          "terrain.vertical_datum to use the DEM's, or give the DEM's (glaswave "
                          "does not override a DEM's own datum)");
}

TEST(DemInputs, ATruncatedBigTiffIsReportedAsTruncated) {
  const TempFolder dir;
  const std::string whole = (dir / "big.tif").string();
  {
    GDALAllRegister();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
    const char* const options[] = {"BIGTIFF=YES", nullptr};
    GDALDataset* dataset =
        driver->Create(whole.c_str(), 200, 200, 1, GDT_Float32, const_cast<char**>(options));
    RasterSpec spec = geographic();
    dataset->SetGeoTransform(spec.geotransform.data());
    OGRSpatialReference srs;
    srs.SetFromUserInput("EPSG:4326");
    dataset->SetSpatialRef(&srs);
    std::vector<float> values(200 * 200, 900.0f);
    ASSERT_EQ(dataset->GetRasterBand(1)->RasterIO(GF_Write, 0, 0, 200, 200, values.data(), 200, 200,
                                                  GDT_Float32, 0, 0),
              CE_None);
    GDALClose(dataset);
  }
  std::ifstream in(whole, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  // Cut inside its GeoKeys (after the directory, before the data): GDAL opens it without a CRS.
  const std::string cut = (dir / "cut.tif").string();
  std::ofstream(cut, std::ios::binary) << bytes.substr(0, 360);
  EXPECT_THAT(refusal(settings_of(cut)),
              HasSubstr(cut + ": the DEM is truncated or corrupt: its data cannot be read"));
}

TEST(DemInputs, WhatIsNoRegularFileIsRefusedBeforeGdalOpensIt) {
  const TempFolder dir;
  const std::string fifo = (dir / "fifo.tif").string();
  ASSERT_EQ(mkfifo(fifo.c_str(), 0600), 0);
  const std::string vrt = (dir / "dem.vrt").string();
  std::ofstream(vrt) << R"(<VRTDataset rasterXSize="20" rasterYSize="20">
  <SRS>EPSG:4326</SRS><GeoTransform>7.995, 0.0005, 0, 46.005, 0, -0.0005</GeoTransform>
  <VRTRasterBand dataType="Float32" band="1"><SimpleSource>
    <SourceFilename relativeToVRT="1">fifo.tif</SourceFilename><SourceBand>1</SourceBand>
  </SimpleSource></VRTRasterBand></VRTDataset>)";
  EXPECT_EQ(refusal(settings_of(vrt)),
            fifo + ": cannot read the DEM's VRT source: it is a FIFO (a pipe), not a regular file");
  EXPECT_EQ(refusal(settings_of("/vsistdin/")),
            "/vsistdin/: cannot read the DEM from /vsistdin/, a stream that GDAL would wait on: "
            "give a file (or /vsizip/, /vsimem/ ...)");
  EXPECT_EQ(refusal(settings_of("/vsizip/" + fifo + "/dem.tif")),
            fifo + ": cannot read the DEM: it is a FIFO (a pipe), not a regular file");
  EXPECT_EQ(refusal(settings_of("/proc/self/mem")),
            "/proc/self/mem: cannot read the DEM: a pseudo-file of /proc or /sys, not a file of "
            "data");
  const std::string good = write_dem(dir, "good.tif", 900.0);
  EXPECT_THAT(refusal(settings_of(good + std::string("\0.ignored", 9))),
              HasSubstr("a path must not hold a NUL byte"));
}

// Issue 42: two VRTs sourcing each other were refused at the second, named "the DEM's VRT
// source's VRT source's ..." nine times; a pixel of 1e-300 degrees was blamed on PROJ.
TEST(DemInputs, VrtsSourcingEachOtherAndAPixelOfNothingAreNamedForWhatTheyAre) {
  const TempFolder dir;
  const auto vrt_over = [&](const std::string& name, const std::string& source) {
    const std::string file = (dir / name).string();
    std::ofstream(file) << R"(<VRTDataset rasterXSize="20" rasterYSize="20">
  <SRS>EPSG:4326</SRS><GeoTransform>7.995, 0.0005, 0, 46.005, 0, -0.0005</GeoTransform>
  <VRTRasterBand dataType="Float32" band="1"><SimpleSource>
    <SourceFilename relativeToVRT="1">)"
                        << source << R"(</SourceFilename><SourceBand>1</SourceBand>
  </SimpleSource></VRTRasterBand></VRTDataset>)";
    return file;
  };
  const std::string a = vrt_over("a.vrt", "b.vrt");
  vrt_over("b.vrt", "a.vrt");
  EXPECT_EQ(refusal(settings_of(a)),
            a + ": cannot read the DEM's VRT source: its VRTs source each other (a.vrt -> b.vrt "
                "-> a.vrt)");
  // A chain of ten, each naming the next: deeper than 8, named at the first.
  const auto chained = [](int i) { return std::string("c").append(std::to_string(i)) + ".vrt"; };
  for (int i = 0; i < 10; ++i) vrt_over(chained(i), chained(i + 1));
  write_dem(dir, "c10.vrt", 900.0);
  EXPECT_THAT(refusal(settings_of((dir / "c0.vrt").string())),
              HasSubstr("c0.vrt: cannot read the DEM's VRT source: VRTs nested deeper than 8 "
                        "(c0.vrt -> c1.vrt"));

  RasterSpec tiny = geographic();
  tiny.geotransform = {kLon, 1e-300, 0.0, kLat, 0.0, -1e-300};
  const std::string pixel = write_dem(dir, "tiny.tif", 900.0, {}, tiny);
  EXPECT_THAT(refusal(settings_of(pixel)),
              HasSubstr("tiny.tif: the DEM's nodes are 0 m apart (its geotransform's pixel is "
                        "1e-300 by 1e-300 in its CRS's units), under the 0.001 m a DEM may have"));
}

}  // namespace
}  // namespace glaswave
