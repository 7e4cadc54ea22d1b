// Tests of shots.nc: a small product written from hand-made records (out of order) and read
// back through the netCDF-C API, attribute by attribute and value by value; and the rule that
// nothing is left under the final name (nor a .part) when a writer is not finished.
#include "pipeline/products/netcdf_writer.hpp"

#include <gtest/gtest.h>
#include <netcdf.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

constexpr int kShots = 3;
constexpr int kBins = 5;
constexpr int kTxBins = 3;
constexpr int kOrders = 2;
// Above 2^63, so a signed attribute would not hold it.
constexpr std::uint64_t kSeed = 18000000000000000001ull;

RunInfo make_info(int orders) {
  RunInfo info;
  info.command_line = "glaswave run demo.json --out out/demo";
  info.config_json = R"({"seed": 18000000000000000001})";
  info.seed = kSeed;
  info.shots = kShots;
  info.bands = {ProductBand{"532", 532.0}, ProductBand{"1064", 1064.0}};
  for (int b = 0; b < kBins; ++b) info.bin_time_ns.push_back(-2.0 + b);
  for (int b = 0; b < kTxBins; ++b) info.tx_time_ns.push_back(-1.0 + b);
  info.tx_waveform_W = {{1.0e6, 2.0e6, 1.0e6}, {3.0e6, 4.0e6, 3.0e6}};
  info.orders = orders;
  return info;
}

// A waveform value that tells record, band, order and bin apart.
double power(int record, int band, int bin, int part, int order = 0) {
  return 1e-9 * (1000 * record + 100 * band + 10 * bin + part + 0.25 * order) + 1e-12;
}

ShotRecord make_record(int record, int orders) {
  ShotRecord shot;
  shot.shot_number = 100 + record;
  shot.source_shot_number = shot.shot_number;  // a synthetic track: the instrument's is the shot
  shot.time_s = 183254400.0 + 0.025 * record;
  shot.lat_deg = 34.3 + 0.0015 * record;
  shot.lon_deg = -118.2 + 0.0003 * record;
  shot.elev_m = 1200.5 + record;
  shot.sc_lat_deg = 34.2 + 0.0015 * record;
  shot.sc_lon_deg = -118.21;
  shot.sc_alt_m = 600000.0 + record;
  shot.off_nadir_deg = 0.3;
  shot.range_m = 598800.0 - record;
  shot.slope_deg = 10.0 + record;
  shot.aspect_deg = 270.0;
  shot.elev_bin0_m = 1260.0 + record;
  shot.elev_lastbin_m = 1180.0 + record;
  shot.quality_flag = quality_good;
  for (int band = 0; band < 2; ++band) {
    std::vector<double> total, canopy, ground;
    for (int bin = 0; bin < kBins; ++bin) {
      total.push_back(power(record, band, bin, 0));
      canopy.push_back(power(record, band, bin, 1));
      ground.push_back(power(record, band, bin, 2));
    }
    shot.rx_waveform_W.push_back(total);
    shot.rx_waveform_canopy_W.push_back(canopy);
    shot.rx_waveform_ground_W.push_back(ground);
    if (orders > 0) {
      std::vector<std::vector<double>> by_order;
      for (int order = 1; order <= orders; ++order) {
        std::vector<double> values;
        for (int bin = 0; bin < kBins; ++bin) values.push_back(power(record, band, bin, 3, order));
        by_order.push_back(values);
      }
      shot.rx_waveform_order_W.push_back(by_order);
    }
    shot.rx_energy_J.push_back(1e-15 * (record + 1) * (band + 1));
    shot.rx_energy_canopy_J.push_back(0.6e-15 * (record + 1) * (band + 1));
    shot.rx_energy_ground_J.push_back(0.4e-15 * (record + 1) * (band + 1));
    shot.reflectance.push_back(0.1 * (record + 1) + 0.01 * band);
    // Waveform metrics: values that tell record and band apart.
    const double tag = 10 * record + band;
    shot.energy_tr_J.push_back(1.0e-15 + 1e-17 * tag);
    shot.energy_cr_J.push_back(0.7e-15 + 1e-17 * tag);
    shot.energy_gr_J.push_back(0.3e-15);
    shot.waveform_index.push_back(0.4 - 0.01 * tag);
    shot.sig_begin_m.push_back(1240.0 + tag);
    shot.sig_end_m.push_back(1195.0 + tag);
    shot.centroid_m.push_back(1215.0 + tag);
    shot.n_peaks.push_back(1 + (record + band) % 6);
    std::vector<double> amp(6, std::nan("")), center(6, std::nan("")), sigma(6, std::nan("")),
        area(6, std::nan(""));
    for (int k = 0; k < shot.n_peaks.back(); ++k) {
      amp[k] = 1e-6 * (k + 1) + 1e-9 * tag;
      center[k] = 1230.0 - 5.0 * k + tag;
      sigma[k] = 5.0 + k + 0.01 * tag;
      area[k] = 1e-14 * (k + 1) + 1e-17 * tag;
    }
    shot.gauss_amp_W.push_back(amp);
    shot.gauss_center_m.push_back(center);
    shot.gauss_sigma_ns.push_back(sigma);
    shot.gauss_area_J.push_back(area);
    shot.ground_elev_est_m.push_back(1200.25 + tag);
    shot.canopy_height_est_m.push_back(25.5 + tag);
    std::vector<double> rh;
    for (int k = 0; k <= 100; ++k) rh.push_back(-2.0 + 0.25 * k + 0.01 * tag);
    shot.rh_m.push_back(rh);
  }
  shot.cover_true = 0.7 - 0.1 * record;
  shot.pgap_true = 0.4 + 0.1 * record;
  shot.pai_true = 3.0 + record;
  shot.canopy_height_true_m = 30.0 + record;
  return shot;
}

// A shot off the terrain: no waveforms at all, as the transport may hand it over.
ShotRecord make_flagged_record(int record) {
  ShotRecord shot = make_record(record, 0);
  shot.quality_flag = quality_invalid;
  shot.quality_reason = reason_nodata;
  shot.rx_waveform_W.clear();
  shot.rx_waveform_canopy_W.clear();
  shot.rx_waveform_ground_W.clear();
  shot.rx_waveform_order_W.clear();
  shot.rx_energy_J.clear();
  shot.rx_energy_canopy_J.clear();
  shot.rx_energy_ground_J.clear();
  shot.reflectance.clear();
  for (auto field :
       {&ShotRecord::energy_tr_J, &ShotRecord::energy_cr_J, &ShotRecord::energy_gr_J,
        &ShotRecord::waveform_index, &ShotRecord::sig_begin_m, &ShotRecord::sig_end_m,
        &ShotRecord::centroid_m, &ShotRecord::ground_elev_est_m, &ShotRecord::canopy_height_est_m})
    (shot.*field).clear();
  shot.n_peaks = {0, 0};  // what the simulation hands over for a flagged shot
  for (auto field : {&ShotRecord::gauss_amp_W, &ShotRecord::gauss_center_m,
                     &ShotRecord::gauss_sigma_ns, &ShotRecord::gauss_area_J, &ShotRecord::rh_m})
    (shot.*field).clear();
  shot.cover_true = shot.pai_true = shot.canopy_height_true_m = shot.pgap_true = std::nan("");
  return shot;
}

class NetcdfWriterTest : public ::testing::Test {
 protected:
  void TearDown() override {
    if (HasFailure()) dir_.keep();  // kept for inspection when a test fails
  }
  fs::path file() const { return dir_ / "shots.nc"; }
  fs::path part() const { return dir_ / "shots.nc.part"; }

  test_support::ScratchDir dir_{"glaswave_netcdf"};
};

// Reads back a file through the C API; every failure is a test failure naming the call.
class Reader {
 public:
  explicit Reader(const fs::path& path) {
    EXPECT_EQ(nc_open(path.c_str(), NC_NOWRITE, &id_), NC_NOERR) << path;
  }
  ~Reader() {
    if (id_ >= 0) nc_close(id_);
  }
  int id() const { return id_; }

  int var(const std::string& name) const {
    int varid = -1;
    EXPECT_EQ(nc_inq_varid(id_, name.c_str(), &varid), NC_NOERR) << "variable " << name;
    return varid;
  }
  bool has_var(const std::string& name) const {
    int varid = -1;
    return nc_inq_varid(id_, name.c_str(), &varid) == NC_NOERR;
  }
  std::size_t dim(const std::string& name) const {
    int dimid = -1;
    std::size_t length = 0;
    if (nc_inq_dimid(id_, name.c_str(), &dimid) != NC_NOERR) return 0;
    EXPECT_EQ(nc_inq_dimlen(id_, dimid, &length), NC_NOERR);
    return length;
  }
  std::vector<std::string> dims_of(const std::string& name) const {
    const int varid = var(name);
    int ndims = 0;
    int dimids[NC_MAX_VAR_DIMS];
    EXPECT_EQ(nc_inq_var(id_, varid, nullptr, nullptr, &ndims, dimids, nullptr), NC_NOERR);
    std::vector<std::string> names;
    for (int i = 0; i < ndims; ++i) {
      char dim_name[NC_MAX_NAME + 1] = {};
      EXPECT_EQ(nc_inq_dimname(id_, dimids[i], dim_name), NC_NOERR);
      names.emplace_back(dim_name);
    }
    return names;
  }
  nc_type type_of(const std::string& name) const {
    nc_type type = NC_NAT;
    EXPECT_EQ(nc_inq_vartype(id_, var(name), &type), NC_NOERR);
    return type;
  }
  // Text attribute of a variable (or NC_GLOBAL), empty when absent.
  std::string text(int varid, const std::string& name) const {
    std::size_t length = 0;
    nc_type type = NC_NAT;
    if (nc_inq_att(id_, varid, name.c_str(), &type, &length) != NC_NOERR) return {};
    EXPECT_EQ(type, NC_CHAR) << name;
    std::string value(length, '\0');
    EXPECT_EQ(nc_get_att_text(id_, varid, name.c_str(), value.data()), NC_NOERR);
    return value;
  }
  std::string text(const std::string& variable, const std::string& name) const {
    return text(var(variable), name);
  }
  bool has_att(int varid, const std::string& name) const {
    int attnum = -1;
    return nc_inq_attid(id_, varid, name.c_str(), &attnum) == NC_NOERR;
  }
  std::vector<double> doubles(const std::string& name) const {
    std::size_t count = 1;
    for (const auto& dim_name : dims_of(name)) count *= dim(dim_name);
    std::vector<double> values(count);
    EXPECT_EQ(nc_get_var_double(id_, var(name), values.data()), NC_NOERR) << name;
    return values;
  }

 private:
  int id_ = -1;
};

void write_product(const fs::path& file, const RunInfo& info, bool flag_middle_shot) {
  NetcdfWriter writer(file, info);
  // Out of order, as worker threads hand records over.
  for (int record : {2, 0, 1}) {
    writer.write(record, flag_middle_shot && record == 1 ? make_flagged_record(record)
                                                         : make_record(record, info.orders));
  }
  writer.finish(RunStats{123456789012LL, 12.5, flag_middle_shot ? 1 : 0});
}

TEST_F(NetcdfWriterTest, WritesFinalFileAndNoPart) {
  write_product(file(), make_info(kOrders), false);
  EXPECT_TRUE(fs::exists(file()));
  EXPECT_FALSE(fs::exists(part()));
}

TEST_F(NetcdfWriterTest, DimensionsAreThoseOfTheRun) {
  write_product(file(), make_info(kOrders), false);
  Reader nc(file());
  int format = 0;
  ASSERT_EQ(nc_inq_format(nc.id(), &format), NC_NOERR);
  EXPECT_EQ(format, NC_FORMAT_NETCDF4);
  EXPECT_EQ(nc.dim("shot"), 3u);
  EXPECT_EQ(nc.dim("band"), 2u);
  EXPECT_EQ(nc.dim("bin"), 5u);
  EXPECT_EQ(nc.dim("tx_bin"), 3u);
  EXPECT_EQ(nc.dim("gaussian"), 6u);
  EXPECT_EQ(nc.dim("order"), 2u);
  int unlimited = -2;
  ASSERT_EQ(nc_inq_unlimdim(nc.id(), &unlimited), NC_NOERR);
  EXPECT_EQ(unlimited, -1) << "shot is a fixed dimension";

  EXPECT_EQ(nc.dims_of("lat"), (std::vector<std::string>{"shot"}));
  EXPECT_EQ(nc.dims_of("rx_waveform"), (std::vector<std::string>{"shot", "band", "bin"}));
  EXPECT_EQ(nc.dims_of("rx_waveform_order"),
            (std::vector<std::string>{"shot", "band", "order", "bin"}));
  EXPECT_EQ(nc.dims_of("rx_energy"), (std::vector<std::string>{"shot", "band"}));
  EXPECT_EQ(nc.dims_of("tx_waveform"), (std::vector<std::string>{"band", "tx_bin"}));
  EXPECT_EQ(nc.dims_of("bin_time_ns"), (std::vector<std::string>{"bin"}));
  EXPECT_EQ(nc.dims_of("tx_time_ns"), (std::vector<std::string>{"tx_bin"}));
  EXPECT_EQ(nc.dims_of("wavelength"), (std::vector<std::string>{"band"}));
  EXPECT_EQ(nc.dims_of("trajectory"), (std::vector<std::string>{}));
}

TEST_F(NetcdfWriterTest, EveryVariableHasUnitsAndLongName) {
  write_product(file(), make_info(kOrders), false);
  Reader nc(file());
  const std::set<std::string> expected = {"trajectory",
                                          "crs",
                                          "shot",
                                          "band",
                                          "quality_reason",
                                          "shot_number",
                                          "time",
                                          "lat",
                                          "lon",
                                          "elev",
                                          "sc_lat",
                                          "sc_lon",
                                          "sc_alt",
                                          "off_nadir_deg",
                                          "range_m",
                                          "slope_deg",
                                          "beam",
                                          "degrade_flag",
                                          "solar_elevation",
                                          "solar_azimuth",
                                          "aspect_deg",
                                          "elev_bin0",
                                          "elev_lastbin",
                                          "quality_flag",
                                          "wavelength",
                                          "band_name",
                                          "bin_time_ns",
                                          "tx_time_ns",
                                          "tx_waveform",
                                          "rx_waveform",
                                          "rx_waveform_canopy",
                                          "rx_waveform_ground",
                                          "rx_waveform_order",
                                          "rx_energy",
                                          "rx_energy_canopy",
                                          "rx_energy_ground",
                                          "reflectance",
                                          "energy_tr",
                                          "energy_cr",
                                          "energy_gr",
                                          "waveform_index",
                                          "sig_begin_m",
                                          "sig_end_m",
                                          "centroid_m",
                                          "n_peaks",
                                          "gauss_amp",
                                          "gauss_center_m",
                                          "gauss_sigma_ns",
                                          "gauss_area",
                                          "ground_elev_est",
                                          "canopy_height_est",
                                          "rh",
                                          "percentile",
                                          "cover_true",
                                          "pai_true",
                                          "canopy_height_true",
                                          "pgap_true",
                                          "order"};
  int nvars = 0;
  ASSERT_EQ(nc_inq_nvars(nc.id(), &nvars), NC_NOERR);
  std::set<std::string> found;
  for (int varid = 0; varid < nvars; ++varid) {
    char name[NC_MAX_NAME + 1] = {};
    ASSERT_EQ(nc_inq_varname(nc.id(), varid, name), NC_NOERR);
    found.insert(name);
    EXPECT_FALSE(nc.text(varid, "units").empty()) << name << " has no units";
    EXPECT_FALSE(nc.text(varid, "long_name").empty()) << name << " has no long_name";
  }
  EXPECT_EQ(found, expected);
}

// PRODUCT.md section 4's table of variables, typed here from the contract (not from the
// product field table): each is in shots.nc with units and long_name, and has the dimensions
// the contract gives it.
TEST_F(NetcdfWriterTest, EveryVariableOfTheProductContractIsThere) {
  write_product(file(), make_info(kOrders), false);
  Reader nc(file());
  const std::map<std::string, std::vector<std::string>> contract = {
      {"shot", {"shot"}},
      {"shot_number", {"shot"}},
      {"band", {"band"}},
      {"quality_flag", {"shot"}},
      {"quality_reason", {"shot"}},
      {"time", {"shot"}},
      {"lat", {"shot"}},
      {"lon", {"shot"}},
      {"elev", {"shot"}},
      {"sc_lat", {"shot"}},
      {"sc_lon", {"shot"}},
      {"sc_alt", {"shot"}},
      {"off_nadir_deg", {"shot"}},
      {"range_m", {"shot"}},
      {"slope_deg", {"shot"}},
      {"aspect_deg", {"shot"}},
      {"wavelength", {"band"}},
      {"bin_time_ns", {"bin"}},
      {"elev_bin0", {"shot"}},
      {"elev_lastbin", {"shot"}},
      {"rx_waveform", {"shot", "band", "bin"}},
      {"rx_waveform_canopy", {"shot", "band", "bin"}},
      {"rx_waveform_ground", {"shot", "band", "bin"}},
      {"rx_waveform_order", {"shot", "band", "order", "bin"}},
      {"rx_energy", {"shot", "band"}},
      {"rx_energy_canopy", {"shot", "band"}},
      {"rx_energy_ground", {"shot", "band"}},
      {"tx_waveform", {"band", "tx_bin"}},
      {"reflectance", {"shot", "band"}},
      {"energy_tr", {"shot", "band"}},
      {"energy_cr", {"shot", "band"}},
      {"energy_gr", {"shot", "band"}},
      {"waveform_index", {"shot", "band"}},
      {"sig_begin_m", {"shot", "band"}},
      {"sig_end_m", {"shot", "band"}},
      {"centroid_m", {"shot", "band"}},
      {"n_peaks", {"shot", "band"}},
      {"gauss_amp", {"shot", "band", "gaussian"}},
      {"gauss_center_m", {"shot", "band", "gaussian"}},
      {"gauss_sigma_ns", {"shot", "band", "gaussian"}},
      {"gauss_area", {"shot", "band", "gaussian"}},
      {"ground_elev_est", {"shot", "band"}},
      {"canopy_height_est", {"shot", "band"}},
      {"rh", {"shot", "band", "percentile"}},
      {"cover_true", {"shot"}},
      {"pai_true", {"shot"}},
      {"canopy_height_true", {"shot"}},
      {"pgap_true", {"shot"}}};
  for (const auto& [name, dims] : contract) {
    ASSERT_TRUE(nc.has_var(name)) << name;
    EXPECT_EQ(nc.dims_of(name), dims) << name;
    EXPECT_FALSE(nc.text(name, "units").empty()) << name << " has no units";
    EXPECT_FALSE(nc.text(name, "long_name").empty()) << name << " has no long_name";
  }
}

TEST_F(NetcdfWriterTest, CfAttributes) {
  write_product(file(), make_info(kOrders), false);
  Reader nc(file());
  EXPECT_EQ(nc.text(NC_GLOBAL, "Conventions"), "CF-1.10, ACDD-1.3");
  EXPECT_EQ(nc.text(NC_GLOBAL, "featureType"), "trajectory");
  EXPECT_FALSE(nc.text(NC_GLOBAL, "title").empty());
  EXPECT_EQ(nc.text(NC_GLOBAL, "history"), "glaswave run demo.json --out out/demo");
  EXPECT_EQ(nc.text(NC_GLOBAL, "source").rfind("glaswave ", 0), 0u) << nc.text(NC_GLOBAL, "source");
  EXPECT_EQ(nc.text(NC_GLOBAL, "config"), R"({"seed": 18000000000000000001})");

  nc_type type = NC_NAT;
  std::size_t length = 0;
  ASSERT_EQ(nc_inq_att(nc.id(), NC_GLOBAL, "seed", &type, &length), NC_NOERR);
  EXPECT_EQ(type, NC_UINT64);
  unsigned long long seed = 0;
  ASSERT_EQ(nc_get_att_ulonglong(nc.id(), NC_GLOBAL, "seed", &seed), NC_NOERR);
  EXPECT_EQ(seed, kSeed);
  long long ray_queries = 0, flagged = -1;
  double wall_s = 0.0;
  ASSERT_EQ(nc_get_att_longlong(nc.id(), NC_GLOBAL, "stats_ray_queries", &ray_queries), NC_NOERR);
  ASSERT_EQ(nc_get_att_double(nc.id(), NC_GLOBAL, "stats_wall_s", &wall_s), NC_NOERR);
  ASSERT_EQ(nc_get_att_longlong(nc.id(), NC_GLOBAL, "stats_shots_flagged", &flagged), NC_NOERR);
  EXPECT_EQ(ray_queries, 123456789012LL);
  EXPECT_EQ(wall_s, 12.5);
  EXPECT_EQ(flagged, 0);

  EXPECT_EQ(nc.text("trajectory", "cf_role"), "trajectory_id");
  EXPECT_EQ(nc.text("time", "units"), "seconds since 2000-01-01 12:00:00");
  EXPECT_EQ(nc.text("time", "calendar"), "standard");
  EXPECT_EQ(nc.text("time", "standard_name"), "time");
  EXPECT_EQ(nc.text("lat", "standard_name"), "latitude");
  EXPECT_EQ(nc.text("lat", "units"), "degrees_north");
  EXPECT_EQ(nc.text("lon", "standard_name"), "longitude");
  EXPECT_EQ(nc.text("lon", "units"), "degrees_east");
  EXPECT_EQ(nc.text("elev", "standard_name"), "height_above_reference_ellipsoid");
  EXPECT_EQ(nc.text("wavelength", "units"), "nm");
  EXPECT_EQ(nc.text("rx_waveform", "units"), "W");
  EXPECT_EQ(nc.text("rx_energy", "units"), "J");
  EXPECT_EQ(nc.text("reflectance", "units"), "1");
  EXPECT_NE(nc.text("reflectance", "long_name").find("eq. 1"), std::string::npos);
  EXPECT_EQ(nc.text("off_nadir_deg", "units"), "degree");

  // Every per-shot variable but the coordinates themselves points at the coordinates.
  for (const char* name : {"shot_number", "elev", "sc_alt", "range_m", "quality_flag",
                           "rx_waveform", "rx_waveform_order", "rx_energy", "reflectance"}) {
    EXPECT_EQ(nc.text(name, "coordinates"), "time lat lon") << name;
  }
  // NaN fill on per-shot floating-point data.
  for (const char* name :
       {"time", "lat", "elev", "rx_waveform", "rx_waveform_ground", "rx_energy", "reflectance"}) {
    ASSERT_TRUE(nc.has_att(nc.var(name), "_FillValue")) << name;
    double fill = 0.0;
    ASSERT_EQ(nc_get_att_double(nc.id(), nc.var(name), "_FillValue", &fill), NC_NOERR);
    EXPECT_TRUE(std::isnan(fill)) << name;
  }

  const int flag = nc.var("quality_flag");
  EXPECT_EQ(nc.type_of("quality_flag"), NC_UBYTE);
  unsigned char flag_values[2] = {9, 9};
  ASSERT_EQ(nc_inq_att(nc.id(), flag, "flag_values", &type, &length), NC_NOERR);
  EXPECT_EQ(type, NC_UBYTE);
  EXPECT_EQ(length, 2u);
  ASSERT_EQ(nc_get_att_uchar(nc.id(), flag, "flag_values", flag_values), NC_NOERR);
  // GEDI L2A's convention: 1 is a valid waveform.
  EXPECT_EQ(flag_values[0], 0);
  EXPECT_EQ(flag_values[1], 1);
  EXPECT_EQ(nc.text(flag, "flag_meanings"), "not_valid valid");
  const int reason = nc.var("quality_reason");
  EXPECT_EQ(nc.type_of("quality_reason"), NC_UBYTE);
  unsigned char reason_values[5] = {9, 9, 9, 9, 9};
  ASSERT_EQ(nc_inq_att(nc.id(), reason, "flag_values", &type, &length), NC_NOERR);
  EXPECT_EQ(type, NC_UBYTE);
  ASSERT_EQ(length, 5u);
  ASSERT_EQ(nc_get_att_uchar(nc.id(), reason, "flag_values", reason_values), NC_NOERR);
  for (unsigned char k = 0; k < 5; ++k) EXPECT_EQ(reason_values[k], k);
  EXPECT_EQ(nc.text(reason, "flag_meanings"), "none off_terrain nodata no_signal low_signal");
}

// What a GEDI or GLAS user's tools look for: the coordinates of the shot and band dimensions,
// the grid mapping, ACDD's discovery attributes with the data's bounds, and the names of the
// missions' own products.
TEST_F(NetcdfWriterTest, ConventionsOfTheMissionsAndOfDiscovery) {
  write_product(file(), make_info(kOrders), true);
  Reader nc(file());
  long long shots[3] = {};
  ASSERT_EQ(nc_get_var_longlong(nc.id(), nc.var("shot"), shots), NC_NOERR);
  for (int record = 0; record < kShots; ++record) EXPECT_EQ(shots[record], 100 + record);
  EXPECT_EQ(nc.doubles("band"), (std::vector<double>{532.0, 1064.0}));
  EXPECT_EQ(nc.text("band", "units"), "nm");
  EXPECT_FALSE(nc.has_att(nc.var("shot"), "coordinates"));

  // Every per-shot variable located by the trajectory's coordinates names the CRS.
  for (const char* name : {"elev", "sc_alt", "quality_flag", "rx_waveform", "rh", "energy_tr"})
    EXPECT_EQ(nc.text(name, "grid_mapping"), "crs") << name;
  const int crs = nc.var("crs");
  const std::string wkt = nc.text(crs, "crs_wkt");
  EXPECT_NE(wkt.find("WGS 84"), std::string::npos) << wkt;
  EXPECT_NE(wkt.find("ellipsoidal,3"), std::string::npos) << "heights above the ellipsoid";
  EXPECT_NE(wkt.find("4979"), std::string::npos) << wkt;
  EXPECT_EQ(nc.text(crs, "grid_mapping_name"), "latitude_longitude");
  double semi_major = 0.0, inverse_flattening = 0.0;
  ASSERT_EQ(nc_get_att_double(nc.id(), crs, "semi_major_axis", &semi_major), NC_NOERR);
  ASSERT_EQ(nc_get_att_double(nc.id(), crs, "inverse_flattening", &inverse_flattening), NC_NOERR);
  EXPECT_EQ(semi_major, 6378137.0);
  EXPECT_EQ(inverse_flattening, 298.257223563);

  for (const char* name : {"title", "summary", "keywords", "date_created"})
    EXPECT_FALSE(nc.text(NC_GLOBAL, name).empty()) << name;
  EXPECT_TRUE(nc.has_att(NC_GLOBAL, "creator_name"));
  // Times of records 0 and 2 (the flagged shot keeps its time): 183254400 s after the GLAS
  // epoch is 2005-10-22T12:00:00Z: 2121 days after 2000-01-01T12:00:00Z (Python datetime).
  EXPECT_EQ(nc.text(NC_GLOBAL, "time_coverage_start"), "2005-10-22T12:00:00.000000Z");
  EXPECT_EQ(nc.text(NC_GLOBAL, "time_coverage_end"), "2005-10-22T12:00:00.050000Z");
  double lat_min = 0.0, lat_max = 0.0, lon_min = 0.0, lon_max = 0.0;
  ASSERT_EQ(nc_get_att_double(nc.id(), NC_GLOBAL, "geospatial_lat_min", &lat_min), NC_NOERR);
  ASSERT_EQ(nc_get_att_double(nc.id(), NC_GLOBAL, "geospatial_lat_max", &lat_max), NC_NOERR);
  ASSERT_EQ(nc_get_att_double(nc.id(), NC_GLOBAL, "geospatial_lon_min", &lon_min), NC_NOERR);
  ASSERT_EQ(nc_get_att_double(nc.id(), NC_GLOBAL, "geospatial_lon_max", &lon_max), NC_NOERR);
  EXPECT_EQ(lat_min, make_record(0, 0).lat_deg);
  EXPECT_EQ(lat_max, make_record(2, 0).lat_deg);
  EXPECT_EQ(lon_min, make_record(0, 0).lon_deg);
  EXPECT_EQ(lon_max, make_record(2, 0).lon_deg);

  const std::map<std::string, std::string> gedi = {{"shot_number", "shot_number"},
                                                   {"time", "delta_time"},
                                                   {"lat", "lat_lowestmode"},
                                                   {"lon", "lon_lowestmode"},
                                                   {"quality_flag", "quality_flag"},
                                                   {"rh", "rh"},
                                                   {"rx_waveform", "rxwaveform"},
                                                   {"tx_waveform", "txwaveform"},
                                                   {"rx_energy", "rx_energy"},
                                                   {"ground_elev_est", "elev_lowestmode"},
                                                   {"elev_bin0", "geolocation/elevation_bin0"}};
  for (const auto& [name, gedi_name] : gedi) EXPECT_EQ(nc.text(name, "gedi_name"), gedi_name);
  const std::map<std::string, std::string> glas = {{"lat", "d_lat"},
                                                   {"lon", "d_lon"},
                                                   {"time", "d_UTCTime_40"},
                                                   {"centroid_m", "d_elev"},
                                                   {"sig_begin_m", "d_SigBegOff"},
                                                   {"sig_end_m", "d_SigEndOff"}};
  for (const auto& [name, glas_name] : glas) EXPECT_EQ(nc.text(name, "glas_name"), glas_name);
  EXPECT_EQ(nc.text("quality_flag", "standard_name"), "quality_flag");
  EXPECT_EQ(nc.text("elev_bin0", "standard_name"), "height_above_reference_ellipsoid");
  EXPECT_EQ(nc.text("slope_deg", "standard_name"), "ground_slope_angle");
  EXPECT_EQ(nc.text("aspect_deg", "standard_name"), "ground_slope_direction");
}

TEST_F(NetcdfWriterTest, TypesAndStorage) {
  write_product(file(), make_info(kOrders), false);
  Reader nc(file());
  EXPECT_EQ(nc.type_of("shot_number"), NC_INT64);
  EXPECT_EQ(nc.type_of("time"), NC_DOUBLE);
  EXPECT_EQ(nc.type_of("rx_waveform"), NC_FLOAT);
  EXPECT_EQ(nc.type_of("rx_waveform_order"), NC_FLOAT);
  EXPECT_EQ(nc.type_of("tx_waveform"), NC_FLOAT);
  EXPECT_EQ(nc.type_of("rx_energy"), NC_DOUBLE);
  EXPECT_EQ(nc.type_of("band_name"), NC_STRING);

  // Whole shots per chunk, compressed with shuffle: long tracks stay small, one shot reads
  // one chunk. This product's three records fit in one chunk of each variable.
  for (const char* name :
       {"rx_waveform", "rx_waveform_canopy", "rx_waveform_ground", "rx_waveform_order"}) {
    int storage = -1;
    std::size_t chunks[4] = {};
    ASSERT_EQ(nc_inq_var_chunking(nc.id(), nc.var(name), &storage, chunks), NC_NOERR);
    EXPECT_EQ(storage, NC_CHUNKED) << name;
    EXPECT_EQ(chunks[0], 3u) << name;
    EXPECT_EQ(chunks[1], 2u) << name;
    int shuffle = 0, deflate = 0, level = 0;
    ASSERT_EQ(nc_inq_var_deflate(nc.id(), nc.var(name), &shuffle, &deflate, &level), NC_NOERR);
    EXPECT_TRUE(shuffle) << name;
    EXPECT_TRUE(deflate) << name;
    EXPECT_GE(level, 1) << name;
    EXPECT_LE(level, 4) << name;
  }
}

TEST_F(NetcdfWriterTest, ValuesComeBack) {
  write_product(file(), make_info(kOrders), false);
  Reader nc(file());

  long long shot_numbers[3] = {};
  ASSERT_EQ(nc_get_var_longlong(nc.id(), nc.var("shot_number"), shot_numbers), NC_NOERR);
  const std::map<std::string, double ShotRecord::*> scalars = {
      {"time", &ShotRecord::time_s},
      {"lat", &ShotRecord::lat_deg},
      {"lon", &ShotRecord::lon_deg},
      {"elev", &ShotRecord::elev_m},
      {"sc_lat", &ShotRecord::sc_lat_deg},
      {"sc_lon", &ShotRecord::sc_lon_deg},
      {"sc_alt", &ShotRecord::sc_alt_m},
      {"off_nadir_deg", &ShotRecord::off_nadir_deg},
      {"range_m", &ShotRecord::range_m},
      {"slope_deg", &ShotRecord::slope_deg},
      {"aspect_deg", &ShotRecord::aspect_deg},
      {"elev_bin0", &ShotRecord::elev_bin0_m},
      {"elev_lastbin", &ShotRecord::elev_lastbin_m}};
  const std::map<std::string, std::vector<double> ShotRecord::*> per_band = {
      {"rx_energy", &ShotRecord::rx_energy_J},
      {"rx_energy_canopy", &ShotRecord::rx_energy_canopy_J},
      {"rx_energy_ground", &ShotRecord::rx_energy_ground_J},
      {"reflectance", &ShotRecord::reflectance}};
  const auto rx = nc.doubles("rx_waveform");
  const auto canopy = nc.doubles("rx_waveform_canopy");
  const auto ground = nc.doubles("rx_waveform_ground");
  const auto by_order = nc.doubles("rx_waveform_order");
  ASSERT_EQ(rx.size(), 3u * 2u * 5u);
  ASSERT_EQ(by_order.size(), 3u * 2u * 2u * 5u);

  for (int record = 0; record < kShots; ++record) {
    const ShotRecord expected = make_record(record, kOrders);
    EXPECT_EQ(shot_numbers[record], expected.shot_number);
    for (const auto& [name, field] : scalars) {
      EXPECT_EQ(nc.doubles(name)[record], expected.*field) << name << " record " << record;
    }
    for (const auto& [name, field] : per_band) {
      const auto values = nc.doubles(name);
      for (int band = 0; band < 2; ++band) {
        EXPECT_EQ(values[record * 2 + band], (expected.*field)[band])
            << name << " record " << record;
      }
    }
    for (int band = 0; band < 2; ++band) {
      for (int bin = 0; bin < kBins; ++bin) {
        const std::size_t at = (record * 2 + band) * kBins + bin;
        // Stored as float: compare to float precision.
        EXPECT_FLOAT_EQ(rx[at], power(record, band, bin, 0));
        EXPECT_FLOAT_EQ(canopy[at], power(record, band, bin, 1));
        EXPECT_FLOAT_EQ(ground[at], power(record, band, bin, 2));
        for (int order = 1; order <= kOrders; ++order) {
          const std::size_t at_order = ((record * 2 + band) * kOrders + (order - 1)) * kBins + bin;
          EXPECT_FLOAT_EQ(by_order[at_order], power(record, band, bin, 3, order));
        }
      }
    }
  }

  unsigned char flags[3] = {9, 9, 9};
  ASSERT_EQ(nc_get_var_uchar(nc.id(), nc.var("quality_flag"), flags), NC_NOERR);
  EXPECT_EQ(flags[0] + flags[1] + flags[2], 3) << "all valid";

  EXPECT_EQ(nc.doubles("wavelength"), (std::vector<double>{532.0, 1064.0}));
  EXPECT_EQ(nc.doubles("bin_time_ns"), (std::vector<double>{-2.0, -1.0, 0.0, 1.0, 2.0}));
  EXPECT_EQ(nc.doubles("tx_time_ns"), (std::vector<double>{-1.0, 0.0, 1.0}));
  EXPECT_EQ(nc.doubles("tx_waveform"),
            (std::vector<double>{1.0e6, 2.0e6, 1.0e6, 3.0e6, 4.0e6, 3.0e6}));
  EXPECT_EQ(nc.doubles("order"), (std::vector<double>{1.0, 2.0}));

  char* names[2] = {nullptr, nullptr};
  ASSERT_EQ(nc_get_var_string(nc.id(), nc.var("band_name"), names), NC_NOERR);
  EXPECT_STREQ(names[0], "532");
  EXPECT_STREQ(names[1], "1064");
  nc_free_string(2, names);
}

// PRODUCT.md section 4's waveform metrics: dimensions, units, CF attributes and values.
TEST_F(NetcdfWriterTest, WaveformMetricsComeBackWithTheirUnits) {
  write_product(file(), make_info(kOrders), true);
  Reader nc(file());
  EXPECT_EQ(nc.dim("percentile"), 101u);
  const std::map<std::string, std::string> units = {
      {"energy_tr", "J"},       {"energy_cr", "J"},         {"energy_gr", "J"},
      {"waveform_index", "1"},  {"sig_begin_m", "m"},       {"sig_end_m", "m"},
      {"centroid_m", "m"},      {"n_peaks", "1"},           {"gauss_amp", "W"},
      {"gauss_center_m", "m"},  {"gauss_sigma_ns", "ns"},   {"gauss_area", "J"},
      {"ground_elev_est", "m"}, {"canopy_height_est", "m"}, {"rh", "m"},
      {"cover_true", "1"},      {"pai_true", "1"},          {"canopy_height_true", "m"},
      {"pgap_true", "1"},       {"percentile", "percent"}};
  for (const auto& [name, unit] : units) {
    EXPECT_EQ(nc.text(name, "units"), unit) << name;
    EXPECT_FALSE(nc.text(name, "long_name").empty()) << name;
  }
  for (const char* name : {"energy_tr", "waveform_index", "sig_begin_m", "ground_elev_est",
                           "canopy_height_est", "n_peaks"})
    EXPECT_EQ(nc.dims_of(name), (std::vector<std::string>{"shot", "band"})) << name;
  for (const char* name : {"gauss_amp", "gauss_center_m", "gauss_sigma_ns", "gauss_area"})
    EXPECT_EQ(nc.dims_of(name), (std::vector<std::string>{"shot", "band", "gaussian"})) << name;
  EXPECT_EQ(nc.dims_of("rh"), (std::vector<std::string>{"shot", "band", "percentile"}));
  EXPECT_EQ(nc.dims_of("percentile"), (std::vector<std::string>{"percentile"}));
  for (const char* name : {"cover_true", "pai_true", "canopy_height_true", "pgap_true"})
    EXPECT_EQ(nc.dims_of(name), (std::vector<std::string>{"shot"})) << name;
  EXPECT_EQ(nc.type_of("n_peaks"), NC_INT);
  EXPECT_EQ(nc.type_of("rh"), NC_FLOAT);
  // CF names where CF has them, and the coordinates of a trajectory.
  EXPECT_EQ(nc.text("ground_elev_est", "standard_name"), "height_above_reference_ellipsoid");
  EXPECT_EQ(nc.text("gauss_center_m", "standard_name"), "height_above_reference_ellipsoid");
  EXPECT_EQ(nc.text("canopy_height_est", "standard_name"), "canopy_height");
  EXPECT_EQ(nc.text("cover_true", "standard_name"), "vegetation_area_fraction");
  EXPECT_NE(nc.text("waveform_index", "long_name").find("eq. 3"), std::string::npos);
  EXPECT_FALSE(nc.text("energy_gr", "comment").empty() && nc.text("energy_cr", "comment").empty());
  for (const char* name : {"energy_tr", "rh", "gauss_amp", "cover_true"})
    EXPECT_EQ(nc.text(name, "coordinates"), "time lat lon") << name;
  for (const char* name : {"energy_tr", "rh", "gauss_center_m", "canopy_height_true"}) {
    double fill = 0.0;
    ASSERT_EQ(nc_get_att_double(nc.id(), nc.var(name), "_FillValue", &fill), NC_NOERR) << name;
    EXPECT_TRUE(std::isnan(fill)) << name;
  }
  std::vector<double> percentiles;
  for (int k = 0; k <= 100; ++k) percentiles.push_back(k);
  EXPECT_EQ(nc.doubles("percentile"), percentiles);

  const std::map<std::string, std::vector<double> ShotRecord::*> per_band = {
      {"energy_tr", &ShotRecord::energy_tr_J},
      {"energy_cr", &ShotRecord::energy_cr_J},
      {"energy_gr", &ShotRecord::energy_gr_J},
      {"waveform_index", &ShotRecord::waveform_index},
      {"sig_begin_m", &ShotRecord::sig_begin_m},
      {"sig_end_m", &ShotRecord::sig_end_m},
      {"centroid_m", &ShotRecord::centroid_m},
      {"ground_elev_est", &ShotRecord::ground_elev_est_m},
      {"canopy_height_est", &ShotRecord::canopy_height_est_m}};
  const std::map<std::string, std::vector<std::vector<double>> ShotRecord::*> per_gaussian = {
      {"gauss_amp", &ShotRecord::gauss_amp_W},
      {"gauss_center_m", &ShotRecord::gauss_center_m},
      {"gauss_sigma_ns", &ShotRecord::gauss_sigma_ns},
      {"gauss_area", &ShotRecord::gauss_area_J}};
  const std::map<std::string, double ShotRecord::*> truth = {
      {"cover_true", &ShotRecord::cover_true},
      {"pai_true", &ShotRecord::pai_true},
      {"canopy_height_true", &ShotRecord::canopy_height_true_m},
      {"pgap_true", &ShotRecord::pgap_true}};
  const auto n_peaks = nc.doubles("n_peaks");
  const auto rh = nc.doubles("rh");
  for (int record : {0, 2}) {
    const ShotRecord expected = make_record(record, kOrders);
    for (int band = 0; band < 2; ++band) {
      for (const auto& [name, field] : per_band)
        EXPECT_EQ(nc.doubles(name)[record * 2 + band], (expected.*field)[band]) << name;
      EXPECT_EQ(n_peaks[record * 2 + band], expected.n_peaks[band]);
      for (const auto& [name, field] : per_gaussian) {
        const auto values = nc.doubles(name);
        for (int k = 0; k < 6; ++k) {
          const double want = (expected.*field)[band][k], got = values[(record * 2 + band) * 6 + k];
          if (std::isnan(want))
            EXPECT_TRUE(std::isnan(got)) << name << " slot " << k << " is unused";
          else
            EXPECT_EQ(got, want) << name << " slot " << k;
        }
      }
      for (int k = 0; k <= 100; ++k)
        EXPECT_FLOAT_EQ(rh[(record * 2 + band) * 101 + k], expected.rh_m[band][k]) << "rh" << k;
    }
    for (const auto& [name, field] : truth)
      EXPECT_EQ(nc.doubles(name)[record], expected.*field) << name;
  }
  // The flagged shot (record 1): fill, and no peaks.
  EXPECT_TRUE(std::isnan(nc.doubles("energy_tr")[2]));
  EXPECT_TRUE(std::isnan(nc.doubles("gauss_center_m")[1 * 2 * 6]));
  EXPECT_TRUE(std::isnan(rh[1 * 2 * 101 + 98]));
  EXPECT_TRUE(std::isnan(nc.doubles("cover_true")[1]));
  EXPECT_EQ(n_peaks[2], 0.0);
}

TEST_F(NetcdfWriterTest, FlaggedShotKeepsFill) {
  write_product(file(), make_info(kOrders), true);
  Reader nc(file());
  unsigned char flags[3] = {9, 9, 9};
  ASSERT_EQ(nc_get_var_uchar(nc.id(), nc.var("quality_flag"), flags), NC_NOERR);
  EXPECT_EQ(flags[0], 1) << "GEDI's valid";
  EXPECT_EQ(flags[1], 0);
  EXPECT_EQ(flags[2], 1);
  unsigned char reasons[3] = {9, 9, 9};
  ASSERT_EQ(nc_get_var_uchar(nc.id(), nc.var("quality_reason"), reasons), NC_NOERR);
  EXPECT_EQ(reasons[0], 0);
  EXPECT_EQ(reasons[1], 2) << "nodata";
  EXPECT_EQ(reasons[2], 0);
  const auto rx = nc.doubles("rx_waveform");
  const auto by_order = nc.doubles("rx_waveform_order");
  const auto energy = nc.doubles("rx_energy");
  for (int bin = 0; bin < 2 * kBins; ++bin) {
    EXPECT_TRUE(std::isnan(rx[1 * 2 * kBins + bin])) << bin;
    EXPECT_FALSE(std::isnan(rx[0 * 2 * kBins + bin])) << bin;
    EXPECT_FALSE(std::isnan(rx[2 * 2 * kBins + bin])) << bin;
  }
  for (int i = 0; i < 2 * kOrders * kBins; ++i)
    EXPECT_TRUE(std::isnan(by_order[1 * 2 * kOrders * kBins + i]));
  EXPECT_TRUE(std::isnan(energy[2]));
  EXPECT_TRUE(std::isnan(energy[3]));
  EXPECT_EQ(energy[4], make_record(2, 0).rx_energy_J[0]);
  // Geolocation of a flagged shot is still written.
  EXPECT_EQ(nc.doubles("lat")[1], make_record(1, 0).lat_deg);
  long long flagged = -1;
  ASSERT_EQ(nc_get_att_longlong(nc.id(), NC_GLOBAL, "stats_shots_flagged", &flagged), NC_NOERR);
  EXPECT_EQ(flagged, 1);
}

// Records are held until their chunk is complete (1024 shots of the scalars here, and of these
// short waveforms): records in any order, across a chunk's edge and into a last chunk that is
// not full, come back where they belong.
TEST_F(NetcdfWriterTest, RecordsInAnyOrderFillEveryChunk) {
  RunInfo info = make_info(0);
  info.shots = 1100;
  std::vector<int> order;
  for (int record = 1; record < info.shots; record += 2) order.push_back(record);
  for (int record = static_cast<int>(info.shots) - 2; record >= 0; record -= 2)
    order.push_back(record);
  constexpr int kFlagged = 1030;
  {
    NetcdfWriter writer(file(), info);
    for (int record : order)
      writer.write(record,
                   record == kFlagged ? make_flagged_record(record) : make_record(record, 0));
    writer.finish(RunStats{});
  }
  Reader nc(file());
  std::vector<long long> numbers(info.shots);
  ASSERT_EQ(nc_get_var_longlong(nc.id(), nc.var("shot_number"), numbers.data()), NC_NOERR);
  for (int record = 0; record < info.shots; ++record)
    ASSERT_EQ(numbers[record], 100 + record) << record;
  const auto rx = nc.doubles("rx_waveform");
  const auto rh = nc.doubles("rh");
  for (int record : {0, 1023, 1024, 1029, 1099}) {
    const ShotRecord shot = make_record(record, 0);
    for (int bin = 0; bin < kBins; ++bin)
      EXPECT_EQ(rx[(2 * record + 1) * kBins + bin],
                static_cast<double>(static_cast<float>(shot.rx_waveform_W[1][bin])))
          << record;
    EXPECT_EQ(rh[(2 * record + 1) * 101 + 50],
              static_cast<double>(static_cast<float>(shot.rh_m[1][50])))
        << record;
  }
  for (int bin = 0; bin < 2 * kBins; ++bin) EXPECT_TRUE(std::isnan(rx[2 * kFlagged * kBins + bin]));
  EXPECT_EQ(nc.doubles("lat")[kFlagged], make_record(kFlagged, 0).lat_deg);
}

// A chunk is compressed and written as soon as it is complete, beside the simulation, not held
// in HDF5's chunk cache until the file closes: before finish() the .part already holds the
// waveforms' bytes. Random waveforms (which deflate cannot shrink) of 2000 bins: 16 kB a shot
// and variable, 8 shots a chunk.
TEST_F(NetcdfWriterTest, CompleteChunksReachTheFileBeforeItCloses) {
  constexpr int kLongBins = 2000;
  RunInfo info = make_info(0);
  info.shots = 64;
  info.bin_time_ns.clear();
  for (int b = 0; b < kLongBins; ++b) info.bin_time_ns.push_back(0.5 * b);
  std::mt19937_64 engine(3);
  std::uniform_real_distribution<double> uniform(1e-9, 2e-9);
  NetcdfWriter writer(file(), info);
  for (int record = 0; record < info.shots; ++record) {
    ShotRecord shot = make_record(record, 0);
    for (auto* waveforms :
         {&shot.rx_waveform_W, &shot.rx_waveform_canopy_W, &shot.rx_waveform_ground_W})
      for (std::vector<double>& band : *waveforms) {
        band.resize(kLongBins);
        for (double& value : band) value = uniform(engine);
      }
    writer.write(record, shot);
  }
  // Three waveform variables of 64 shots x 2 bands x 2000 float32 bins: 3 MiB before deflate.
  const double waveform_bytes = 3.0 * info.shots * 2 * kLongBins * sizeof(float);
  EXPECT_GT(static_cast<double>(fs::file_size(part())), 0.5 * waveform_bytes);
  writer.finish(RunStats{});
  EXPECT_GT(static_cast<double>(fs::file_size(file())), 0.5 * waveform_bytes);
}

TEST_F(NetcdfWriterTest, NoOrderDimensionWithoutPerOrderOutput) {
  write_product(file(), make_info(0), false);
  Reader nc(file());
  EXPECT_EQ(nc.dim("order"), 0u);
  EXPECT_FALSE(nc.has_var("rx_waveform_order"));
  EXPECT_FALSE(nc.has_var("order"));
  EXPECT_TRUE(nc.has_var("rx_waveform"));
}

TEST_F(NetcdfWriterTest, UnfinishedWriterLeavesNothing) {
  {
    NetcdfWriter writer(file(), make_info(kOrders));
    writer.write(0, make_record(0, kOrders));
    EXPECT_TRUE(fs::exists(part()));
    EXPECT_FALSE(fs::exists(file()));
  }
  EXPECT_FALSE(fs::exists(part()));
  EXPECT_FALSE(fs::exists(file()));
}

TEST_F(NetcdfWriterTest, BadRecordsAreErrorsNamingFileAndVariable) {
  NetcdfWriter writer(file(), make_info(kOrders));
  EXPECT_THROW(writer.write(3, make_record(0, kOrders)), Error);
  EXPECT_THROW(writer.write(-1, make_record(0, kOrders)), Error);

  ShotRecord short_waveform = make_record(0, kOrders);
  short_waveform.rx_waveform_ground_W[1].pop_back();
  try {
    writer.write(0, short_waveform);
    FAIL() << "a waveform with a bin missing was accepted";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::run);
    EXPECT_EQ(error.place(), file().string());
    EXPECT_NE(std::string(error.what()).find("rx_waveform_ground"), std::string::npos)
        << error.what();
  }
  // A good shot must carry its arrays; only a flagged one may leave them empty.
  ShotRecord no_energy = make_record(0, kOrders);
  no_energy.rx_energy_J.clear();
  EXPECT_THROW(writer.write(0, no_energy), Error);

  writer.write(1, make_record(1, kOrders));
  EXPECT_THROW(writer.write(1, make_record(1, kOrders)), Error);
  // A refused record was not taken: it can still be written, once.
  EXPECT_NO_THROW(writer.write(0, make_record(0, kOrders)));
  EXPECT_THROW(writer.write(0, make_record(0, kOrders)), Error);
}

TEST_F(NetcdfWriterTest, UnwritableDirectoryIsARunError) {
  try {
    NetcdfWriter writer(dir_ / "missing" / "shots.nc", make_info(kOrders));
    FAIL() << "created a file in a directory that does not exist";
  } catch (const Error& error) {
    EXPECT_EQ(error.kind(), ErrorKind::run);
    EXPECT_EQ(error.exit_status(), 4);
  }
}

}  // namespace
}  // namespace glaswave
