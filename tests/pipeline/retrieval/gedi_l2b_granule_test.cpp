// gedi_l2b.h5's layout read back as rGEDI reads a real GEDI02_B: every path its functions open,
// in their order, with the dtype and shape of the real product, and the values of the L2B
// algorithm's closed-form case. The paths, from carlos-alberto-silva/rGEDI (read, not copied):
// R/getLevel2BVPM.R (its default `cols` through its var.map, from each group matching
// BEAM\d{4}), R/getLevel2BPAIProfile.R and R/getLevel2BPAVDProfile.R (pai_z and pavd_z read as
// [, 1:dims[2]] by hdf5r, which reverses HDF5's dimensions: (shots, 30) in HDF5, 30 columns
// named pai_z0_5m ... pai_z145_150m). The dtypes and shapes, from the real GEDI02_B subset
// rGEDI ships (inst/extdata/GEDI02_B_2019108080338_O01964_T05337_02_001_01_sub.zip, read with
// h5py) and the GEDI L2B data dictionary (LP DAAC): rh100 int16 in cm, the profiles float32
// (shots, 30), flags uint8, shot_number uint64, lat/lon float64, elevations and heights float32.
#include "pipeline/retrieval/gedi_l2b_granule.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using test_support::ScratchDir;

// The closed-form case of tests/pipeline/products/gedi_l2b_algorithm_test.cpp: canopy of area
// 120 and ground of area 80 (waveform unit x bins), far apart, so Rv = 120, Rg = 80 and Pgap =
// 1 - 120 / (120 + 1.5 x 80) = 0.5: cover 0.5, PAI = -2 cos(theta) ln 0.5.
constexpr int kBins = 1100;
constexpr double kBinM = 0.125, kTopM = 1000.0, kGroundBin = 900.5, kZenith = 0.1;
const WaveformAxis kAxis{1.0, kTopM, kTopM - (kBins - 1) * kBinM};
double elevation(double bin) { return kTopM - bin * kBinM; }

std::vector<double> two_gaussians() {
  std::vector<double> w(kBins, 7.0);
  const auto add = [&](double area, double center, double sigma) {
    for (int i = 0; i < kBins; ++i)
      w[i] += area / (sigma * std::sqrt(2.0 * std::numbers::pi)) *
              std::exp(-0.5 * std::pow((i - center) / sigma, 2));
  };
  add(120.0, kGroundBin - 160.0, 20.0);
  add(80.0, kGroundBin, 6.0);
  return w;
}

GediL2bShot closed_form_shot(std::uint64_t number, std::uint16_t beam,
                             const std::vector<double>& w) {
  GediL2bShot s;
  s.shot_number = number;
  s.info.present = true;
  s.info.beam = beam;
  s.info.channel = gedi_real_channel(beam);
  s.info.delta_time_s = 4.0e7 + 0.5;
  s.info.lat_bin0_deg = 1.0;
  s.info.lat_lastbin_deg = 1.0 + 1e-4;
  s.info.lon_bin0_deg = 2.0;
  s.info.lon_lastbin_deg = 2.0 - 2e-4;
  s.info.solar_elevation_deg = 30.0;
  s.info.solar_azimuth_deg = 120.0;
  s.info.dem_m = elevation(kGroundBin);
  s.info.local_beam_elevation_rad = std::numbers::pi / 2 - kZenith;
  s.info.local_beam_azimuth_rad = 0.5;
  s.axis = kAxis;
  s.bins = kBins;
  s.selected_algorithm = 2;
  s.l2a.signal = s.l2a.has_ground = true;
  s.l2a.toploc_bin = kGroundBin - 160.0 - 160.0;
  s.l2a.botloc_bin = kGroundBin + 48.0;
  s.l2a.elev_highestreturn_m = elevation(s.l2a.toploc_bin);
  s.l2a.elev_lowestmode_m = elevation(kGroundBin);
  s.l2a.elev_lowestreturn_m = elevation(s.l2a.botloc_bin);
  s.l2a.num_detectedmodes = 2;
  s.l2a_quality_flag = 1;
  s.sensitivity = 0.95;
  GediL2bInput in;
  in.waveform = w;
  in.axis = kAxis;
  in.noise_mean = 7.0;
  in.elev_highestreturn_m = s.l2a.elev_highestreturn_m;
  in.elev_lowestmode_m = s.l2a.elev_lowestmode_m;
  in.elev_lowestreturn_m = s.l2a.elev_lowestreturn_m;
  in.zenith_rad = kZenith;
  s.l2b = gedi_l2b(in);
  return s;
}

// A dataset as HDF5 stores it.
struct Stored {
  H5T_class_t type_class = H5T_NO_CLASS;
  std::size_t bytes = 0;
  bool is_signed = false;
  std::vector<hsize_t> dims;
  std::vector<double> values;
};

Stored stored(hid_t file, const std::string& path) {
  Stored s;
  if (H5Lexists(file, path.substr(0, path.find('/')).c_str(), H5P_DEFAULT) <= 0) return s;
  H5E_BEGIN_TRY {
    const hid_t set = H5Dopen2(file, path.c_str(), H5P_DEFAULT);
    if (set >= 0) {
      const hid_t type = H5Dget_type(set);
      s.type_class = H5Tget_class(type);
      s.bytes = H5Tget_size(type);
      s.is_signed = s.type_class == H5T_INTEGER && H5Tget_sign(type) == H5T_SGN_2;
      H5Tclose(type);
      const hid_t space = H5Dget_space(set);
      s.dims.resize(static_cast<std::size_t>(H5Sget_simple_extent_ndims(space)));
      H5Sget_simple_extent_dims(space, s.dims.data(), nullptr);
      s.values.resize(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
      H5Sclose(space);
      H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, s.values.data());
      H5Dclose(set);
    }
  }
  H5E_END_TRY;
  return s;
}

// What the real product stores at a path: 'f' float, 'u' unsigned, 'i' signed; bytes; rank.
struct Expected {
  const char* path;
  char kind;
  std::size_t bytes;
  int rank;
};

// Every path rGEDI's getLevel2BVPM (default cols), getLevel2BPAIProfile and
// getLevel2BPAVDProfile open under a beam, in the order they open them.
const Expected kRgediPaths[] = {
    // getLevel2BVPM
    {"beam", 'u', 2, 1},
    {"shot_number", 'u', 8, 1},
    {"algorithmrun_flag", 'u', 1, 1},
    {"l2b_quality_flag", 'u', 1, 1},
    {"delta_time", 'f', 8, 1},
    {"sensitivity", 'f', 4, 1},
    {"geolocation/solar_elevation", 'f', 4, 1},
    {"geolocation/latitude_lastbin", 'f', 8, 1},
    {"geolocation/latitude_bin0", 'f', 8, 1},
    {"geolocation/longitude_bin0", 'f', 8, 1},
    {"geolocation/longitude_lastbin", 'f', 8, 1},
    {"geolocation/elev_highestreturn", 'f', 4, 1},
    {"geolocation/elev_lowestmode", 'f', 4, 1},
    {"rh100", 'i', 2, 1},
    {"pai", 'f', 4, 1},
    {"fhd_normal", 'f', 4, 1},
    {"omega", 'f', 4, 1},
    {"pgap_theta", 'f', 4, 1},
    {"cover", 'f', 4, 1},
    // getLevel2BPAIProfile, then getLevel2BPAVDProfile (the same but pavd_z)
    {"shot_number", 'u', 8, 1},
    {"algorithmrun_flag", 'u', 1, 1},
    {"l2b_quality_flag", 'u', 1, 1},
    {"geolocation/delta_time", 'f', 8, 1},
    {"geolocation/lat_lowestmode", 'f', 8, 1},
    {"geolocation/lon_lowestmode", 'f', 8, 1},
    {"geolocation/elev_highestreturn", 'f', 4, 1},
    {"geolocation/elev_lowestmode", 'f', 4, 1},
    {"geolocation/height_lastbin", 'f', 4, 1},
    {"geolocation/height_bin0", 'f', 4, 1},
    {"pai_z", 'f', 4, 2},
    {"pavd_z", 'f', 4, 2},
    // The rest of issue 37's list (PRODUCT.md section 11), as the real subset stores them.
    {"channel", 'u', 1, 1},
    {"cover_z", 'f', 4, 2},
    {"rhov", 'f', 4, 1},
    {"rhog", 'f', 4, 1},
    {"rossg", 'f', 4, 1},
    {"geolocation/lat_highestreturn", 'f', 8, 1},
    {"geolocation/lon_highestreturn", 'f', 8, 1},
    {"geolocation/shot_number", 'u', 8, 1},
    {"geolocation/degrade_flag", 'i', 1, 1},
    {"geolocation/local_beam_elevation", 'f', 4, 1},
    {"selected_l2a_algorithm", 'u', 1, 1},
    {"l2a_quality_flag", 'u', 1, 1},
    {"master_int", 'u', 4, 1},
    {"rx_sample_count", 'i', 8, 1},
    {"rx_sample_start_index", 'i', 8, 1},
};

TEST(GediL2bGranule, RgediReadsEveryPathWithTheRealDtypeAndShape) {
  const ScratchDir dir("glaswave_l2b_granule");
  const std::vector<double> w = two_gaussians();
  GediL2bShot missed = closed_form_shot(3, 5, w);
  missed.l2b = GediL2bResult::none({});
  missed.l2a.has_ground = false;
  const std::vector<GediL2bShot> shots = {closed_form_shot(1, 5, w), closed_form_shot(2, 5, w),
                                          missed, closed_form_shot(9, 0, w)};
  const auto path = dir.path() / "gedi_l2b.h5";
  write_gedi_l2b(path, shots, "test");
  ASSERT_FALSE(std::filesystem::exists(dir.path() / "gedi_l2b.h5.part"));
  const hid_t file = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  ASSERT_GE(file, 0);
  // Beam groups in the order of their numbers: BEAM0000 (one shot), BEAM0101 (three).
  for (const auto& [group, count] :
       {std::pair{std::string("BEAM0000"), 1u}, std::pair{std::string("BEAM0101"), 3u}}) {
    for (const Expected& e : kRgediPaths) {
      const std::string full = group + "/" + e.path;
      const Stored s = stored(file, full);
      ASSERT_NE(s.type_class, H5T_NO_CLASS) << full << " missing";
      EXPECT_EQ(s.type_class, e.kind == 'f' ? H5T_FLOAT : H5T_INTEGER) << full;
      EXPECT_EQ(s.bytes, e.bytes) << full;
      if (e.kind != 'f') {
        EXPECT_EQ(s.is_signed, e.kind == 'i') << full;
      }
      ASSERT_EQ(s.dims.size(), static_cast<std::size_t>(e.rank)) << full;
      EXPECT_EQ(s.dims[0], count) << full;
      if (e.rank == 2) {
        EXPECT_EQ(s.dims[1], 30u) << full;  // rGEDI names 30 columns
      }
    }
  }
  const auto at = [&](const char* path) {
    return stored(file, std::string("BEAM0101/") + path).values;
  };
  // The closed form, to float32's rounding (6e-8 relative).
  const double pai = -2.0 * std::cos(kZenith) * std::log(0.5);
  EXPECT_NEAR(at("cover")[0], 0.5, 1e-6);
  EXPECT_NEAR(at("pgap_theta")[0], 0.5, 1e-6);
  EXPECT_NEAR(at("pai")[0], pai, 1e-6);
  EXPECT_NEAR(at("rhov")[0], 0.6, 1e-7);
  EXPECT_NEAR(at("rhog")[0], 0.4, 1e-7);
  EXPECT_NEAR(at("rossg")[0], 0.5, 1e-7);
  EXPECT_NEAR(at("omega")[0], 1.0, 1e-7);
  EXPECT_NEAR(at("rv")[0], 120.0, 1e-4);
  EXPECT_NEAR(at("rg")[0], 80.0, 1e-4);
  const std::vector<double> pai_z = at("pai_z"), cover_z = at("cover_z"), pavd_z = at("pavd_z");
  EXPECT_NEAR(pai_z[0], pai, 1e-6);    // pai_z[0] is the PAI above the ground
  EXPECT_NEAR(cover_z[0], 0.5, 1e-6);  // cover_z[0] the cover
  double sum = 0.0;
  for (int k = 0; k < 30; ++k) sum += pavd_z[k] * 5.0;
  EXPECT_NEAR(sum, pai, 1e-5);  // the PAVD profile holds the PAI
  // rh100 in cm: toploc 320 bins of 0.125 m above the ground.
  EXPECT_EQ(at("rh100")[0], 4000.0);
  EXPECT_EQ(at("channel")[0], 2.0);  // BEAM0101 is channel 2 in the real product
  EXPECT_EQ(stored(file, "BEAM0000/channel").values[0], 0.0);
  EXPECT_EQ(at("beam")[0], 5.0);
  EXPECT_EQ(at("shot_number")[2], 3.0);
  EXPECT_EQ(at("selected_l2a_algorithm")[0], 2.0);
  EXPECT_NEAR(at("sensitivity")[0], 0.95, 1e-7);
  EXPECT_EQ(at("master_int")[0], 4.0e7);
  // The ground lies 900.5 of 1099 bins down the beam: its latitude as far along bin 0 to last.
  const double t = kGroundBin / (kBins - 1);
  EXPECT_NEAR(at("geolocation/lat_lowestmode")[0], 1.0 + 1e-4 * t, 1e-12);
  EXPECT_NEAR(at("geolocation/lon_lowestmode")[0], 2.0 - 2e-4 * t, 1e-12);
  EXPECT_NEAR(at("geolocation/elev_lowestmode")[0], elevation(kGroundBin), 1e-4);
  // pgap_theta_z spans toploc to botloc in whole bins (580 to 949): its first bin 320.5 bins
  // above the ground (bin 900.5), its last 48.5 below.
  EXPECT_NEAR(at("geolocation/height_bin0")[0], 320.5 * kBinM, 1e-5);
  EXPECT_NEAR(at("geolocation/height_lastbin")[0], -48.5 * kBinM, 1e-5);
  EXPECT_EQ(at("rx_sample_count")[0], 370.0);
  EXPECT_EQ(at("rx_sample_start_index")[1], 371.0);
  // A shot L2B could not run on: flags 0, every metric the product's fill.
  EXPECT_EQ(at("algorithmrun_flag")[2], 0.0);
  EXPECT_EQ(at("l2b_quality_flag")[2], 0.0);
  EXPECT_EQ(at("algorithmrun_flag")[0], 1.0);
  EXPECT_EQ(at("l2b_quality_flag")[0], 1.0);
  for (const char* name : {"cover", "pai", "fhd_normal", "rh100", "geolocation/elev_lowestmode"})
    EXPECT_EQ(at(name)[2], -9999.0) << name;
  for (int k = 0; k < 30; ++k) EXPECT_EQ(pai_z[2 * 30 + k], -9999.0);
  EXPECT_EQ(at("rx_sample_count")[2], 0.0);
  H5Fclose(file);
}

}  // namespace
}  // namespace glaswave
