// The Receiver interface holds receivers other than the waveform one: a test double, one class
// and one registration, that emits photon events (the variable-length fields a photon-counting
// receiver writes) runs through the shot, and shots.nc stores them as CF contiguous ragged
// arrays.
#include "pipeline/shot/receiver.hpp"

#include <gtest/gtest.h>
#include <netcdf.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "pipeline/products/netcdf_writer.hpp"
#include "tests/pipeline/shot/shot_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using namespace glaswave::testing;

// One photon a bin where band 0's received power is above half its peak, at the bin's centre,
// classed by which of the ground's and the canopy's light is the larger there.
class HalfPeakPhotons : public Receiver {
 public:
  explicit HalfPeakPhotons(const ReceiverSettings& settings) : lidar_(settings.lidar) {}

  void receive(ShotReturns returns, ShotRecord& record) const override {
    const std::vector<double>& total = returns.waveforms.total_W[0];
    const double peak_W = *std::max_element(total.begin(), total.end());
    const std::vector<double> times_ns = lidar_.bin_time_ns();
    for (std::size_t bin = 0; bin < total.size(); ++bin) {
      if (!(total[bin] > 0.5 * peak_W)) continue;
      const Geodetic at = returns.position_at(times_ns[bin]);
      record.photon_time_ns.push_back(times_ns[bin]);
      record.photon_lat_deg.push_back(at.lat_deg);
      record.photon_lon_deg.push_back(at.lon_deg);
      record.photon_h_m.push_back(at.h_m);
      record.photon_class.push_back(
          returns.waveforms.ground_W[0][bin] >= returns.waveforms.canopy_W[0][bin] ? photon_ground
                                                                                   : photon_canopy);
      record.photon_order.push_back(1);
    }
  }
  bool photon_events() const override { return true; }

 private:
  LidarModel lidar_;
};

const Registration<Receiver> half_peak_photons("half_peak_photons", 0,
                                               {[](const ReceiverSettings& s) {
                                                 return std::make_unique<HalfPeakPhotons>(s);
                                               }});

// Over bare ground at nadir the pulse (sigma 5 ns) is above half its peak within 1.18 sigma of
// the ground's return: 11 or 12 one-ns bins, within c / 2 * 5.9 ns = 0.88 m of the ground.
TEST(Receiver, PhotonEventsThroughTheShot) {
  const std::unique_ptr<Terrain> terrain = plane_terrain(0.3);
  const ShotSettings settings = shot_settings(0.3, 500);
  const ShotSimulator simulator(settings, *terrain, nullptr,
                                make_receiver(receiver_settings(settings, "half_peak_photons")));
  ASSERT_TRUE(simulator.receiver().photon_events());
  const ShotRecord record = simulator.simulate(nadir_footprint(*terrain));
  ASSERT_GE(record.photon_time_ns.size(), 11u);
  ASSERT_LE(record.photon_time_ns.size(), 12u);
  for (std::size_t i = 0; i < record.photon_time_ns.size(); ++i) {
    EXPECT_LT(std::abs(record.photon_h_m[i]), 0.9);
    EXPECT_NEAR(record.photon_h_m[i], -0.5 * 0.299792458 * record.photon_time_ns[i], 1e-6);
    EXPECT_NEAR(record.photon_lat_deg[i], kLat0, 1e-9);
    EXPECT_EQ(record.photon_class[i], photon_ground);
  }
}

// Three shots of 2, 0 and 3 photons, written out of order: photon_count says 2 0 3 along
// `shot`, the photons lie in shot order along `photon`, and the count names its dimension.
TEST(Receiver, NetcdfStoresPhotonsAsContiguousRaggedArrays) {
  const test_support::ScratchDir dir("ragged");
  RunInfo info;
  info.shots = 3;
  info.bands = {{"1064", 1064.0}};
  info.bin_time_ns = {0.0};
  info.tx_time_ns = {0.0};
  info.tx_waveform_W = {{1.0}};
  info.photon_events = true;
  const std::vector<std::vector<double>> times = {{1.0, 2.0}, {}, {3.0, 4.0, 5.0}};
  std::vector<ShotRecord> records(3);
  for (std::size_t i = 0; i < 3; ++i) {
    records[i].shot_number = static_cast<std::int64_t>(i);
    records[i].quality_flag = quality_invalid;
    records[i].photon_time_ns = records[i].photon_lat_deg = records[i].photon_lon_deg =
        records[i].photon_h_m = times[i];
    records[i].photon_class.assign(times[i].size(), photon_canopy);
    records[i].photon_order.assign(times[i].size(), 1);
  }
  const std::filesystem::path path = dir.path() / "shots.nc";
  {
    NetcdfWriter writer(path, info);
    for (std::size_t i : {2, 0, 1}) writer.write(static_cast<std::int64_t>(i), records[i]);
    writer.finish({});
  }
  int nc = -1, dim = -1, var = -1;
  ASSERT_EQ(nc_open(path.c_str(), NC_NOWRITE, &nc), NC_NOERR);
  std::size_t photons = 0;
  ASSERT_EQ(nc_inq_dimid(nc, "photon", &dim), NC_NOERR);
  ASSERT_EQ(nc_inq_dimlen(nc, dim, &photons), NC_NOERR);
  EXPECT_EQ(photons, 5u);
  int counts[3] = {};
  ASSERT_EQ(nc_inq_varid(nc, "photon_count", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_int(nc, var, counts), NC_NOERR);
  EXPECT_EQ(counts[0], 2);
  EXPECT_EQ(counts[1], 0);
  EXPECT_EQ(counts[2], 3);
  char sample_dimension[16] = {};
  ASSERT_EQ(nc_get_att_text(nc, var, "sample_dimension", sample_dimension), NC_NOERR);
  EXPECT_STREQ(sample_dimension, "photon");
  double read[5] = {};
  ASSERT_EQ(nc_inq_varid(nc, "photon_time", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_double(nc, var, read), NC_NOERR);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(read[i], i + 1.0);
  unsigned char classes[5] = {};
  ASSERT_EQ(nc_inq_varid(nc, "photon_class", &var), NC_NOERR);
  ASSERT_EQ(nc_get_var_uchar(nc, var, classes), NC_NOERR);
  EXPECT_EQ(classes[4], photon_canopy);
  nc_close(nc);
}

}  // namespace
}  // namespace glaswave
