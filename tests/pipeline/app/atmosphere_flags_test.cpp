// End to end: ATL08's cloud flags from the simulated atmosphere (issue 40, PRODUCT.md section 12).
// ATL08's land_segments carry ATL09's msw_flag (0 without layers; by the lowest layer's base above
// the ground: 3 below 1 km, 2 from 1 to 3 km, 1 above 3 km), cloud_flag_atm (the number of layers)
// and layer_flag (1 where there are any), as the ATL08 data dictionary defines them. A run
// without an atmosphere section keeps its zeros and writes no cloud_flag_atm.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tests/pipeline/atlas_pass.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

namespace fs = std::filesystem;

struct Flags {
  std::vector<std::int8_t> msw, cloud_atm, layer;
  bool has_cloud_atm = false;
};

std::vector<std::int8_t> read_int8(hid_t file, const std::string& path) {
  const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
  if (set < 0) return {};
  const hid_t space = H5Dget_space(set);
  std::vector<std::int8_t> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
  if (!values.empty()) H5Dread(set, H5T_NATIVE_INT8, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data());
  H5Sclose(space);
  H5Dclose(set);
  return values;
}

class AtmosphereFlags : public ::testing::Test {
 protected:
  // 150 shots 0.7 m apart (one 100 m segment and a part) over the ATLAS pass's forest on a plane
  // at 100 m above the ellipsoid, through `atmosphere` (null: no section).
  Flags run(const std::string& name, const nlohmann::json& atmosphere) {
    nlohmann::json config = test_support::atlas_pass(150, 100, 5);
    config["output"]["atl03"] = false;
    if (!atmosphere.is_null()) config["atmosphere"] = atmosphere;
    const fs::path file = dir_.path() / (name + ".json");
    std::ofstream(file) << config.dump(2);
    const fs::path out = dir_.path() / name;
    const std::string command = std::string(GLASWAVE_BINARY) + " run '" + file.string() +
                                "' --out '" + out.string() + "' --quiet > '" +
                                (dir_.path() / (name + ".txt")).string() + "' 2>&1";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    Flags f;
    const hid_t h5 = H5Fopen((out / "atl08.h5").c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
    EXPECT_GE(h5, 0) << name;
    if (h5 < 0) return f;
    const std::string land = "/gt2l/land_segments/";
    f.msw = read_int8(h5, land + "msw_flag");
    f.layer = read_int8(h5, land + "layer_flag");
    f.has_cloud_atm = H5Lexists(h5, (land + "cloud_flag_atm").c_str(), H5P_DEFAULT) > 0;
    if (f.has_cloud_atm) f.cloud_atm = read_int8(h5, land + "cloud_flag_atm");
    H5Fclose(h5);
    EXPECT_FALSE(f.msw.empty()) << name;
    return f;
  }

  static void expect_all(const std::vector<std::int8_t>& values, int expected, const char* what) {
    for (const std::int8_t v : values) EXPECT_EQ(v, expected) << what;
  }

  test_support::ScratchDir dir_{"glaswave_atmosphere_flags"};
};

nlohmann::json cloud(double base_m, double top_m, const char* above, double tau) {
  return {{"base_m", base_m},
          {"top_m", top_m},
          {"above", above},
          {"optical_depth", tau},
          {"phase", {{"hg_g", 0.8}}}};
}

TEST_F(AtmosphereFlags, NoSectionKeepsZerosAndWritesNoCloudCount) {
  const Flags f = run("none", nullptr);
  expect_all(f.msw, 0, "msw_flag");
  expect_all(f.layer, 0, "layer_flag");
  EXPECT_FALSE(f.has_cloud_atm);
}

// `clear`'s boundary-layer aerosol (tau 0.07 over 2 km, g 0.7) backscatters a fifth of what the
// molecules do there: no layer is reported. `cirrus` adds one from 9 km above the ellipsoid,
// 8.9 km above this ground: above 3 km.
TEST_F(AtmosphereFlags, ClearReportsNoLayerAndCirrusAHighOne) {
  const Flags clear = run("clear", "clear");
  ASSERT_TRUE(clear.has_cloud_atm);
  expect_all(clear.msw, 0, "clear msw_flag");
  expect_all(clear.cloud_atm, 0, "clear cloud_flag_atm");
  expect_all(clear.layer, 0, "clear layer_flag");
  const Flags cirrus = run("cirrus", "cirrus");
  expect_all(cirrus.msw, 1, "cirrus msw_flag");
  expect_all(cirrus.cloud_atm, 1, "cirrus cloud_flag_atm");
  expect_all(cirrus.layer, 1, "cirrus layer_flag");
}

// Two clouds: one based 1050 m above the ellipsoid, 950 m above this ground (below 1 km: 3,
// where taken above the ground it would be 2), and one 5 km above the ground.
TEST_F(AtmosphereFlags, TheLowestLayersBaseAboveTheGroundSetsTheWarning) {
  const Flags low = run(
      "low", {{"layers",
               {cloud(1050.0, 1500.0, "ellipsoid", 0.5), cloud(5000.0, 6000.0, "ground", 0.2)}}});
  expect_all(low.msw, 3, "msw_flag");
  expect_all(low.cloud_atm, 2, "cloud_flag_atm");
  expect_all(low.layer, 1, "layer_flag");
  const Flags middle = run("middle", {{"layers", {cloud(1050.0, 1500.0, "ground", 0.5)}}});
  expect_all(middle.msw, 2, "msw_flag");
  expect_all(middle.cloud_atm, 1, "cloud_flag_atm");
}

}  // namespace
}  // namespace glaswave
