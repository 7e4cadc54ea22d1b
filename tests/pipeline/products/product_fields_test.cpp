// Tests of the product field table and what it drives outside the writers: the table's own
// consistency, the fill of a flagged shot (shapes and values typed here, not taken from the
// table), the copy of the waveform metrics, and the writer interface with its factory (abort
// leaves nothing behind).
#include "pipeline/products/product_fields.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

#include "core/error.hpp"
#include "pipeline/products/product_writer.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

bool all_nan(const std::vector<double>& values) {
  for (double v : values)
    if (!std::isnan(v)) return false;
  return true;
}

// How many dimensions a member has after the shot: 0 for a scalar, 1 for [band], ...
std::size_t rank_of(const ProductField& field) {
  return std::visit(
      [](auto member) -> std::size_t {
        using T = std::remove_cvref_t<decltype(std::declval<ShotRecord>().*member)>;
        if constexpr (std::is_arithmetic_v<T>)
          return 0;
        else if constexpr (std::is_same_v<T, std::vector<std::vector<std::vector<double>>>>)
          return 3;
        else if constexpr (std::is_same_v<T, std::vector<std::vector<double>>>)
          return 2;
        else
          return 1;
      },
      field.field);
}

TEST(ProductFields, TableIsConsistent) {
  std::set<std::string> names;
  for (const ProductField& field : product_fields()) {
    EXPECT_TRUE(names.insert(field.name).second) << field.name << " twice";
    EXPECT_NE(std::string(field.units), "") << field.name;
    EXPECT_NE(std::string(field.long_name), "") << field.name;
    std::size_t inner = 0;
    for (const char* dim : field.inner_dims) inner += dim != nullptr;
    if (field.ragged()) {  // a list a shot, along `photon` alone, in no footprint's properties
      EXPECT_EQ(rank_of(field), 1) << field.name;
      EXPECT_EQ(inner, 1u) << field.name;
      EXPECT_EQ(field.geojson, GeojsonProperty::none) << field.name;
      continue;
    }
    // The member's type has as many dimensions as the row declares (band, then its inner ones).
    EXPECT_EQ(rank_of(field), field.per_band() ? 1 + inner : 0) << field.name;
    // Only metrics come from the waveform processing, and every one names its metric.
    EXPECT_EQ(field.source == FieldSource::metrics,
              !std::holds_alternative<std::monostate>(field.metric))
        << field.name;
    // Integer storage holds no NaN: an integer field a flagged shot fills must fill with a number.
    const bool integer = field.type == StorageType::int64 || field.type == StorageType::uint8 ||
                         field.type == StorageType::int32;
    if (integer && field.source != FieldSource::shot) {
      EXPECT_FALSE(std::isnan(field.fill)) << field.name;
    }
  }
  EXPECT_EQ(find_product_field("rx_waveform")->name, std::string("rx_waveform"));
  EXPECT_EQ(find_product_field("no_such_field"), nullptr);
}

std::set<std::string> words(const std::string& text) {
  std::set<std::string> out;
  std::istringstream in(text);
  for (std::string word; in >> word;) out.insert(word);
  return out;
}

// Which variables of shots.nc have a band dimension, typed from PRODUCT.md section 4's table
// (its dims column), the atmosphere's truth of section 12 ("per band"), and the granule and sun
// fields and the truth's gap probability added since (per shot). A row whose member changes shape,
// or a new row, has to agree with the contract written here.
TEST(ProductFields, PerBandFieldsAreThoseOfProductMdsTable) {
  const std::set<std::string> per_band = words(
      "rx_waveform rx_waveform_canopy rx_waveform_ground rx_waveform_order rx_energy "
      "rx_energy_canopy rx_energy_ground reflectance energy_tr energy_cr energy_gr waveform_index "
      "sig_begin_m sig_end_m centroid_m n_peaks gauss_amp gauss_center_m gauss_sigma_ns "
      "gauss_area ground_elev_est canopy_height_est rh atmosphere_transmission "
      "atmosphere_delay_m atmosphere_scattered_fraction");
  const std::set<std::string> per_shot = words(
      "shot shot_number quality_flag quality_reason time lat lon elev sc_lat sc_lon sc_alt "
      "off_nadir_deg range_m slope_deg aspect_deg elev_bin0 elev_lastbin cover_true pai_true "
      "canopy_height_true pgap_true beam degrade_flag solar_elevation solar_azimuth");
  std::size_t fixed = 0;
  for (const ProductField& field : product_fields()) {
    if (field.ragged()) continue;  // the photon lists: their own test above
    ++fixed;
    const bool listed_per_band = per_band.count(field.name) == 1;
    EXPECT_TRUE(listed_per_band || per_shot.count(field.name) == 1)
        << field.name << " is in neither list of PRODUCT.md";
    EXPECT_EQ(field.per_band(), listed_per_band) << field.name;
  }
  EXPECT_EQ(fixed, per_band.size() + per_shot.size()) << "a variable of PRODUCT.md is missing";
}

// PRODUCT.md section 12: the atmosphere's truth only in a run with an atmosphere section, and
// those three alone.
TEST(ProductFields, AtmosphereTruthOnlyWithAnAtmosphere) {
  std::set<std::string> only;
  for (const ProductField& field : product_fields()) {
    const std::vector<std::size_t> without = ProductShape{.bands = 2}.of(field);
    const std::vector<std::size_t> with = ProductShape{.bands = 2, .atmosphere = true}.of(field);
    if (field.atmosphere_only) {
      only.insert(field.name);
      EXPECT_TRUE(without.empty()) << field.name;
      EXPECT_EQ(with, std::vector<std::size_t>{2}) << field.name;
    } else {
      EXPECT_EQ(without, with) << field.name;
    }
  }
  EXPECT_EQ(only, words("atmosphere_transmission atmosphere_delay_m "
                        "atmosphere_scattered_fraction"));
}

// Per-band properties carry the band's name as a suffix, band after band; per-shot scalars none.
std::vector<std::string> names_of(const char* field, const std::vector<std::string>& bands) {
  std::vector<std::string> names;
  for (const GeojsonPropertyName& property : geojson_properties(*find_product_field(field), bands))
    names.push_back(property.name);
  return names;
}

TEST(ProductFields, GeojsonNames) {
  const std::vector<std::string> bands = {"532", "1064"};
  EXPECT_EQ(names_of("energy_tr", bands),
            (std::vector<std::string>{"energy_tr_532", "energy_tr_1064"}));
  EXPECT_EQ(names_of("energy_tr", {"1064"}), (std::vector<std::string>{"energy_tr_1064"}));
  EXPECT_EQ(
      names_of("rh", bands),
      (std::vector<std::string>{"rh25_532", "rh50_532", "rh75_532", "rh98_532", "rh100_532",
                                "rh25_1064", "rh50_1064", "rh75_1064", "rh98_1064", "rh100_1064"}));
  EXPECT_EQ(names_of("shot_number", bands), (std::vector<std::string>{"shot_number"}));
  EXPECT_EQ(names_of("elev", bands), (std::vector<std::string>{"elev"}));
  EXPECT_TRUE(names_of("rx_waveform", bands).empty());
  EXPECT_TRUE(names_of("gauss_amp", bands).empty());
  const auto rh = geojson_properties(*find_product_field("rh"), bands);
  EXPECT_EQ(rh[8].band, 1u);
  EXPECT_EQ(rh[8].level, 98);
  const auto reflectance = geojson_properties(*find_product_field("reflectance"), bands);
  EXPECT_EQ(reflectance[1].band, 1u);
  EXPECT_EQ(reflectance[1].level, -1);
}

ShotRecord shot_known_values() {
  ShotRecord record;
  record.shot_number = 42;
  record.time_s = 1000.5;
  record.sc_lat_deg = 34.0;
  record.sc_lon_deg = -118.0;
  record.sc_alt_m = 600000.0;
  record.off_nadir_deg = 0.3;
  record.lat_deg = 34.1;
  record.elev_m = 1200.0;
  record.slope_deg = 10.0;
  record.elev_bin0_m = 1250.0;
  record.cover_true = 0.5;
  record.rx_energy_J = {1.0, 2.0};
  record.n_peaks = {3, 4};
  record.quality_flag = quality_invalid;
  return record;
}

// What PRODUCT.md section 5 asks of a shot with no waveform: its waveform and everything derived
// from it is fill, it keeps what the track says of it, and it has no peaks.
TEST(FillFlagged, FillsWhatTheShotCannotKnowAndKeepsTheRest) {
  ShotRecord record = shot_known_values();
  fill_flagged(record, {.bands = 2, .bins = 5, .orders = 3});
  EXPECT_EQ(record.shot_number, 42);
  EXPECT_EQ(record.time_s, 1000.5);
  EXPECT_EQ(record.sc_lat_deg, 34.0);
  EXPECT_EQ(record.sc_lon_deg, -118.0);
  EXPECT_EQ(record.sc_alt_m, 600000.0);
  EXPECT_EQ(record.off_nadir_deg, 0.3);
  EXPECT_EQ(record.quality_flag, quality_invalid);
  for (double v : {record.lat_deg, record.lon_deg, record.elev_m, record.range_m, record.slope_deg,
                   record.aspect_deg, record.elev_bin0_m, record.elev_lastbin_m, record.cover_true,
                   record.pai_true, record.canopy_height_true_m})
    EXPECT_TRUE(std::isnan(v));

  for (const auto* waveforms :
       {&record.rx_waveform_W, &record.rx_waveform_canopy_W, &record.rx_waveform_ground_W}) {
    ASSERT_EQ(waveforms->size(), 2u);
    for (const auto& band : *waveforms) {
      EXPECT_EQ(band.size(), 5u);
      EXPECT_TRUE(all_nan(band));
    }
  }
  ASSERT_EQ(record.rx_waveform_order_W.size(), 2u);
  for (const auto& band : record.rx_waveform_order_W) {
    ASSERT_EQ(band.size(), 3u);
    for (const auto& order : band) {
      EXPECT_EQ(order.size(), 5u);
      EXPECT_TRUE(all_nan(order));
    }
  }
  for (const auto* values :
       {&record.rx_energy_J, &record.rx_energy_canopy_J, &record.rx_energy_ground_J,
        &record.reflectance, &record.energy_tr_J, &record.energy_cr_J, &record.energy_gr_J,
        &record.waveform_index, &record.sig_begin_m, &record.sig_end_m, &record.centroid_m,
        &record.ground_elev_est_m, &record.canopy_height_est_m}) {
    EXPECT_EQ(values->size(), 2u);
    EXPECT_TRUE(all_nan(*values));
  }
  EXPECT_EQ(record.n_peaks, (std::vector<std::int32_t>{0, 0}));
  for (const auto* slots : {&record.gauss_amp_W, &record.gauss_center_m, &record.gauss_sigma_ns,
                            &record.gauss_area_J}) {
    ASSERT_EQ(slots->size(), 2u);
    for (const auto& band : *slots) {
      EXPECT_EQ(band.size(), 6u);  // PRODUCT.md: up to 6 Gaussians
      EXPECT_TRUE(all_nan(band));
    }
  }
  ASSERT_EQ(record.rh_m.size(), 2u);
  EXPECT_EQ(record.rh_m[1].size(), 101u);  // rh0 .. rh100
  EXPECT_TRUE(all_nan(record.rh_m[1]));
}

TEST(FillFlagged, NoOrdersWithoutPerOrderOutput) {
  ShotRecord record = shot_known_values();
  record.rx_waveform_order_W = {{{1.0}}};
  fill_flagged(record, {.bands = 1, .bins = 4, .orders = 0});
  EXPECT_TRUE(record.rx_waveform_order_W.empty());
  ASSERT_EQ(record.rx_waveform_W.size(), 1u);
  EXPECT_EQ(record.rx_waveform_W[0].size(), 4u);
}

// Every metric lands in the record field of the same meaning, in its own band only.
TEST(StoreMetrics, CopiesEachMetricToItsField) {
  WaveformMetrics m = WaveformMetrics::none();
  m.energy_tr_J = 1.0;
  m.energy_cr_J = 2.0;
  m.energy_gr_J = 3.0;
  m.waveform_index = 4.0;
  m.sig_begin_m = 5.0;
  m.sig_end_m = 6.0;
  m.centroid_m = 7.0;
  m.n_peaks = 2;
  m.gauss_amp_W[0] = 8.0;
  m.gauss_center_m[1] = 9.0;
  m.gauss_sigma_ns[0] = 10.0;
  m.gauss_area_J[1] = 11.0;
  m.ground_elev_m = 12.0;
  m.canopy_height_m = 13.0;
  m.rh_m[98] = 14.0;

  ShotRecord record;
  fill_fields(record, FieldSource::metrics, {.bands = 2});
  store_metrics(record, 1, m);
  const std::vector<std::pair<const std::vector<double>*, double>> per_band = {
      {&record.energy_tr_J, 1.0},         {&record.energy_cr_J, 2.0},
      {&record.energy_gr_J, 3.0},         {&record.waveform_index, 4.0},
      {&record.sig_begin_m, 5.0},         {&record.sig_end_m, 6.0},
      {&record.centroid_m, 7.0},          {&record.ground_elev_est_m, 12.0},
      {&record.canopy_height_est_m, 13.0}};
  for (const auto& [values, want] : per_band) {
    EXPECT_TRUE(std::isnan((*values)[0]));
    EXPECT_EQ((*values)[1], want);
  }
  EXPECT_EQ(record.n_peaks, (std::vector<std::int32_t>{0, 2}));
  EXPECT_EQ(record.gauss_amp_W[1][0], 8.0);
  EXPECT_EQ(record.gauss_center_m[1][1], 9.0);
  EXPECT_EQ(record.gauss_sigma_ns[1][0], 10.0);
  EXPECT_EQ(record.gauss_area_J[1][1], 11.0);
  EXPECT_TRUE(std::isnan(record.gauss_area_J[1][0]));
  EXPECT_EQ(record.rh_m[1][98], 14.0);
  EXPECT_TRUE(std::isnan(record.rh_m[0][98]));
  EXPECT_TRUE(std::isnan(record.rh_m[1][97]));
}

class ProductWritersTest : public ::testing::Test {
 protected:
  static RunInfo info() {
    RunInfo info;
    info.shots = 2;
    info.bands = {ProductBand{"1064", 1064.0}};
    info.bin_time_ns = {0.0, 1.0, 2.0};
    info.tx_time_ns = {0.0};
    info.tx_waveform_W = {{1.0}};
    return info;
  }
  // A flagged shot: valid for every writer, with no footprint and fill everywhere.
  static ShotRecord flagged(std::int64_t shot) {
    ShotRecord record;
    record.shot_number = shot;
    record.quality_flag = quality_invalid;
    fill_flagged(record, {.bands = 1, .bins = 3, .orders = 0});
    return record;
  }
  std::set<std::string> files() const {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_.path()))
      names.insert(entry.path().filename().string());
    return names;
  }

  test_support::ScratchDir dir_{"glaswave_writers"};
};

TEST_F(ProductWritersTest, MakesTheWritersAskedFor) {
  EXPECT_EQ(make_writers(dir_.path(), {.netcdf = true, .footprints = true}, info()).size(), 2u);
  EXPECT_EQ(make_writers(dir_.path(), {.netcdf = false, .footprints = true}, info()).size(), 1u);
  EXPECT_TRUE(make_writers(dir_.path(), {.netcdf = false, .footprints = false}, info()).empty());
  EXPECT_TRUE(files().empty()) << "writers destroyed unfinished leave nothing";
}

TEST_F(ProductWritersTest, FinishedWritersLeaveTheirProducts) {
  auto writers = make_writers(dir_.path(), {}, info());
  for (std::int64_t i : {1, 0})
    for (const auto& writer : writers) writer->write(i, flagged(i));
  for (const auto& writer : writers) writer->finish(RunStats{});
  for (const auto& writer : writers) writer->abort();  // too late: the products stay
  EXPECT_EQ(files(), (std::set<std::string>{"footprints.geojson", "shots.nc"}));
}

TEST_F(ProductWritersTest, GpkgFootprintsWhenAskedFor) {
  auto writers = make_writers(
      dir_.path(), {.netcdf = false, .footprints_format = FootprintsFormat::gpkg}, info());
  ASSERT_EQ(writers.size(), 1u);
  for (std::int64_t i : {1, 0}) writers[0]->write(i, flagged(i));
  writers[0]->finish(RunStats{});
  EXPECT_EQ(files(), (std::set<std::string>{"footprints.gpkg"}));
}

TEST_F(ProductWritersTest, AbortRemovesThePartAndRefusesMore) {
  auto writers = make_writers(dir_.path(), {}, info());
  for (const auto& writer : writers) writer->write(0, flagged(0));
  EXPECT_EQ(files(), (std::set<std::string>{"footprints.geojson.part", "shots.nc.part"}));
  for (const auto& writer : writers) {
    writer->abort();
    writer->abort();  // twice is harmless
    EXPECT_THROW(writer->write(1, flagged(1)), Error);
    EXPECT_THROW(writer->finish(RunStats{}), Error);
  }
  EXPECT_TRUE(files().empty());
}

// Every writer, whatever its format, refuses to finish a product with a record missing, and
// leaves neither the product nor its .part behind.
TEST_F(ProductWritersTest, FinishWithAMissingRecordFailsAndLeavesNothing) {
  for (const FootprintsFormat format : {FootprintsFormat::geojson, FootprintsFormat::gpkg}) {
    {
      auto writers = make_writers(dir_.path(), {.footprints_format = format}, info());
      ASSERT_EQ(writers.size(), 2u);
      for (const auto& writer : writers) {
        writer->write(0, flagged(0));
        try {
          writer->finish(RunStats{});
          ADD_FAILURE() << "finish accepted a product with record 1 missing";
        } catch (const Error& error) {
          EXPECT_EQ(error.kind(), ErrorKind::run);
          // The place is the product's final path.
          EXPECT_EQ(fs::path(error.place()).parent_path(), dir_.path()) << error.place();
          EXPECT_EQ(error.place().find(".part"), std::string::npos) << error.place();
          EXPECT_NE(std::string(error.what()).find("record 1"), std::string::npos) << error.what();
        }
      }
    }
    EXPECT_TRUE(files().empty());
  }
}

}  // namespace
}  // namespace glaswave
