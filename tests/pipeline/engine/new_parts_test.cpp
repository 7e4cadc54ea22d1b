// A new part is its own files (issue 36): a vegetation source, a receiver and a product writer,
// each a test double declared and registered in this file alone (nothing else in the tree names
// them), with the writer's key `output.parts_double` declared beside it. The configuration takes
// the doubles' kinds from their registrations (`sensor.receiver`, `canopy.slab_double`) and asks
// its rules of what they declared, not of their names; a configuration that names them is read as
// the command reads it, and one shot runs from the engine's typed settings through the double
// source's canopy and the double receiver to the double writer.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <functional>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "canopy/leaf_angles.hpp"
#include "core/part_switch.hpp"
#include "pipeline/config/keys.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/products/product_writer.hpp"
#include "pipeline/shot/receiver.hpp"
#include "pipeline/shot/vegetation_source.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;

// A turbid slab between 5 and 15 m over the whole region, plant area density 0.5 m2/m3: PAI 5
// along every vertical line. Counts the regions it grows.
class SlabSource final : public VegetationSource {
 public:
  static inline std::atomic<int> regions_grown{0};

  RegionVegetation grow(const VegetationRegion& region) const override {
    ++regions_grown;
    RegionVegetation grown;
    grown.geometry.trunks.max_height_m = -std::numeric_limits<double>::infinity();
    grown.geometry.layer = TurbidLayer{0.0, 0.0, 5.0, 15.0, 0.5, 0};
    Foliage leaves;
    leaves.reflectance.assign(region.bands, 0.45);
    leaves.transmittance.assign(region.bands, 0.45);
    leaves.trunk_reflectance.assign(region.bands, 0.3);
    leaves.leaf_angles = &angles_;
    grown.materials = {leaves};
    return grown;
  }

 private:
  LeafAngles angles_{LeafAngleDistribution::spherical, 57.3};
};

// Two photon events a shot, at the power-weighted centroids of band 0's canopy and ground
// returns, placed on the beam's axis by the returns' own clock.
class CentroidPhotons final : public Receiver {
 public:
  explicit CentroidPhotons(const ReceiverSettings& settings) : lidar_(settings.lidar) {}

  void receive(ShotReturns returns, ShotRecord& record) const override {
    const std::vector<double> times_ns = lidar_.bin_time_ns();
    const auto add = [&](const std::vector<double>& power_W, std::int32_t truth) {
      const double total_W = std::accumulate(power_W.begin(), power_W.end(), 0.0);
      if (!(total_W > 0.0)) return;
      double time_ns = 0.0;
      for (std::size_t bin = 0; bin < power_W.size(); ++bin)
        time_ns += power_W[bin] * times_ns[bin] / total_W;
      const Geodetic at = returns.position_at(time_ns);
      record.photon_time_ns.push_back(time_ns);
      record.photon_lat_deg.push_back(at.lat_deg);
      record.photon_lon_deg.push_back(at.lon_deg);
      record.photon_h_m.push_back(at.h_m);
      record.photon_class.push_back(truth);
      record.photon_order.push_back(1);
    };
    add(returns.waveforms.canopy_W[0], photon_canopy);
    add(returns.waveforms.ground_W[0], photon_ground);
  }
  bool photon_events() const override { return true; }

 private:
  LidarModel lidar_;
};

// Keeps what it is given.
struct KeepingWriter final : ProductWriter {
  static inline std::vector<ShotRecord> records;
  void write(std::int64_t, const ShotRecord& shot) override { records.push_back(shot); }
  void finish(const RunStats&) override {}
  void abort() noexcept override {}
};

// The parts' registrations, and the writer's key beside it. Two vegetation kinds and two
// receivers, each declaring a trait the other lacks: a kind whose file's ground points may be the
// terrain, a receiver that flies ATLAS's beams.
VegetationKind slab_kind() {
  return {[](const VegetationSettings&) { return std::make_unique<SlabSource>(); },
          [](const VegetationSettings&, double side_m) { return 64.0 * side_m; }, nullptr,
          "/canopy"};
}
const VegetationRegistration slab("slab_double", 0, {"a turbid slab (a test double)", {}},
                                  slab_kind());
const VegetationRegistration grounded_slab("ground_double", 0,
                                           {"a turbid slab over its own ground (a test double)",
                                            {.ground_points = true}},
                                           slab_kind());
ReceiverFactory centroid_photons() {
  return [](const ReceiverSettings& s) { return std::make_unique<CentroidPhotons>(s); };
}
const ReceiverRegistration centroids("centroid_double", 90,
                                     {"two photons a shot (a test double)", {}},
                                     centroid_photons());
const ReceiverRegistration beam_centroids("beams_double", 91,
                                          {"two photons a shot of each of ATLAS's beams (a test "
                                           "double)",
                                           {.atlas_beams = true}},
                                          centroid_photons());
const Registration<PartSwitch> keeping_key("parts_double", 0,
                                           {"output", false,
                                            "keep the records in memory (a test double)"});
const Registration<ProductWriter> keeping(
    "parts_double", 98, [](const WriterContext& c) -> std::unique_ptr<ProductWriter> {
      if (!switched_on(c.settings.switches, "parts_double")) return nullptr;
      return std::make_unique<KeepingWriter>();
    });

// One shot of the glas preset at nadir over a level plane of soil 0.2, as a user would write it,
// with the double writer alone asked for; the receiver and the canopy as given.
json one_shot(const json& output, const std::string& receiver = "waveform",
              const json& canopy = nullptr) {
  return {
      {"sensor", {{"preset", "glas"}, {"receiver", receiver}}},
      {"simulation", {{"rays_per_shot", 2000}, {"max_order", 4}}},
      {"terrain",
       {{"plane", {{"origin_lat_deg", 46.0}, {"origin_lon_deg", 8.0}}}, {"soil_reflectance", 0.2}}},
      {"canopy", canopy},
      {"track",
       {{"type", "points"}, {"points", json::array({{{"lat_deg", 46.0}, {"lon_deg", 8.0}}})}}},
      {"output", output}};
}

std::string error_of(const std::function<void()>& read) {
  try {
    read();
  } catch (const Error& e) {
    return e.what();
  }
  return "no error";
}

TEST(NewParts, TheWritersKeyIsTheConfigurationsOwn) {
  const Key* output = configuration_keys().child("output");
  ASSERT_NE(output, nullptr);
  const Key* key = output->child("parts_double");
  ASSERT_NE(key, nullptr);
  EXPECT_EQ(key->type, KeyType::boolean);
  EXPECT_EQ(key->default_value, json(false));
  EXPECT_EQ(parse_config(one_shot({{"parts_double", true}})).output.switches.at("parts_double"),
            true);
  const Config off = parse_config(one_shot(json::object()));
  EXPECT_EQ(off.output.switches.at("parts_double"), false);
  EXPECT_EQ(off.resolved["output"]["parts_double"], json(false));
  // A key the part did not declare is still refused, naming its place.
  EXPECT_THROW(parse_config(one_shot({{"parts_doubel", true}})), Error);
}

// The receivers and the canopy's kinds the configuration takes are those registered: the doubles
// are named, and a misspelt name is refused with every registered name listed.
TEST(NewParts, TheConfigurationNamesTheKindsThatRegistered) {
  using testing::HasSubstr;
  EXPECT_THAT(
      configuration_keys().child("sensor")->child("receiver")->choices,
      testing::ElementsAre("waveform", "photon_counting", "centroid_double", "beams_double"));
  EXPECT_EQ(parse_config(one_shot({}, "centroid_double")).sensor.receiver, "centroid_double");
  const std::string misspelt = error_of([] { parse_config(one_shot({}, "centroid_doubel")); });
  EXPECT_THAT(misspelt, HasSubstr("/sensor/receiver: must be one of waveform, photon_counting, "
                                  "centroid_double, beams_double, got \"centroid_doubel\""));

  // A kind whose keys the configuration does not declare is chosen by its empty object, alone.
  const std::optional<CanopySettings> canopy =
      parse_config(one_shot({}, "waveform", {{"slab_double", json::object()}})).canopy;
  ASSERT_TRUE(canopy.has_value());
  EXPECT_EQ(canopy->kind, "slab_double");
  EXPECT_EQ(
      error_of([] {
        parse_config(one_shot({}, "waveform", {{"slab_double", json::object()}, {"pai", 1.0}}));
      }),
      "/canopy/pai: cannot be given beside canopy.slab_double (the canopy holds one vegetation "
      "source)");
  EXPECT_THAT(error_of([] {
                parse_config(one_shot({}, "waveform", {{"slab_double", {{"pai", 1.0}}}}));
              }),
              testing::StartsWith("/canopy/slab_double/pai: "));
}

// The rules across keys ask what a kind declared: RAMI's measurements and the forward table need
// a receiver that declared a waveform; ATLAS's beams and the ICESat-2 granules are a receiver's
// that declared it flies them; the terrain may be the ground points of a kind that declared them.
TEST(NewParts, TheRulesAskWhatAKindDeclared) {
  const json rami = {{"per_order", true}, {"rami", {{"experiment", "x_{band}"}}}};
  EXPECT_EQ(error_of([&] { check_outputs(parse_config(one_shot(rami, "centroid_double"))); }),
            "/output/rami: RAMI's lidar measurements need the waveform receiver");

  const Config asked = parse_config(one_shot({{"atl03", true}}, "centroid_double"));
  ASSERT_EQ(asked.warnings.size(), 1u);
  EXPECT_EQ(asked.warnings[0],
            "/output/atl03: the centroid_double receiver writes no ICESat-2 granule; it is "
            "written with sensor.receiver \"photon_counting\" or \"beams_double\"");
  EXPECT_TRUE(parse_config(one_shot({{"atl03", true}}, "beams_double")).warnings.empty());

  // Its granules are something to write; the other double's run would write nothing.
  const json nothing = {{"netcdf", false}, {"footprints", false}};
  EXPECT_NO_THROW(check_outputs(parse_config(one_shot(nothing, "beams_double"))));
  EXPECT_THAT(error_of([&] { check_outputs(parse_config(one_shot(nothing, "centroid_double"))); }),
              testing::StartsWith("/output: nothing to write"));

  // ATLAS's beams are checked for the receiver that flies them alone.
  json beams = one_shot({}, "beams_double");
  beams["sensor"]["beams"] = {"gt9x"};
  EXPECT_THAT(error_of([&] { parse_config(beams); }),
              testing::StartsWith("/sensor/beams: no beam \"gt9x\""));
  beams["sensor"]["receiver"] = "centroid_double";
  EXPECT_NO_THROW(parse_config(beams));

  json ground = one_shot({}, "waveform", {{"ground_double", json::object()}});
  ground["terrain"] = {{"point_cloud", true}};
  EXPECT_EQ(parse_config(ground).canopy->kind, "ground_double");
  ground["canopy"] = {{"slab_double", json::object()}};
  EXPECT_THAT(error_of([&] { parse_config(ground); }),
              testing::StartsWith("/terrain/point_cloud: is the ground of canopy.point_cloud's "
                                  "cloud, and the canopy has no point cloud"));
}

// The slab holds PAI 5 (0.5 m2/m3 over 10 m, a closed form) from 5 to 15 m above the ground:
// the canopy's photon lies within it; the ground's no higher than the plane (to a 1 ns bin,
// 0.15 m: light scattered more than once only arrives later) and under the canopy's. Both on
// the beam's axis, at the footprint's latitude and longitude.
TEST(NewParts, AShotRunsThroughTheThreeDoubles) {
  const Config config =
      parse_config(one_shot({{"netcdf", false}, {"footprints", false}, {"parts_double", true}},
                            "centroid_double", {{"slab_double", json::object()}}));
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  const ShotSimulator simulator(shot_settings(config), *terrain,
                                make_vegetation_source(vegetation_settings(config)),
                                make_receiver(receiver_settings(config)));
  const std::unique_ptr<Track> track = plan_track(config, *terrain);

  const test_support::ScratchDir dir("glaswave_new_parts");
  ProductSettings products;
  products.netcdf = config.output.netcdf;
  products.footprints = config.output.footprints;
  products.switches = config.output.switches;
  RunInfo info;
  info.shots = 1;
  auto writers = make_writers(dir.path(), products, info);
  ASSERT_EQ(writers.size(), 1u);  // the double alone: the run asked for nothing else

  SlabSource::regions_grown = 0;
  KeepingWriter::records.clear();
  writers[0]->write(0, simulator.simulate(track->footprint(0)));
  writers[0]->finish({});
  EXPECT_GE(SlabSource::regions_grown.load(), 1);

  ASSERT_EQ(KeepingWriter::records.size(), 1u);
  const ShotRecord& shot = KeepingWriter::records[0];
  EXPECT_NEAR(shot.pai_true, 5.0, 1e-6);
  ASSERT_EQ(shot.photon_class.size(), 2u);
  EXPECT_EQ(shot.photon_class[0], photon_canopy);
  EXPECT_EQ(shot.photon_class[1], photon_ground);
  EXPECT_LT(shot.photon_time_ns[0], shot.photon_time_ns[1]);  // the canopy's light comes first
  const double ground_m = terrain->height_m(46.0, 8.0);
  EXPECT_GT(shot.photon_h_m[0] - ground_m, 5.0);
  EXPECT_LT(shot.photon_h_m[0] - ground_m, 15.0);
  EXPECT_LT(shot.photon_h_m[1], ground_m + 0.15);
  EXPECT_LT(shot.photon_h_m[1], shot.photon_h_m[0]);
  for (std::size_t i = 0; i < 2; ++i) {
    EXPECT_NEAR(shot.photon_lat_deg[i], 46.0, 1e-6);
    EXPECT_NEAR(shot.photon_lon_deg[i], 8.0, 1e-6);
  }
}

}  // namespace
}  // namespace glaswave
