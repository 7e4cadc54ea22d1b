// Tests of the footprints (footprints.geojson, footprints.gpkg): written from hand-made records
// out of order, then read back through GDAL/OGR as QGIS and ogrinfo would (no warning allowed),
// and the GeoJSON as plain JSON for what RFC 7946 asks of the text itself (no crs, no NaN,
// 8-decimal coordinates, counter-clockwise exterior rings within +-180 degrees).
#include "pipeline/products/ogr_writer.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <numbers>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "pipeline/products/product_fields.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr int kShots = 3;

RunInfo make_info() {
  RunInfo info;
  info.command_line = "glaswave run demo.json";
  info.config_json = "{}";
  info.seed = 7;
  info.shots = kShots;
  info.bands = {ProductBand{"532", 532.0}, ProductBand{"1064", 1064.0}};
  info.bin_time_ns = {0.0, 1.0, 2.0};
  info.tx_time_ns = {-1.0, 0.0, 1.0};
  info.tx_waveform_W = {{1.0, 2.0, 1.0}, {1.0, 2.0, 1.0}};
  return info;
}

// A closed octagon about (lon, lat), counter-clockwise (angle increasing in the lon/lat plane),
// with more decimals than the product keeps.
std::vector<std::array<double, 2>> octagon(double lon, double lat) {
  std::vector<std::array<double, 2>> ring;
  for (int k = 0; k < 8; ++k) {
    const double angle = 2.0 * std::numbers::pi * k / 8.0;
    ring.push_back(
        {lon + 0.00038123456789 * std::cos(angle), lat + 0.00031987654321 * std::sin(angle)});
  }
  ring.push_back(ring.front());
  return ring;
}

ShotRecord make_record(int record) {
  ShotRecord shot;
  shot.shot_number = 100 + record;
  shot.source_shot_number = shot.shot_number;  // a synthetic track: the instrument's is the shot
  shot.time_s = 183254400.0 + 0.025 * record;
  shot.lat_deg = 34.3 + 0.0015 * record;
  shot.lon_deg = -118.123456789012 + 0.0003 * record;
  shot.elev_m = 1200.5 + record;
  shot.sc_lat_deg = 34.2;
  shot.sc_lon_deg = -118.21;
  shot.sc_alt_m = 600000.0;
  shot.off_nadir_deg = 0.3;
  shot.range_m = 598800.0 - record;
  shot.slope_deg = 10.0 + record;  // integral values on purpose: the field must still be Real
  shot.aspect_deg = record == 0 ? std::nan("") : 270.0;  // no aspect on flat ground
  shot.elev_bin0_m = 1260.0;
  shot.elev_lastbin_m = 1180.0;
  shot.quality_flag = quality_good;
  shot.rx_energy_J = {1e-15 * (record + 1), 2e-15};
  shot.rx_energy_canopy_J = {0.6e-15 * (record + 1), 1e-15};
  shot.rx_energy_ground_J = {0.4e-15 * (record + 1), 1e-15};
  shot.reflectance = {0.1 * (record + 1), 0.5};
  shot.energy_tr_J = {1e-15 * (record + 1), 2e-15};
  shot.energy_cr_J = {0.7e-15 * (record + 1), 1e-15};
  shot.energy_gr_J = {0.3e-15 * (record + 1), 1e-15};
  shot.waveform_index = {0.4, 0.0};
  shot.sig_begin_m = {1230.5 + record, 1231.0};
  shot.sig_end_m = {1198.25 + record, 1198.0};
  shot.centroid_m = {1215.125 + record, 1215.0};
  shot.ground_elev_est_m = {1200.75 + record, 1200.5};
  shot.canopy_height_est_m = {27.5 + record, 28.0};
  shot.n_peaks = {3 + record, 2};
  shot.rh_m.assign(2, std::vector<double>(101, 0.0));
  for (int k = 0; k <= 100; ++k) shot.rh_m[0][k] = -1.5 + 0.3 * k + record;
  shot.cover_true = 0.65;
  shot.pai_true = 3.0;
  shot.canopy_height_true_m = 31.0 + record;
  shot.pgap_true = 0.45;
  shot.footprint_lonlat = octagon(shot.lon_deg, shot.lat_deg);
  return shot;
}

ShotRecord make_flagged_record(int record) {
  ShotRecord shot = make_record(record);
  shot.quality_flag = quality_invalid;
  shot.elev_m = std::nan("");
  shot.rx_energy_J.clear();
  shot.rx_energy_canopy_J.clear();
  shot.rx_energy_ground_J.clear();
  shot.reflectance.clear();
  for (auto field :
       {&ShotRecord::energy_tr_J, &ShotRecord::energy_cr_J, &ShotRecord::energy_gr_J,
        &ShotRecord::waveform_index, &ShotRecord::sig_begin_m, &ShotRecord::sig_end_m,
        &ShotRecord::centroid_m, &ShotRecord::ground_elev_est_m, &ShotRecord::canopy_height_est_m})
    (shot.*field).clear();
  shot.n_peaks.clear();
  shot.rh_m.clear();
  shot.cover_true = shot.pai_true = shot.canopy_height_true_m = shot.pgap_true = std::nan("");
  shot.footprint_lonlat.clear();
  return shot;
}

// Counts GDAL warnings and errors, keeping their text for the failure message.
struct GdalMessages {
  int count = 0;
  std::string text;
};

void CPL_STDCALL collect_gdal_message(CPLErr level, CPLErrorNum, const char* message) {
  auto* messages = static_cast<GdalMessages*>(CPLGetErrorHandlerUserData());
  if (level >= CE_Warning) {
    ++messages->count;
    messages->text += std::string(message) + "\n";
  }
}

class OgrWriterTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { GDALAllRegister(); }
  void TearDown() override {
    if (HasFailure()) dir_.keep();  // kept for inspection when a test fails
  }
  fs::path file() const { return dir_ / "footprints.geojson"; }
  fs::path part() const { return dir_ / "footprints.geojson.part"; }

  void write_product() const {
    OgrWriter writer(file(), FootprintsFormat::geojson, make_info());
    for (int record : {2, 1, 0})
      writer.write(record, record == 1 ? make_flagged_record(1) : make_record(record));
    writer.finish(RunStats{10, 1.0, 1});
  }

  std::string text() const {
    std::ifstream in(file());
    std::stringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
  }

  test_support::ScratchDir dir_{"glaswave_geojson"};
};

TEST_F(OgrWriterTest, FinalFileAndNoPart) {
  write_product();
  EXPECT_TRUE(fs::exists(file()));
  EXPECT_FALSE(fs::exists(part()));
}

TEST_F(OgrWriterTest, OgrReadsItWithoutWarnings) {
  write_product();
  GdalMessages messages;
  CPLPushErrorHandlerEx(collect_gdal_message, &messages);
  GDALDatasetUniquePtr dataset(GDALDataset::FromHandle(
      GDALOpenEx(file().c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  std::vector<OGRFeatureUniquePtr> features;
  OGRLayer* layer = dataset ? dataset->GetLayer(0) : nullptr;
  if (layer != nullptr) {
    // Reading every feature, not only opening, is what ogrinfo does.
    for (auto& feature : *layer) features.emplace_back(feature.release());
  }
  CPLPopErrorHandler();
  EXPECT_EQ(messages.count, 0) << messages.text;
  ASSERT_TRUE(dataset);
  ASSERT_NE(layer, nullptr);
  EXPECT_STREQ(dataset->GetDriver()->GetDescription(), "GeoJSON");

  EXPECT_EQ(dataset->GetLayerCount(), 1);
  EXPECT_EQ(layer->GetFeatureCount(), kShots);
  EXPECT_EQ(wkbFlatten(layer->GetGeomType()), wkbPolygon);
  const OGRSpatialReference* crs = layer->GetSpatialRef();
  ASSERT_NE(crs, nullptr);
  EXPECT_TRUE(crs->IsGeographic());

  const OGRFeatureDefn* definition = layer->GetLayerDefn();
  std::vector<std::string> reals = {
      "time",         "lat",        "lon",        "elev",
      "sc_lat",       "sc_lon",     "sc_alt",     "off_nadir_deg",
      "range_m",      "slope_deg",  "aspect_deg", "elev_bin0",
      "elev_lastbin", "cover_true", "pai_true",   "canopy_height_true",
      "pgap_true"};
  std::vector<std::string> integers = {"shot_number", "quality_flag"};
  // Every band's values, each under its name suffixed with the band's.
  for (const char* band : {"_532", "_1064"}) {
    for (const std::string name :
         {"rx_energy", "rx_energy_canopy", "rx_energy_ground", "reflectance", "energy_tr",
          "energy_cr", "energy_gr", "waveform_index", "sig_begin_m", "sig_end_m", "centroid_m",
          "ground_elev_est", "canopy_height_est", "rh25", "rh50", "rh75", "rh98", "rh100"})
      reals.push_back(name + band);
    integers.push_back(std::string("n_peaks") + band);
  }
  for (const std::string& name : reals) {
    const int index = definition->GetFieldIndex(name.c_str());
    ASSERT_GE(index, 0) << name;
    EXPECT_EQ(definition->GetFieldDefn(index)->GetType(), OFTReal) << name;
  }
  for (const std::string& name : integers) {
    const int index = definition->GetFieldIndex(name.c_str());
    ASSERT_GE(index, 0) << name;
    const OGRFieldType type = definition->GetFieldDefn(index)->GetType();
    EXPECT_TRUE(type == OFTInteger || type == OFTInteger64) << name;
  }
  // No unsuffixed per-band value: a reader cannot mistake one band's for another's.
  for (const char* name : {"reflectance", "energy_tr", "rh98", "n_peaks"})
    EXPECT_LT(definition->GetFieldIndex(name), 0) << name;
  EXPECT_EQ(definition->GetFieldCount(), 23 + 2 * 19);

  // Features come in record order although they were written 2, 1, 0.
  ASSERT_EQ(features.size(), 3u);
  for (int record = 0; record < kShots; ++record) {
    const OGRFeature& feature = *features[record];
    const ShotRecord expected = record == 1 ? make_flagged_record(1) : make_record(record);
    EXPECT_EQ(feature.GetFieldAsInteger64("shot_number"), expected.shot_number);
    EXPECT_EQ(feature.GetFieldAsDouble("time"), expected.time_s);
    EXPECT_EQ(feature.GetFieldAsDouble("lat"), expected.lat_deg);
    EXPECT_EQ(feature.GetFieldAsDouble("lon"), expected.lon_deg);
    EXPECT_EQ(feature.GetFieldAsDouble("slope_deg"), expected.slope_deg);
    EXPECT_EQ(feature.GetFieldAsInteger("quality_flag"), expected.quality_flag);
  }

  // A good shot: its polygon, first vertex to the 8 decimals kept, counter-clockwise as given.
  const OGRFeature& first = *features[0];
  const ShotRecord record0 = make_record(0);
  const OGRGeometry* geometry = first.GetGeometryRef();
  ASSERT_NE(geometry, nullptr);
  ASSERT_EQ(wkbFlatten(geometry->getGeometryType()), wkbPolygon);
  const OGRLinearRing* ring = geometry->toPolygon()->getExteriorRing();
  ASSERT_NE(ring, nullptr);
  ASSERT_EQ(ring->getNumPoints(), static_cast<int>(record0.footprint_lonlat.size()));
  EXPECT_NEAR(ring->getX(0), record0.footprint_lonlat[0][0], 0.51e-8);
  EXPECT_NEAR(ring->getY(0), record0.footprint_lonlat[0][1], 0.51e-8);
  EXPECT_NEAR(ring->getX(2), record0.footprint_lonlat[2][0], 0.51e-8);
  EXPECT_NEAR(ring->getY(2), record0.footprint_lonlat[2][1], 0.51e-8);
  EXPECT_FALSE(ring->isClockwise());
  EXPECT_EQ(geometry->toPolygon()->getNumInteriorRings(), 0);
  EXPECT_TRUE(first.IsFieldNull(definition->GetFieldIndex("aspect_deg")))
      << "NaN must read back as null";
  EXPECT_DOUBLE_EQ(first.GetFieldAsDouble("reflectance_532"), record0.reflectance[0]);
  EXPECT_DOUBLE_EQ(first.GetFieldAsDouble("reflectance_1064"), record0.reflectance[1]);
  EXPECT_DOUBLE_EQ(first.GetFieldAsDouble("rx_energy_532"), record0.rx_energy_J[0]);
  EXPECT_DOUBLE_EQ(first.GetFieldAsDouble("rx_energy_ground_1064"), record0.rx_energy_ground_J[1]);
  // Each band's waveform metrics, and the footprint's truth.
  for (int record : {0, 2}) {
    const OGRFeature& feature = *features[record];
    const ShotRecord expected = make_record(record);
    for (std::size_t band : {0u, 1u}) {
      const std::string suffix = band == 0 ? "_532" : "_1064";
      auto value = [&](const char* name) {
        return feature.GetFieldAsDouble((name + suffix).c_str());
      };
      EXPECT_DOUBLE_EQ(value("energy_tr"), expected.energy_tr_J[band]);
      EXPECT_DOUBLE_EQ(value("energy_cr"), expected.energy_cr_J[band]);
      EXPECT_DOUBLE_EQ(value("energy_gr"), expected.energy_gr_J[band]);
      EXPECT_DOUBLE_EQ(value("waveform_index"), expected.waveform_index[band]);
      EXPECT_DOUBLE_EQ(value("sig_begin_m"), expected.sig_begin_m[band]);
      EXPECT_DOUBLE_EQ(value("sig_end_m"), expected.sig_end_m[band]);
      EXPECT_DOUBLE_EQ(value("centroid_m"), expected.centroid_m[band]);
      EXPECT_DOUBLE_EQ(value("ground_elev_est"), expected.ground_elev_est_m[band]);
      EXPECT_DOUBLE_EQ(value("canopy_height_est"), expected.canopy_height_est_m[band]);
      EXPECT_EQ(feature.GetFieldAsInteger(("n_peaks" + suffix).c_str()), expected.n_peaks[band]);
      for (int k : {25, 50, 75, 98, 100})
        EXPECT_DOUBLE_EQ(value(("rh" + std::to_string(k)).c_str()), expected.rh_m[band][k])
            << k << suffix;
    }
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("cover_true"), expected.cover_true);
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("pai_true"), expected.pai_true);
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("canopy_height_true"), expected.canopy_height_true_m);
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("pgap_true"), expected.pgap_true);
  }

  // The flagged shot: no geometry, no metrics, its position still there.
  const OGRFeature& flagged = *features[1];
  EXPECT_EQ(flagged.GetGeometryRef(), nullptr);
  EXPECT_EQ(flagged.GetFieldAsInteger("quality_flag"), quality_invalid);
  for (const char* name :
       {"elev", "rx_energy_532", "rx_energy_canopy_1064", "rx_energy_ground_532",
        "reflectance_1064", "energy_tr_1064", "ground_elev_est_532", "canopy_height_est_1064",
        "n_peaks_532", "n_peaks_1064", "rh98_1064", "cover_true"}) {
    EXPECT_TRUE(flagged.IsFieldNull(definition->GetFieldIndex(name))) << name;
  }
  EXPECT_FALSE(flagged.IsFieldNull(definition->GetFieldIndex("lat")));
}

// The words of `text`, in order.
std::vector<std::string> words(const std::string& text) {
  std::istringstream in(text);
  std::vector<std::string> out;
  for (std::string word; in >> word;) out.push_back(word);
  return out;
}

// The properties of every Feature, in their order, are the contract's (docs/reference/products.md,
// PRODUCT.md section 4), written out here: the shot's scalars, then each per-band value under
// its name suffixed with each band's in turn, rh at GEDI's usual levels, then the truth. Taken
// from the writer's own table, a renamed property would pass.
TEST_F(OgrWriterTest, PropertiesAreTheContracts) {
  write_product();
  const nlohmann::json document = nlohmann::json::parse(text());
  const std::vector<std::string> expected = words(
      "shot_number time lat lon elev sc_lat sc_lon sc_alt off_nadir_deg range_m slope_deg "
      "aspect_deg elev_bin0 elev_lastbin quality_flag beam degrade_flag solar_elevation "
      "solar_azimuth "
      "rx_energy_532 rx_energy_1064 rx_energy_canopy_532 rx_energy_canopy_1064 "
      "rx_energy_ground_532 rx_energy_ground_1064 reflectance_532 reflectance_1064 "
      "energy_tr_532 energy_tr_1064 energy_cr_532 energy_cr_1064 energy_gr_532 energy_gr_1064 "
      "waveform_index_532 waveform_index_1064 sig_begin_m_532 sig_begin_m_1064 "
      "sig_end_m_532 sig_end_m_1064 centroid_m_532 centroid_m_1064 n_peaks_532 n_peaks_1064 "
      "ground_elev_est_532 ground_elev_est_1064 canopy_height_est_532 canopy_height_est_1064 "
      "rh25_532 rh50_532 rh75_532 rh98_532 rh100_532 rh25_1064 rh50_1064 rh75_1064 rh98_1064 "
      "rh100_1064 "
      "cover_true pai_true canopy_height_true pgap_true");
  ASSERT_EQ(expected.size(), 23u + 2 * 19u);
  for (const auto& feature : document.at("features")) {
    std::vector<std::string> names;
    for (const auto& [name, value] : feature.at("properties").items()) names.push_back(name);
    // nlohmann::json sorts object keys; the file's order is checked on the text below.
    std::vector<std::string> sorted = expected;
    std::sort(sorted.begin(), sorted.end());
    std::vector<std::string> missing, extra;
    std::set_difference(sorted.begin(), sorted.end(), names.begin(), names.end(),
                        std::back_inserter(missing));
    std::set_difference(names.begin(), names.end(), sorted.begin(), sorted.end(),
                        std::back_inserter(extra));
    EXPECT_EQ(names, sorted) << "missing: " << testing::PrintToString(missing)
                             << ", not in the contract: " << testing::PrintToString(extra);
  }
  // Order in the text of the first Feature: each property after the one before it.
  const std::string content = text();
  // OGR writes a Feature's properties before its geometry.
  const std::size_t end_of_first = content.find("\"geometry\"");
  ASSERT_NE(end_of_first, std::string::npos);
  std::size_t at = 0;
  for (const std::string& name : expected) {
    const std::size_t found = content.find("\"" + name + "\":", at);
    ASSERT_LT(found, end_of_first) << name << " out of order";
    at = found;
  }
}

// RFC 7946 section 3.1.9: a footprint across the antimeridian is cut there into a MultiPolygon
// whose parts lie either side, together the octagon's area; one clear of it stays a Polygon.
TEST_F(OgrWriterTest, FootprintAcrossTheAntimeridianIsCut) {
  RunInfo info = make_info();
  info.shots = 2;
  {
    OgrWriter writer(file(), FootprintsFormat::geojson, info);
    ShotRecord across = make_record(0), clear = make_record(1);
    across.footprint_lonlat = octagon(179.9998, 12.0);
    for (auto& p : across.footprint_lonlat)
      if (p[0] > 180.0) p[0] -= 360.0;  // as the simulation gives it: within [-180, 180]
    clear.footprint_lonlat = octagon(179.99, 12.0);
    writer.write(0, across);
    writer.write(1, clear);
    writer.finish(RunStats{});
  }
  GDALDatasetUniquePtr dataset(GDALDataset::FromHandle(
      GDALOpenEx(file().c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  ASSERT_TRUE(dataset);
  OGRLayer* layer = dataset->GetLayer(0);
  std::vector<OGRFeatureUniquePtr> features;
  for (auto& feature : *layer) features.emplace_back(feature.release());
  ASSERT_EQ(features.size(), 2u);
  const OGRGeometry* cut = features[0]->GetGeometryRef();
  ASSERT_EQ(wkbFlatten(cut->getGeometryType()), wkbMultiPolygon);
  const OGRMultiPolygon* parts = cut->toMultiPolygon();
  ASSERT_EQ(parts->getNumGeometries(), 2);
  OGREnvelope west, east;
  parts->getGeometryRef(0)->getEnvelope(&west);
  parts->getGeometryRef(1)->getEnvelope(&east);
  EXPECT_NEAR(west.MaxX, 180.0, 1e-9);
  EXPECT_NEAR(east.MinX, -180.0, 1e-9);
  EXPECT_GT(west.MinX, 179.999);
  EXPECT_LT(east.MaxX, -179.999);
  // The octagon's area: 8/2 sin(45 deg) a b with its semi-axes.
  const double area = 4.0 * std::sin(std::numbers::pi / 4.0) * 0.00038123456789 * 0.00031987654321;
  EXPECT_NEAR(parts->getGeometryRef(0)->get_Area() + parts->getGeometryRef(1)->get_Area(), area,
              1e-6 * area + 1e-14);
  EXPECT_EQ(wkbFlatten(features[1]->GetGeometryRef()->getGeometryType()), wkbPolygon);
}

// Every exterior ring of `geometry` (a Polygon or a MultiPolygon's parts): checks `check`.
template <typename Check>
void for_each_exterior_ring(const OGRGeometry& geometry, Check check) {
  if (wkbFlatten(geometry.getGeometryType()) == wkbPolygon) {
    check(*geometry.toPolygon()->getExteriorRing());
    return;
  }
  ASSERT_EQ(wkbFlatten(geometry.getGeometryType()), wkbMultiPolygon);
  for (const OGRPolygon* part : *geometry.toMultiPolygon()) check(*part->getExteriorRing());
}

// Twice the signed area of a ring in the lon/lat plane, computed here from its points (not with
// OGR's isClockwise): positive when counter-clockwise.
double twice_signed_area(const OGRLinearRing& ring) {
  double sum = 0.0;
  for (int i = 0; i + 1 < ring.getNumPoints(); ++i)
    sum += ring.getX(i) * ring.getY(i + 1) - ring.getX(i + 1) * ring.getY(i);
  return sum;
}

// A track across the antimeridian, eastward then westward, with rings given counter-clockwise
// and clockwise, in both formats: every exterior ring is counter-clockwise (RFC 7946 section
// 3.1.6) and every position within [-180, 180]; the footprints over the line are cut in two.
TEST_F(OgrWriterTest, AntimeridianTrackRingsAreCounterClockwiseWithinRange) {
  constexpr int kTrack = 9;
  for (const FootprintsFormat format : {FootprintsFormat::geojson, FootprintsFormat::gpkg}) {
    const fs::path path =
        dir_ / (format == FootprintsFormat::gpkg ? "track.gpkg" : "track.geojson");
    RunInfo info = make_info();
    info.shots = kTrack;
    {
      OgrWriter writer(path, format, info);
      for (int record = kTrack - 1; record >= 0; --record) {
        ShotRecord shot = make_record(record);
        // 179.9990 ... 180.0010 (wrapped past 180), 0.00025 degree apart: the octagons of
        // shots 3 to 5 straddle the line.
        double lon = 179.999 + 0.00025 * record;
        if (lon > 180.0) lon -= 360.0;
        shot.footprint_lonlat = octagon(lon, -5.0 + 0.001 * record);
        for (auto& p : shot.footprint_lonlat) p[0] = std::remainder(p[0], 360.0);
        if (record % 2 == 1)  // clockwise as given
          std::reverse(shot.footprint_lonlat.begin(), shot.footprint_lonlat.end());
        writer.write(record, shot);
      }
      writer.finish(RunStats{});
    }
    GdalMessages messages;
    CPLPushErrorHandlerEx(collect_gdal_message, &messages);
    GDALDatasetUniquePtr dataset(GDALDataset::FromHandle(
        GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
    std::vector<OGRFeatureUniquePtr> features;
    if (dataset)
      for (auto& feature : *dataset->GetLayer(0)) features.emplace_back(feature.release());
    CPLPopErrorHandler();
    EXPECT_EQ(messages.count, 0) << messages.text;
    ASSERT_EQ(features.size(), static_cast<std::size_t>(kTrack)) << path;
    int cut = 0, rings = 0;
    for (int record = 0; record < kTrack; ++record) {
      const OGRGeometry* geometry = features[record]->GetGeometryRef();
      ASSERT_NE(geometry, nullptr) << record;
      EXPECT_EQ(features[record]->GetFieldAsInteger64("shot_number"), 100 + record);
      if (wkbFlatten(geometry->getGeometryType()) == wkbMultiPolygon &&
          geometry->toMultiPolygon()->getNumGeometries() == 2)
        ++cut;
      for_each_exterior_ring(*geometry, [&](const OGRLinearRing& ring) {
        ++rings;
        EXPECT_GT(twice_signed_area(ring), 0.0) << path << " record " << record;
        for (int i = 0; i < ring.getNumPoints(); ++i) {
          EXPECT_LE(std::abs(ring.getX(i)), 180.0) << path << " record " << record;
          EXPECT_LE(std::abs(ring.getY(i)), 90.0);
        }
      });
    }
    EXPECT_EQ(cut, 3) << path;
    EXPECT_EQ(rings, kTrack + 3) << path;
  }
}

// footprints.gpkg: the same features through the GPKG driver, in EPSG:4326, every footprint a
// MultiPolygon (one geometry type per layer, as GeoPackage readers expect), a flagged shot's
// geometry null, the per-band properties under their suffixed names; no .part left.
TEST_F(OgrWriterTest, GeoPackage) {
  const fs::path gpkg = dir_ / "footprints.gpkg";
  {
    OgrWriter writer(gpkg, FootprintsFormat::gpkg, make_info());
    for (int record : {2, 1, 0})
      writer.write(record, record == 1 ? make_flagged_record(1) : make_record(record));
    writer.finish(RunStats{});
  }
  std::vector<std::string> left;
  for (const auto& entry : fs::directory_iterator(dir_.path()))
    left.push_back(entry.path().filename().string());
  EXPECT_EQ(left, std::vector<std::string>{"footprints.gpkg"});

  GdalMessages messages;
  CPLPushErrorHandlerEx(collect_gdal_message, &messages);
  GDALDatasetUniquePtr dataset(GDALDataset::FromHandle(
      GDALOpenEx(gpkg.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  OGRLayer* layer = dataset ? dataset->GetLayerByName("footprints") : nullptr;
  std::vector<OGRFeatureUniquePtr> features;
  if (layer != nullptr)
    for (auto& feature : *layer) features.emplace_back(feature.release());
  CPLPopErrorHandler();
  EXPECT_EQ(messages.count, 0) << messages.text;
  ASSERT_TRUE(dataset);
  ASSERT_NE(layer, nullptr);
  EXPECT_STREQ(dataset->GetDriver()->GetDescription(), "GPKG");
  EXPECT_EQ(layer->GetFeatureCount(), kShots);
  EXPECT_EQ(wkbFlatten(layer->GetGeomType()), wkbMultiPolygon);
  const OGRSpatialReference* crs = layer->GetSpatialRef();
  ASSERT_NE(crs, nullptr);
  EXPECT_STREQ(crs->GetAuthorityName(nullptr), "EPSG");
  EXPECT_STREQ(crs->GetAuthorityCode(nullptr), "4326");

  ASSERT_EQ(features.size(), 3u);
  for (int record : {0, 2}) {
    const ShotRecord expected = make_record(record);
    const OGRFeature& feature = *features[record];
    EXPECT_EQ(feature.GetFieldAsInteger64("shot_number"), expected.shot_number);
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("energy_tr_1064"), expected.energy_tr_J[1]);
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("reflectance_532"), expected.reflectance[0]);
    EXPECT_DOUBLE_EQ(feature.GetFieldAsDouble("rh98_532"), expected.rh_m[0][98]);
    const OGRGeometry* geometry = feature.GetGeometryRef();
    ASSERT_NE(geometry, nullptr);
    ASSERT_EQ(wkbFlatten(geometry->getGeometryType()), wkbMultiPolygon);
    const OGRLinearRing* ring = geometry->toMultiPolygon()->getGeometryRef(0)->getExteriorRing();
    ASSERT_EQ(ring->getNumPoints(), static_cast<int>(expected.footprint_lonlat.size()));
    EXPECT_DOUBLE_EQ(ring->getX(0), expected.footprint_lonlat[0][0]);
    EXPECT_DOUBLE_EQ(ring->getY(0), expected.footprint_lonlat[0][1]);
  }
  EXPECT_EQ(features[1]->GetGeometryRef(), nullptr);
  EXPECT_TRUE(features[1]->IsFieldNull(features[1]->GetFieldIndex("energy_tr_1064")));
}

TEST_F(OgrWriterTest, UnfinishedGeoPackageLeavesNothing) {
  {
    OgrWriter writer(dir_ / "footprints.gpkg", FootprintsFormat::gpkg, make_info());
    writer.write(0, make_record(0));
    writer.write(2, make_record(2));
    EXPECT_TRUE(fs::exists(dir_ / "footprints.gpkg.part"));
    writer.abort();
    EXPECT_THROW(writer.write(1, make_record(1)), Error);
  }
  EXPECT_TRUE(fs::is_empty(dir_.path()));
}

TEST_F(OgrWriterTest, TextIsRfc7946) {
  write_product();
  const std::string content = text();
  EXPECT_EQ(content.find("NaN"), std::string::npos);
  EXPECT_EQ(content.find("nan"), std::string::npos);
  EXPECT_EQ(content.find("inf"), std::string::npos);
  const nlohmann::json document = nlohmann::json::parse(content);  // throws on invalid JSON
  EXPECT_EQ(document.at("type"), "FeatureCollection");
  EXPECT_FALSE(document.contains("crs"));
  ASSERT_EQ(document.at("features").size(), 3u);
  for (const auto& feature : document.at("features")) {
    EXPECT_EQ(feature.at("type"), "Feature");
    EXPECT_TRUE(feature.contains("geometry"));
    EXPECT_TRUE(feature.at("properties").is_object());
  }
  EXPECT_TRUE(document.at("features")[1].at("geometry").is_null());
  const auto& coordinates = document.at("features")[0].at("geometry").at("coordinates");
  ASSERT_EQ(coordinates.size(), 1u);
  EXPECT_EQ(coordinates[0].front(), coordinates[0].back()) << "ring closed";

  // No more than 8 decimals in coordinates (about a millimetre on the ground).
  const std::regex coordinate_list(R"re("coordinates": ?\[ ?\[(.*?)\] ?\] ?\})re");
  const std::regex too_precise(R"(\.\d{9,})");
  int polygons = 0;
  for (auto it = std::sregex_iterator(content.begin(), content.end(), coordinate_list);
       it != std::sregex_iterator(); ++it) {
    ++polygons;
    const std::string numbers = (*it)[1];
    EXPECT_FALSE(std::regex_search(numbers, too_precise)) << numbers;
    EXPECT_TRUE(std::regex_search(numbers, std::regex(R"(\.\d{8}\b)")))
        << "8 decimals kept: " << numbers;
  }
  EXPECT_EQ(polygons, 2);
}

TEST_F(OgrWriterTest, UnfinishedWriterLeavesNothing) {
  {
    OgrWriter writer(file(), FootprintsFormat::geojson, make_info());
    writer.write(0, make_record(0));
    writer.write(2, make_record(2));
    EXPECT_TRUE(fs::exists(part()));
    EXPECT_FALSE(fs::exists(file()));
  }
  EXPECT_FALSE(fs::exists(part()));
  EXPECT_FALSE(fs::exists(file()));
}

TEST_F(OgrWriterTest, BadRecordsAreErrors) {
  OgrWriter writer(file(), FootprintsFormat::geojson, make_info());
  EXPECT_THROW(writer.write(3, make_record(0)), Error);
  EXPECT_THROW(writer.write(-1, make_record(0)), Error);

  ShotRecord open_ring = make_record(0);
  open_ring.footprint_lonlat.pop_back();
  EXPECT_THROW(writer.write(0, open_ring), Error);
  ShotRecord nan_vertex = make_record(0);
  nan_vertex.footprint_lonlat[3][1] = std::nan("");
  EXPECT_THROW(writer.write(0, nan_vertex), Error);

  writer.write(1, make_record(1));
  EXPECT_THROW(writer.write(1, make_record(1)), Error);  // held, not yet written out
  writer.write(0, make_record(0));
  EXPECT_THROW(writer.write(0, make_record(0)), Error);  // already written out
}

TEST_F(OgrWriterTest, UnwritableDirectoryIsARunError) {
  try {
    OgrWriter writer(dir_ / "missing" / "footprints.geojson", FootprintsFormat::geojson,
                     make_info());
    FAIL() << "created a file in a directory that does not exist";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::run);
    EXPECT_EQ(error.exit_status(), 4);
  }
}

}  // namespace
}  // namespace glaswave
