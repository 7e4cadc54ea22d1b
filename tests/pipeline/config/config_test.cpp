// Tests of the configuration parser: presets and defaults against the seed's Tables 1 and 2,
// spectral values, every configuration error of PRODUCT.md §5 with its JSON path, overrides,
// the resolved configuration, and the ISO 8601 time stamps of the GLAS epoch.
#include "pipeline/config/config.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "core/error.hpp"
#include "pipeline/config/presets.hpp"
#include "tests/pipeline/config/config_test_support.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

using nlohmann::json;
using test_support::doc;
using test_support::error_of;
using ::testing::HasSubstr;
using ::testing::StartsWith;

std::string place_of(const json& document) {
  try {
    parse_config(document);
  } catch (const Error& e) {
    return e.place();
  }
  return "(no error)";
}

// A fresh folder under the system's temporary directory, removed at the end of the test.
using TempDir = test_support::ScratchDir;

// ---- sensor presets (the seed's Table 2) ----------------------------------------------------

void expect_table2_bands(const SensorSettings& s) {
  ASSERT_EQ(s.bands.size(), 2u);
  EXPECT_EQ(s.bands[0].name, "532");
  EXPECT_EQ(s.bands[0].wavelength_nm, 532.0);
  EXPECT_EQ(s.bands[0].pulse_energy_mJ, 32.0);
  EXPECT_EQ(s.bands[0].atmos_transmission_roundtrip, 0.8);
  EXPECT_EQ(s.bands[1].name, "1064");
  EXPECT_EQ(s.bands[1].wavelength_nm, 1064.0);
  EXPECT_EQ(s.bands[1].pulse_energy_mJ, 72.0);
  EXPECT_EQ(s.bands[1].atmos_transmission_roundtrip, 0.9);
}

TEST(SensorPreset, North2010IsTable2Exactly) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "north2010"}})"));
  EXPECT_EQ(c.sensor.preset, "north2010");
  EXPECT_EQ(c.sensor.pulse_sigma_ns, 5.0);
  EXPECT_EQ(c.sensor.divergence_sigma_rad, 0.00011);
  EXPECT_EQ(c.sensor.ifov_rad, 0.0004);
  EXPECT_EQ(c.sensor.telescope_area_m2, 0.709);
  EXPECT_EQ(c.sensor.bin_ns, 1.0);
  EXPECT_EQ(c.sensor.bins, 544);
  expect_table2_bands(c.sensor);
}

TEST(SensorPreset, NoPresetMeansNorth2010Values) {
  const Config c = parse_config(doc("{}"));
  EXPECT_EQ(c.sensor.preset, "");
  EXPECT_EQ(c.sensor.pulse_sigma_ns, 5.0);
  EXPECT_EQ(c.sensor.divergence_sigma_rad, 0.00011);
  EXPECT_EQ(c.sensor.ifov_rad, 0.0004);
  EXPECT_EQ(c.sensor.telescope_area_m2, 0.709);
  expect_table2_bands(c.sensor);
  EXPECT_FALSE(c.resolved["sensor"].contains("preset"));
}

TEST(SensorPreset, GlasFootprintIsAbout70m) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas"}})"));
  // A Gaussian beam of angular RMS width σθ per axis has intensity exp(-θ²/(2σθ²)); it falls to
  // 1/e² at θ = 2σθ, so the 1/e² diameter from altitude H at nadir is 4·σθ·H. GLAS's footprint
  // was about 70 m; 1 m of tolerance covers the rounding of the preset's σθ.
  const double diameter_m = 4.0 * c.sensor.divergence_sigma_rad * 600000.0;
  EXPECT_NEAR(diameter_m, 70.0, 1.0);
  // Everything else is the seed's Table 2.
  EXPECT_EQ(c.sensor.pulse_sigma_ns, 5.0);
  EXPECT_EQ(c.sensor.ifov_rad, 0.0004);
  EXPECT_EQ(c.sensor.telescope_area_m2, 0.709);
  EXPECT_EQ(c.sensor.bin_ns, 1.0);
  expect_table2_bands(c.sensor);
}

// GEDI's published instrument: one 1064 nm band; a pulse of 15.6 ns FWHM; footprints about 25 m
// across (1/e² diameter) from the ISS at about 420 km (Dubayah et al. 2020); an 0.8 m receiver
// telescope whose fibres each see 300 µrad of the ground; 10 mJ for a full-power laser's beam
// (gedi.umd.edu, instrument specifications). The expected values are computed here from those.
TEST(SensorPreset, GediMatchesThePublishedInstrument) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "gedi"}})"));
  EXPECT_EQ(c.sensor.preset, "gedi");
  // A Gaussian pulse's FWHM is 2 sqrt(2 ln 2) sigma.
  const double fwhm_ns = 2.0 * std::sqrt(2.0 * std::log(2.0)) * c.sensor.pulse_sigma_ns;
  EXPECT_NEAR(fwhm_ns, 15.6, 0.05);
  // The 1/e² diameter at nadir is 4·σθ·H (see GlasFootprintIsAbout70m); 0.1 m of tolerance.
  const double altitude_m = 420000.0;
  EXPECT_NEAR(4.0 * c.sensor.divergence_sigma_rad * altitude_m, 25.0, 0.1);
  const double footprint_area_m2 = std::numbers::pi * 12.5 * 12.5;
  const double radius_m = 2.0 * c.sensor.divergence_sigma_rad * altitude_m;
  EXPECT_NEAR(std::numbers::pi * radius_m * radius_m / footprint_area_m2, 1.0, 0.01);
  EXPECT_NEAR(c.sensor.telescope_area_m2, std::numbers::pi * 0.4 * 0.4, 1e-3);
  EXPECT_NEAR(c.sensor.ifov_rad, 300e-6, 1e-9);
  // The field of view takes in the whole beam: its half angle is many beam sigmas.
  EXPECT_GT(0.5 * c.sensor.ifov_rad, 6.0 * c.sensor.divergence_sigma_rad);
  EXPECT_EQ(c.sensor.bin_ns, 1.0);
  // The window holds GEDI L1B's longest records (1420 samples of 1 ns).
  EXPECT_GE(c.sensor.bins, 1420);
  ASSERT_EQ(c.sensor.bands.size(), 1u);
  EXPECT_EQ(c.sensor.bands[0].name, "1064");
  EXPECT_EQ(c.sensor.bands[0].wavelength_nm, 1064.0);
  EXPECT_EQ(c.sensor.bands[0].pulse_energy_mJ, 10.0);
  EXPECT_GT(c.sensor.bands[0].atmos_transmission_roundtrip, 0.0);
  EXPECT_LE(c.sensor.bands[0].atmos_transmission_roundtrip, 1.0);
}

// ATLAS on ICESat-2 (docs/icesat2.md gives each source): a 1.5 ns FWHM pulse at 532 nm; a
// footprint about 11 m across (86 % of the energy, i.e. 1/e^2, measured on orbit by Magruder et al.
// 2021; under 17.4 m by requirement, Markus et al. 2017) from about 496 km; an 83.5 urad field of
// view; the 0.8 m telescope's 0.41 m^2 unobscured; 175 uJ a strong beam's pulse.
TEST(SensorPreset, AtlasMatchesThePublishedInstrument) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "atlas"}})"));
  EXPECT_EQ(c.sensor.preset, "atlas");
  const double fwhm_ns = 2.0 * std::sqrt(2.0 * std::log(2.0)) * c.sensor.pulse_sigma_ns;
  EXPECT_NEAR(fwhm_ns, 1.5, 0.01);
  EXPECT_NEAR(4.0 * c.sensor.divergence_sigma_rad * 496000.0, 11.0, 0.05);
  EXPECT_NEAR(c.sensor.ifov_rad, 83.5e-6, 1e-10);
  EXPECT_LT(c.sensor.telescope_area_m2, std::numbers::pi * 0.4 * 0.4);
  EXPECT_NEAR(c.sensor.telescope_area_m2, 0.41, 1e-9);
  // The field of view takes in the whole beam (its half angle is 7.5 beam sigmas).
  EXPECT_GT(0.5 * c.sensor.ifov_rad, 6.0 * c.sensor.divergence_sigma_rad);
  // Bins much finer than the pulse, and a window holding a 50 m canopy on a slope.
  EXPECT_LT(c.sensor.bin_ns, 0.5 * c.sensor.pulse_sigma_ns);
  EXPECT_GE(c.sensor.bin_ns * c.sensor.bins * 0.299792458 / 2.0, 70.0);
  ASSERT_EQ(c.sensor.bands.size(), 1u);
  EXPECT_EQ(c.sensor.bands[0].name, "532");
  EXPECT_EQ(c.sensor.bands[0].wavelength_nm, 532.0);
  EXPECT_NEAR(c.sensor.bands[0].pulse_energy_mJ, 0.175, 1e-12);
  EXPECT_NEAR(c.sensor.bands[0].atmos_transmission_roundtrip, 0.8 * 0.8, 1e-12);
}

// Photon counting's keys: the receiver, its beam, the background's three forms, the granules'
// switches (absent: decided by the receiver), and what each refuses.
TEST(PhotonCountingKeys, ReceiverBeamsBackgroundAndGranules) {
  const Config plain = parse_config(doc("{}"));
  EXPECT_EQ(plain.sensor.receiver, "waveform");
  EXPECT_EQ(plain.sensor.beams, std::vector<std::string>{"gt2l"});
  EXPECT_EQ(plain.simulation.background, "sun");
  EXPECT_FALSE(plain.output.atl03.has_value());
  EXPECT_NEAR(plain.sensor.photon_efficiency, 0.0675, 1e-12);
  EXPECT_EQ(plain.sensor.dead_time_ns, 3.2);
  const Config c = parse_config(doc(R"({"sensor": {"receiver": "photon_counting",
      "beams": ["gt1r"], "dead_time_ns": 2.5}, "simulation": {"background": {"rate_MHz": 2.5}},
      "output": {"atl08": false}})"));
  EXPECT_EQ(c.sensor.receiver, "photon_counting");
  EXPECT_EQ(c.sensor.beams, std::vector<std::string>{"gt1r"});
  EXPECT_EQ(c.sensor.dead_time_ns, 2.5);
  EXPECT_EQ(c.simulation.background, "rate");
  EXPECT_EQ(c.simulation.background_rate_MHz, 2.5);
  EXPECT_FALSE(c.output.atl03.has_value());
  EXPECT_EQ(c.output.atl08, std::optional<bool>(false));
  EXPECT_EQ(parse_config(doc(R"({"simulation": {"background": "none"}})")).simulation.background,
            "none");
  EXPECT_THAT(error_of(doc(R"({"sensor": {"receiver": "photon_counting", "beams": ["gt4l"]}})")),
              HasSubstr("/sensor/beams: no beam \"gt4l\""));
  EXPECT_EQ(parse_config(doc(R"({"sensor": {"receiver": "photon_counting",
      "beams": ["gt3r", "gt1l"]}})"))
                .sensor.beams,
            (std::vector<std::string>{"gt3r", "gt1l"}));
  EXPECT_THAT(
      error_of(doc(R"({"sensor": {"receiver": "photon_counting", "beams": ["gt1l", "gt1l"]}})")),
      HasSubstr("/sensor/beams: names \"gt1l\" twice"));
  // Issue 42: an empty list ran gt2l without a word.
  EXPECT_THAT(error_of(doc(R"({"sensor": {"receiver": "photon_counting", "beams": []}})")),
              HasSubstr("/sensor/beams: names no beam: name one or more of gt1l"));
  EXPECT_THAT(error_of(doc(R"({"simulation": {"background": "moon"}})")),
              HasSubstr("/simulation/background: must be"));
  EXPECT_THAT(error_of(doc(R"({"simulation": {"background": {"rate_MHz": -1}}})")),
              HasSubstr("/simulation/background/rate_MHz"));
  EXPECT_THAT(error_of(doc(R"({"sensor": {"receiver": "counting"}})")),
              HasSubstr("/sensor/receiver"));
}

TEST(SensorPreset, KeysBesidePresetOverrideIt) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas", "pulse_sigma_ns": 3.5,
      "bins": 200, "bands": [{"name": "1064", "wavelength_nm": 1064, "pulse_energy_mJ": 75,
      "atmos_transmission_roundtrip": 0.95}]}})"));
  EXPECT_EQ(c.sensor.preset, "glas");
  EXPECT_EQ(c.sensor.pulse_sigma_ns, 3.5);
  EXPECT_EQ(c.sensor.bins, 200);
  EXPECT_NEAR(4.0 * c.sensor.divergence_sigma_rad * 600000.0, 70.0, 1.0);  // still glas
  // `bands` replaces the preset's bands as a whole.
  ASSERT_EQ(c.sensor.bands.size(), 1u);
  EXPECT_EQ(c.sensor.bands[0].name, "1064");
  EXPECT_EQ(c.sensor.bands[0].pulse_energy_mJ, 75.0);
  EXPECT_EQ(c.resolved["sensor"]["pulse_sigma_ns"], 3.5);
  EXPECT_EQ(c.resolved["sensor"]["preset"], "glas");
}

TEST(SensorPreset, UnknownPresetListsKnownOnes) {
  const std::string what = error_of(doc(R"({"sensor": {"preset": "icesat2"}})"));
  EXPECT_THAT(what, StartsWith("/sensor/preset: unknown preset \"icesat2\""));
  EXPECT_THAT(what, HasSubstr("gedi"));
  EXPECT_THAT(what, HasSubstr("glas"));
  EXPECT_THAT(what, HasSubstr("north2010"));
  EXPECT_EQ(error_of(doc(R"({"sensor": {"preset": 1}})")),
            "/sensor/preset: must be a string, got 1");
}

TEST(SensorPreset, CompiledPresetsParse) {
  ASSERT_TRUE(sensor_presets().count("north2010"));
  ASSERT_TRUE(sensor_presets().count("glas"));
  ASSERT_TRUE(sensor_presets().count("gedi"));
  ASSERT_TRUE(sensor_presets().count("atlas"));
  for (const auto& [name, text] : sensor_presets())
    EXPECT_TRUE(json::parse(text).is_object()) << name;
}

TEST(Sensor, BandErrors) {
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bands": [{"name": "532", "wavelength_nm": 532,
      "pulse_energy_mJ": 32, "atmos_transmission_roundtrip": 0.8}, {"name": "1064",
      "wavelength_nm": 1064, "atmos_transmission_roundtrip": 0.9}]}})")),
            "/sensor/bands/1/pulse_energy_mJ: is required");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bands": [{"name": "532", "wavelength_nm": 532,
      "pulse_energy_mJ": 32, "atmos_transmission_roundtrip": 0.8}, {"name": "532",
      "wavelength_nm": 1064, "pulse_energy_mJ": 1, "atmos_transmission_roundtrip": 0.9}]}})")),
            "/sensor/bands/1/name: duplicate band name \"532\"");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bands": [{"name": "", "wavelength_nm": 532,
      "pulse_energy_mJ": 32, "atmos_transmission_roundtrip": 0.8}]}})")),
            "/sensor/bands/0/name: must not be empty");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bands": [{"name": "532", "wavelength_nm": 532,
      "pulse_energy_mJ": 32, "atmos_transmission_roundtrip": 0}]}})")),
            "/sensor/bands/0/atmos_transmission_roundtrip: must be in (0, 1], got 0");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bands": []}})")), "/sensor/bands: must not be empty");
  EXPECT_EQ(
      error_of(doc(R"({"sensor": {"bands": [{"name": "532", "wavelength_nm": 532,
      "pulse_energy_mJ": 32, "atmos_transmission_roundtrip": 0.8, "colour": "green"}]}})")),
      "/sensor/bands/0/colour: unknown key \"colour\"; known keys: atmos_transmission_roundtrip, "
      "name, pulse_energy_mJ, wavelength_nm");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"pulse_sigma_ns": 0}})")),
            "/sensor/pulse_sigma_ns: must be in [0.001, 1000], got 0");
  EXPECT_EQ(error_of(doc(R"({"sensor": {"bins": 0}})")), "/sensor/bins: must be >= 1, got 0");
}

// ---- defaults (the seed's Table 1 and the product contract) ---------------------------------

TEST(Defaults, CanopyIsTable1) {
  const Config c = parse_config(doc(R"({"canopy": {}})"));
  ASSERT_TRUE(c.canopy.has_value());
  const CanopySettings& k = *c.canopy;
  EXPECT_EQ(k.pai, 3.0);
  EXPECT_EQ(k.lad, LeafAngleDistribution::spherical);
  EXPECT_EQ(k.cover, 0.7);
  EXPECT_EQ(k.green_fraction, 0.8);
  EXPECT_EQ(k.bark_fraction, 0.2);
  EXPECT_EQ(k.crown_shape, CrownShape::ellipsoid);
  EXPECT_EQ(k.crown_radius_m, 8.0);
  EXPECT_EQ(k.crown_half_height_m, 8.0);
  EXPECT_EQ(k.crown_base_m[0], 15.0);
  EXPECT_EQ(k.crown_base_m[1], 20.0);
  EXPECT_EQ(k.leaf_size_m, 0.05);
  EXPECT_EQ(k.dbh_m, 0.1);
  EXPECT_EQ(k.leaf_reflectance, (std::vector<double>{0.4, 0.4}));
  EXPECT_EQ(k.leaf_transmittance, (std::vector<double>{0.4, 0.4}));
  EXPECT_EQ(k.bark_reflectance, (std::vector<double>{0.3, 0.3}));
  EXPECT_EQ(k.crowns_file, "");
  EXPECT_EQ(k.stands, "");
  // Table 1's soil: smooth, flat, reflectance 0.15.
  EXPECT_EQ(c.terrain.roughness.rms_m, 0.0);
  EXPECT_EQ(c.terrain.roughness.correlation_m, 2.0);
  ASSERT_TRUE(c.terrain.plane.has_value());
  EXPECT_EQ(c.terrain.plane->slope_deg, 0.0);
  EXPECT_EQ(c.terrain.soil_reflectance, (std::vector<double>{0.15, 0.15}));
}

// output.geojson, the old name of output.footprints: read into it with a warning naming the key,
// the resolved configuration under the new name; refused beside the new name.
TEST(OldNames, OutputGeojsonIsOutputFootprintsWithAWarning) {
  const Config old = parse_config(doc(R"({"output": {"geojson": false}})"));
  EXPECT_FALSE(old.output.footprints);
  ASSERT_EQ(old.warnings.size(), 1u);
  EXPECT_EQ(old.warnings[0],
            "/output/geojson: is now output.footprints (the old name still works, for now)");
  EXPECT_EQ(old.resolved["output"]["footprints"], false);
  EXPECT_FALSE(old.resolved["output"].contains("geojson"));
  const Config fresh = parse_config(doc(R"({"output": {"footprints": false}})"));
  EXPECT_FALSE(fresh.output.footprints);
  EXPECT_TRUE(fresh.warnings.empty());
  EXPECT_THROW(parse_config(doc(R"({"output": {"geojson": true, "footprints": true}})")), Error);
}

// Issue 42: output.atl03 asked of the waveform receiver was accepted and wrote nothing.
TEST(OutputKeys, IcesatGranulesAskedOfTheWaveformReceiverAreWarnedAbout) {
  const Config waveform = parse_config(doc(R"({"output": {"atl03": true, "atl08": false}})"));
  ASSERT_EQ(waveform.warnings.size(), 1u);
  EXPECT_EQ(waveform.warnings[0],
            "/output/atl03: the waveform receiver writes no ICESat-2 granule; it is written with "
            "sensor.receiver \"photon_counting\"");
  EXPECT_TRUE(
      parse_config(doc(R"({"sensor": {"receiver": "photon_counting"}, "output": {"atl03": true}})"))
          .warnings.empty());
}

// A list left out is the default the key reference shows (docs/guide/rami.md's five and two
// measurements); brf.rami without `measurements` read as empty and was refused as naming none
// (given empty, `check` still refuses it as naming none).
TEST(Defaults, ListsLeftOutAreTheirDefaults) {
  const Config c = parse_config(doc(R"({"brf": {"rami": {"experiment": "HET01"}},
                                         "output": {"per_order": true,
                                                    "rami": {"experiment": "HOM03"}}})"));
  ASSERT_TRUE(c.brf.rami.has_value());
  EXPECT_EQ(c.brf.rami->measurements,
            (std::vector<std::string>{"brfpp", "brfop", "fabs", "ftran", "falb"}));
  ASSERT_TRUE(c.output.rami.has_value());
  EXPECT_EQ(c.output.rami->measurements, (std::vector<std::string>{"lidar_sgl_co", "lidar_tot"}));
  EXPECT_EQ(c.sensor.beams, std::vector<std::string>{"gt2l"});
}

TEST(Defaults, EverythingElse) {
  const Config c = parse_config(doc("{}"));
  EXPECT_EQ(c.seed, 1u);
  EXPECT_FALSE(c.canopy.has_value());  // bare ground
  EXPECT_EQ(c.simulation.rays_per_shot, 10000);
  EXPECT_EQ(c.simulation.max_order, 8);
  EXPECT_EQ(c.track.type, TrackType::pass);
  EXPECT_EQ(c.track.shots, 1);
  EXPECT_EQ(c.track.rate_hz, 40.0);
  EXPECT_FALSE(c.track.spacing_m.has_value());
  EXPECT_EQ(c.track.altitude_m, 600000.0);
  EXPECT_EQ(c.track.start_time_s, 0.0);
  EXPECT_EQ(c.track.orbit.epoch_s, 0.0);
  EXPECT_TRUE(c.output.netcdf);
  EXPECT_TRUE(c.output.footprints);
  EXPECT_FALSE(c.output.plots);
  EXPECT_FALSE(c.output.per_order);
  EXPECT_EQ(c.brf.sun_zenith_deg, 30.0);
  EXPECT_EQ(c.brf.sun_azimuth_deg, 0.0);
  ASSERT_EQ(c.brf.views.size(), 1u);
  EXPECT_EQ(c.brf.views[0].zenith_deg, 0.0);
  EXPECT_EQ(c.brf.photons, 1000000);
  EXPECT_EQ(c.brf.image_resolution_m, 1.0);
  EXPECT_EQ(c.brf.scene_size_m, 300.0);
}

TEST(Defaults, CanopyNullIsBareGround) {
  json d = doc("{}");
  d["canopy"] = nullptr;
  const Config c = parse_config(d);
  EXPECT_FALSE(c.canopy.has_value());
  EXPECT_TRUE(c.resolved["canopy"].is_null());
}

// ---- the resolved configuration -------------------------------------------------------------

TEST(Resolved, ContainsPresetAndDefaults) {
  const Config c = parse_config(doc(R"({"sensor": {"preset": "glas"}, "canopy": {"leaf_reflectance":
      {"532": 0.1, "1064": 0.45}}, "track": {"start_time": "2005-10-21T12:00:00Z"}})"));
  const json& r = c.resolved;
  EXPECT_EQ(r["seed"], 1);
  EXPECT_EQ(r["sensor"]["preset"], "glas");
  EXPECT_EQ(r["sensor"]["ifov_rad"], 0.0004);
  EXPECT_EQ(r["sensor"]["bands"].size(), 2u);
  EXPECT_EQ(r["sensor"]["bands"][1]["pulse_energy_mJ"], 72);
  EXPECT_EQ(r["simulation"]["rays_per_shot"], 10000);
  EXPECT_EQ(r["simulation"]["max_order"], 8);
  EXPECT_EQ(r["terrain"]["plane"]["slope_deg"], 0.0);
  EXPECT_EQ(r["terrain"]["roughness"]["correlation_m"], 2.0);
  EXPECT_EQ(r["terrain"]["soil_reflectance"], 0.15);
  EXPECT_FALSE(r["terrain"].contains("dem"));
  EXPECT_EQ(r["canopy"]["pai"], 3.0);
  EXPECT_EQ(r["canopy"]["lad"], "spherical");
  EXPECT_EQ(r["canopy"]["crown_shape"], "ellipsoid");
  EXPECT_EQ(r["canopy"]["crown_base_m"], json::array({15.0, 20.0}));
  // Spectral values as given: the per-band object stays an object, a default stays a scalar.
  EXPECT_EQ(r["canopy"]["leaf_reflectance"], json({{"532", 0.1}, {"1064", 0.45}}));
  EXPECT_EQ(r["canopy"]["leaf_transmittance"], 0.4);
  EXPECT_EQ(r["track"]["type"], "pass");
  EXPECT_EQ(r["track"]["start_time"], "2005-10-21T12:00:00Z");
  EXPECT_EQ(r["track"]["epoch"], "2005-10-21T12:00:00Z");  // elements at the first shot
  EXPECT_FALSE(r["track"].contains("spacing_m"));          // unset: has no value
  EXPECT_EQ(r["output"]["netcdf"], true);
  EXPECT_EQ(r["output"]["per_order"], false);
  EXPECT_EQ(r["brf"]["views"], json::parse(R"([{"zenith_deg": 0.0, "azimuth_deg": 0.0}])"));
  EXPECT_EQ(r["brf"]["photons"], 1000000);
}

TEST(Resolved, ParsesBackToTheSameConfiguration) {
  const Config c = parse_config(doc(R"({"seed": 7, "sensor": {"preset": "glas"},
      "canopy": {"pai": 2, "lad": {"ellipsoidal_mean_deg": 30}, "bark_fraction": 0.1},
      "track": {"type": "points", "points": [{"lat_deg": 1, "lon_deg": 2}]}})"));
  const Config again = parse_config(c.resolved);
  EXPECT_EQ(again.resolved, c.resolved);
  EXPECT_EQ(again.seed, 7u);
  ASSERT_TRUE(again.canopy.has_value());
  EXPECT_EQ(again.canopy->lad, LeafAngleDistribution::ellipsoidal);
  EXPECT_EQ(again.canopy->lad_mean_deg, 30.0);
  EXPECT_EQ(again.track.shots, 1);
}

// ---- spectral properties --------------------------------------------------------------------

TEST(Spectral, ScalarAppliesToEveryBand) {
  const Config c = parse_config(doc(R"({"canopy": {"bark_reflectance": 0.25},
      "terrain": {"plane": {}, "soil_reflectance": 0.2}})"));
  EXPECT_EQ(c.canopy->bark_reflectance, (std::vector<double>{0.25, 0.25}));
  EXPECT_EQ(c.terrain.soil_reflectance, (std::vector<double>{0.2, 0.2}));
}

TEST(Spectral, ObjectGivesOneValuePerBandInBandOrder) {
  // The object's keys come in another order than the bands: values follow the bands.
  const Config c = parse_config(doc(R"({"canopy": {"leaf_reflectance": {"1064": 0.45, "532": 0.05},
      "leaf_transmittance": {"532": 0.03, "1064": 0.5}},
      "terrain": {"plane": {}, "soil_reflectance": {"532": 0.1, "1064": 0.4}}})"));
  EXPECT_EQ(c.canopy->leaf_reflectance, (std::vector<double>{0.05, 0.45}));
  EXPECT_EQ(c.canopy->leaf_transmittance, (std::vector<double>{0.03, 0.5}));
  EXPECT_EQ(c.terrain.soil_reflectance, (std::vector<double>{0.1, 0.4}));
}

TEST(Spectral, FollowsTheSensorsBands) {
  const Config c = parse_config(doc(R"({"sensor": {"bands": [
      {"name": "green", "wavelength_nm": 532, "pulse_energy_mJ": 1, "atmos_transmission_roundtrip": 1},
      {"name": "red", "wavelength_nm": 660, "pulse_energy_mJ": 1, "atmos_transmission_roundtrip": 1},
      {"name": "nir", "wavelength_nm": 1064, "pulse_energy_mJ": 1, "atmos_transmission_roundtrip": 1}]},
      "canopy": {"leaf_reflectance": {"green": 0.1, "red": 0.05, "nir": 0.45}}})"));
  EXPECT_EQ(c.canopy->leaf_reflectance, (std::vector<double>{0.1, 0.05, 0.45}));
  EXPECT_EQ(c.canopy->leaf_transmittance, (std::vector<double>{0.4, 0.4, 0.4}));
}

TEST(Spectral, Errors) {
  EXPECT_EQ(error_of(doc(R"({"canopy": {"leaf_reflectance": {"532": 0.1}}})")),
            "/canopy/leaf_reflectance: missing band \"1064\": give a value for every band, or one "
            "number for all");
  EXPECT_EQ(
      error_of(doc(R"({"canopy": {"leaf_reflectance": {"532": 0.1, "1064": 0.4, "700": 0.2}}})")),
      "/canopy/leaf_reflectance/700: unknown band \"700\"; the bands are 532, 1064");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"leaf_reflectance": {"532": 1.5, "1064": 0.4}}})")),
            "/canopy/leaf_reflectance/532: must be in [0, 1], got 1.5");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {}, "soil_reflectance": -0.1}})")),
            "/terrain/soil_reflectance: must be in [0, 1], got -0.1");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"bark_reflectance": "dark"}})")),
            "/canopy/bark_reflectance: must be a number or an object keyed by band name (532, "
            "1064), got \"dark\"");
}

// ---- the configuration errors of PRODUCT.md §5 ----------------------------------------------

TEST(Errors, MalformedJsonNamesFileLineAndColumn) {
  TempDir dir;
  const auto file = dir.write("config.json", "{\n  \"seed\": 1,\n  \"canopy\" 2\n}\n");
  try {
    read_json_file(file);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::config);
    EXPECT_EQ(e.place(), file.string());
    const std::string what = e.what();
    EXPECT_THAT(what, StartsWith(file.string() + ": malformed JSON at line 3, column 12: "));
    EXPECT_THAT(what, HasSubstr("syntax error"));
    EXPECT_EQ(what.find('\n'), std::string::npos);
    EXPECT_EQ(what.find("json.exception"), std::string::npos);
  }
  // Column counted on the bad token's line, also when the token is not last on its line.
  const auto inline_error = dir.write("inline.json", "{\"a\": 1,\n \"b\": tru, \"c\": 2}");
  try {
    read_json_file(inline_error);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("malformed JSON at line 2, column "));
  }
  const auto empty = dir.write("empty.json", "");
  try {
    read_json_file(empty);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("malformed JSON at line 1, column 1: "));
  }
}

TEST(Errors, MissingFile) {
  TempDir dir;
  const auto file = dir.path() / "absent.json";
  try {
    load_config(file, {});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), file.string());
    EXPECT_THAT(e.what(), HasSubstr("cannot read"));
    EXPECT_EQ(e.exit_status(), 2);
  }
  try {
    read_json_file(dir.path());
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_THAT(e.what(), HasSubstr("cannot read"));
  }
}

TEST(Errors, UnknownKeySuggestsTheNearest) {
  EXPECT_EQ(error_of(doc(R"({"canopy": {"pia": 2}})")),
            "/canopy/pia: unknown key \"pia\"; did you mean \"pai\"?");
  EXPECT_EQ(error_of(doc(R"({"simulaton": {}})")),
            "/simulaton: unknown key \"simulaton\"; did you mean \"simulation\"?");
  EXPECT_EQ(error_of(doc(R"({"track": {"rate_Hz": 40}})")),
            "/track/rate_Hz: unknown key \"rate_Hz\"; did you mean \"rate_hz\"?");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {"slope": 3}}})")),
            "/terrain/plane/slope: unknown key \"slope\"; did you mean \"slope_deg\"?");
  EXPECT_EQ(error_of(doc(R"({"brf": {"views": [{}, {"zenith": 10}]}})")),
            "/brf/views/1/zenith: unknown key \"zenith\"; did you mean \"zenith_deg\"?");
  // Nothing close: the known keys are listed instead of a guess.
  EXPECT_EQ(error_of(doc(R"({"output": {"xyz": true}})")),
            "/output/xyz: unknown key \"xyz\"; known keys: atl03, atl08, footprints, "
            "footprints_format, gedi_l1b, gedi_l2a, geojson, glah01, glah14, glas_ellipsoid, "
            "metrics, netcdf, per_order, plots, rami");
}

TEST(Errors, WrongTypes) {
  EXPECT_EQ(error_of(doc(R"({"simulation": {"rays_per_shot": "many"}})")),
            "/simulation/rays_per_shot: must be an integer, got \"many\"");
  EXPECT_EQ(error_of(doc(R"({"simulation": {"rays_per_shot": 2.5}})")),
            "/simulation/rays_per_shot: must be an integer, got 2.5");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"pai": "3"}})")),
            "/canopy/pai: must be a number, got \"3\"");
  EXPECT_EQ(error_of(doc(R"({"output": {"plots": 1}})")),
            "/output/plots: must be a boolean (true or false), got 1");
  EXPECT_EQ(error_of(doc(R"({"output": {"plots": "yes"}})")),
            "/output/plots: must be a boolean (true or false), got \"yes\"");
  EXPECT_EQ(error_of(doc(R"({"canopy": 3})")), "/canopy: must be an object, got 3");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"dem": 5}})")), "/terrain/dem: must be a string, got 5");
  EXPECT_EQ(error_of(doc(R"({"seed": -1})")), "/seed: must be >= 0, got -1");
  EXPECT_EQ(error_of(json::array()), "the configuration must be a JSON object, got []");
  // An integral number written as a float is an integer.
  EXPECT_EQ(parse_config(doc(R"({"simulation": {"rays_per_shot": 1e4}})")).simulation.rays_per_shot,
            10000);
  EXPECT_EQ(parse_config(doc(R"({"seed": 18446744073709551615})")).seed,
            std::numeric_limits<std::uint64_t>::max());
}

TEST(Errors, OutOfRange) {
  EXPECT_EQ(error_of(doc(R"({"canopy": {"pai": -1}})")), "/canopy/pai: must be >= 0, got -1");
  EXPECT_EQ(
      error_of(doc(R"({"canopy": {"leaf_reflectance": 0.6, "leaf_transmittance": 0.6}})")),
      "/canopy/leaf_transmittance: leaf_reflectance + leaf_transmittance must be <= 1 in band "
      "532, got 1.2");
  EXPECT_EQ(
      error_of(doc(R"({"canopy": {"leaf_reflectance": {"532": 0.1, "1064": 0.7},
      "leaf_transmittance": 0.35}})")),
      "/canopy/leaf_transmittance: leaf_reflectance + leaf_transmittance must be <= 1 in band "
      "1064, got 1.05");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"cover": 1.5}})")),
            "/canopy/cover: must be in [0, 1], got 1.5");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"cover": -0.1}})")),
            "/canopy/cover: must be in [0, 1], got -0.1");
  EXPECT_EQ(error_of(doc(R"({"simulation": {"rays_per_shot": 0}})")),
            "/simulation/rays_per_shot: must be >= 1, got 0");
  EXPECT_EQ(error_of(doc(R"({"simulation": {"max_order": 0}})")),
            "/simulation/max_order: must be >= 1, got 0");
  EXPECT_EQ(error_of(doc(R"({"track": {"off_nadir_deg": 45}})")),
            "/track/off_nadir_deg: must be in [0, 45), got 45");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {"slope_deg": 90}}})")),
            "/terrain/plane/slope_deg: must be in [0, 89], got 90");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {"origin_lat_deg": 91}}})")),
            "/terrain/plane/origin_lat_deg: must be in [-90, 90], got 91");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {}, "roughness": {"correlation_m": 0}}})")),
            "/terrain/roughness/correlation_m: must be > 0, got 0");
  EXPECT_EQ(error_of(doc(R"({"brf": {"sun_zenith_deg": 90}})")),
            "/brf/sun_zenith_deg: must be in [0, 90), got 90");
  EXPECT_EQ(error_of(doc(R"({"brf": {"photons": 0}})")), "/brf/photons: must be >= 1, got 0");
  EXPECT_EQ(error_of(doc(R"({"track": {"semi_major_axis_m": 6000000}})")),
            "/track/semi_major_axis_m: must be in (6378137, 46378137], got 6000000");
  EXPECT_EQ(error_of(doc(R"({"track": {"eccentricity": 1}})")),
            "/track/eccentricity: must be in [0, 1), got 1");
}

TEST(Errors, NonFiniteNumbers) {
  // nlohmann-json refuses 1e999 while parsing; the error still names the key, line and column.
  TempDir dir;
  const auto file =
      dir.write("config.json", "{\"terrain\": {\"plane\": {}},\n \"canopy\": {\"pai\": 1e999}}\n");
  try {
    load_config(file, {});
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/canopy/pai");
    EXPECT_EQ(std::string(e.what()), "/canopy/pai: must be a finite number, got 1e999 (" +
                                         file.string() + ", line 2, column 20)");
  }
  const auto in_array = dir.write("array.json", "{\"canopy\": {\"crown_base_m\": [1, -1e400]}}");
  try {
    read_json_file(in_array);
    FAIL() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(e.place(), "/canopy/crown_base_m/1");
  }
  // A document built in code can hold infinities and NaN; they are refused too.
  json d = doc("{}");
  d["canopy"]["pai"] = std::numeric_limits<double>::infinity();
  EXPECT_EQ(error_of(d), "/canopy/pai: must be a finite number, got inf");
  d["canopy"]["pai"] = std::nan("");
  EXPECT_THAT(error_of(d), StartsWith("/canopy/pai: must be a finite number"));
  d = doc("{}");
  d["simulation"]["rays_per_shot"] = std::numeric_limits<double>::infinity();
  EXPECT_THAT(error_of(d), StartsWith("/simulation/rays_per_shot: must be a finite number"));
  d = doc("{}");
  d["canopy"]["leaf_reflectance"]["532"] = std::numeric_limits<double>::infinity();
  d["canopy"]["leaf_reflectance"]["1064"] = 0.4;
  EXPECT_THAT(error_of(d), StartsWith("/canopy/leaf_reflectance/532: must be a finite number"));
}

TEST(Errors, TerrainNeedsExactlyOneOfDemPlaneAndPointCloud) {
  EXPECT_EQ(error_of(doc(R"({"terrain": {}})")),
            "/terrain: give exactly one of \"dem\", \"plane\" and \"point_cloud\"");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"dem": "a.tif", "plane": {}}})")),
            "/terrain: give exactly one of \"dem\" and \"plane\", not both");
  EXPECT_EQ(error_of(json::object()),
            "/terrain: is required: give \"dem\", \"plane\" or \"point_cloud\"");
  // The point cloud's ground beside another, or false, is refused at its own key.
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {}, "point_cloud": true}})")),
            "/terrain/point_cloud: cannot be given beside terrain.plane: the ground is one of "
            "\"dem\", \"plane\" and \"point_cloud\"");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"dem": "a.tif", "point_cloud": true}})")),
            "/terrain/point_cloud: cannot be given beside terrain.dem: the ground is one of "
            "\"dem\", \"plane\" and \"point_cloud\"");
  EXPECT_THAT(error_of(doc(R"({"terrain": {"point_cloud": false}})")),
              StartsWith("/terrain/point_cloud: must be true"));
  EXPECT_THAT(error_of(doc(R"({"terrain": {"point_cloud": 1}})")),
              StartsWith("/terrain/point_cloud: must be a boolean"));
  // Without a point cloud in the canopy there is no ground to take.
  EXPECT_THAT(error_of(doc(R"({"terrain": {"point_cloud": true}})")),
              StartsWith("/terrain/point_cloud: is the ground of canopy.point_cloud's cloud, and "
                         "the canopy has no point cloud"));
  EXPECT_THAT(error_of(doc(R"({"terrain": {"point_cloud": true, "dem_band": 2}})")),
              StartsWith("/terrain/dem_band: applies to terrain.dem only"));
  EXPECT_EQ(error_of(doc(R"({"terrain": {"dem": ""}})")), "/terrain/dem: must not be empty");
  const Config c = parse_config(doc(R"({"terrain": {"dem": "/data/dem.tif"}})"));
  EXPECT_EQ(c.terrain.dem, "/data/dem.tif");
  EXPECT_FALSE(c.terrain.plane.has_value());
}

// PRODUCT.md §6's example: a wrong value is named before the terrain that is not given, in
// whichever section it is.
TEST(Errors, AWrongValueIsNamedBeforeAMissingTerrain) {
  const json example = json::parse(R"({"canopy": {"pai": -1}})");
  EXPECT_EQ(error_of(example), "/canopy/pai: must be >= 0, got -1");
  EXPECT_EQ(place_of(example), "/canopy/pai");
  EXPECT_EQ(error_of(json::parse(R"({"output": {"netcdf": 1}})")),
            "/output/netcdf: must be a boolean (true or false), got 1");
  // With every given value right, the missing terrain is the error.
  EXPECT_EQ(error_of(json::parse(R"({"canopy": {"pai": 1}})")),
            "/terrain: is required: give \"dem\", \"plane\" or \"point_cloud\"");
  EXPECT_EQ(place_of(json::parse(R"({"terrain": null})")), "/terrain");
  // A misspelt terrain is named as such, with the key it was meant to be.
  EXPECT_EQ(error_of(json::parse(R"({"terrian": {"plane": {}}})")),
            "/terrian: unknown key \"terrian\"; did you mean \"terrain\"?");
}

TEST(Terrain, DemBandAndVerticalDatum) {
  // Defaults: no band chosen (a one-band raster), heights above the ellipsoid.
  Config c = parse_config(doc(R"({"terrain": {"dem": "/data/dem.tif"}})"));
  EXPECT_EQ(c.terrain.dem_band, 0);
  EXPECT_EQ(c.terrain.vertical_datum, "ellipsoid");
  EXPECT_EQ(c.resolved["terrain"]["vertical_datum"], "ellipsoid");
  EXPECT_FALSE(c.resolved["terrain"].contains("dem_band"));
  c = parse_config(
      doc(R"({"terrain": {"dem": "a.tif", "dem_band": 2, "vertical_datum": "egm96"}})"));
  EXPECT_EQ(c.terrain.dem_band, 2);
  EXPECT_EQ(c.terrain.vertical_datum, "egm96");
  EXPECT_EQ(parse_config(c.resolved).resolved, c.resolved);
  c = parse_config(doc(R"({"terrain": {"dem": "a.tif", "vertical_datum": "EPSG:3855"}})"));
  EXPECT_EQ(c.terrain.vertical_datum, "EPSG:3855");  // PROJ judges it when the DEM is opened

  EXPECT_EQ(error_of(doc(R"({"terrain": {"dem": "a.tif", "dem_band": 0}})")),
            "/terrain/dem_band: must be >= 1, got 0");
  EXPECT_EQ(error_of(doc(R"({"terrain": {"plane": {}, "dem_band": 1}})")),
            "/terrain/dem_band: applies to terrain.dem only");
  EXPECT_THAT(
      error_of(doc(R"({"terrain": {"dem": "a.tif", "vertical_datum": "egm69"}})")),
      AllOf(StartsWith("/terrain/vertical_datum: must be"), HasSubstr("did you mean \"egm96\"?")));
  EXPECT_THAT(
      error_of(doc(R"({"terrain": {"plane": {}, "vertical_datum": "egm96"}})")),
      StartsWith("/terrain/vertical_datum: applies to terrain.dem and terrain.point_cloud only"));
  // A plane's resolved configuration says "ellipsoid", and parses back.
  c = parse_config(doc(R"({"terrain": {"plane": {}}})"));
  EXPECT_EQ(c.resolved["terrain"]["vertical_datum"], "ellipsoid");
  EXPECT_EQ(parse_config(c.resolved).resolved, c.resolved);
}

// ---- canopy shapes --------------------------------------------------------------------------

TEST(Canopy, Fractions) {
  EXPECT_EQ(error_of(doc(R"({"canopy": {"green_fraction": 0.7, "bark_fraction": 0.2}})")),
            "/canopy/bark_fraction: green_fraction + bark_fraction must be 1, got 0.9");
  // One fraction given implies the other.
  Config c = parse_config(doc(R"({"canopy": {"bark_fraction": 0.1}})"));
  EXPECT_EQ(c.canopy->green_fraction, 0.9);
  c = parse_config(doc(R"({"canopy": {"green_fraction": 1}})"));
  EXPECT_EQ(c.canopy->bark_fraction, 0.0);
  EXPECT_EQ(c.resolved["canopy"]["bark_fraction"], 0.0);
}

TEST(Canopy, LeafAngleDistribution) {
  const std::vector<std::pair<std::string, LeafAngleDistribution>> names = {
      {"spherical", LeafAngleDistribution::spherical},
      {"planophile", LeafAngleDistribution::planophile},
      {"erectophile", LeafAngleDistribution::erectophile},
      {"plagiophile", LeafAngleDistribution::plagiophile},
      {"extremophile", LeafAngleDistribution::extremophile},
      {"uniform", LeafAngleDistribution::uniform}};
  for (const auto& [name, lad] : names) {
    json d = doc(R"({"canopy": {}})");
    d["canopy"]["lad"] = name;
    EXPECT_EQ(parse_config(d).canopy->lad, lad) << name;
  }
  const Config c = parse_config(doc(R"({"canopy": {"lad": {"ellipsoidal_mean_deg": 20}}})"));
  EXPECT_EQ(c.canopy->lad, LeafAngleDistribution::ellipsoidal);
  EXPECT_EQ(c.canopy->lad_mean_deg, 20.0);
  EXPECT_EQ(c.resolved["canopy"]["lad"], json({{"ellipsoidal_mean_deg", 20}}));
  EXPECT_EQ(error_of(doc(R"({"canopy": {"lad": {"ellipsoidal_mean_deg": 90}}})")),
            "/canopy/lad/ellipsoidal_mean_deg: must be in (0, 90), got 90");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"lad": {}}})")),
            "/canopy/lad/ellipsoidal_mean_deg: is required");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"lad": "sphercal"}})")),
            "/canopy/lad: must be one of spherical, planophile, erectophile, plagiophile, "
            "extremophile, uniform, or {\"ellipsoidal_mean_deg\": X}, got \"sphercal\"; did you "
            "mean \"spherical\"?");
  EXPECT_THAT(error_of(doc(R"({"canopy": {"lad": 3}})")),
              StartsWith("/canopy/lad: must be a name"));
}

TEST(Canopy, CrownsAndPaths) {
  const Config c = parse_config(doc(R"({"canopy": {"crown_shape": "layer", "crown_base_m": [2, 2],
      "crowns_file": "crowns.csv"}})"));
  EXPECT_EQ(c.canopy->crown_shape, CrownShape::layer);
  EXPECT_EQ(c.canopy->crown_base_m[0], 2.0);
  EXPECT_EQ(c.canopy->crowns_file, "crowns.csv");
  EXPECT_EQ(c.resolved["canopy"]["crowns_file"], "crowns.csv");
  EXPECT_FALSE(c.resolved["canopy"].contains("stands"));
  EXPECT_EQ(error_of(doc(R"({"canopy": {"crown_base_m": [20, 15]}})")),
            "/canopy/crown_base_m: min must be <= max, got [20,15]");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"crown_base_m": [-1, 15]}})")),
            "/canopy/crown_base_m/0: must be >= 0, got -1");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"crown_base_m": [15]}})")),
            "/canopy/crown_base_m: must be an array of 2 numbers [min, max], got [15]");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"crown_shape": "box"}})")),
            "/canopy/crown_shape: must be one of ellipsoid, cone, layer, got \"box\"");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"crown_shape": "ellipse"}})")),
            "/canopy/crown_shape: must be one of ellipsoid, cone, layer, got \"ellipse\"; did you "
            "mean \"ellipsoid\"?");
  EXPECT_EQ(error_of(doc(R"({"canopy": {"crown_radius_m": 0}})")),
            "/canopy/crown_radius_m: must be in (0, 100], got 0");
}

// ---- track ----------------------------------------------------------------------------------

TEST(Track, Pass) {
  const Config c = parse_config(doc(R"({"track": {"start_lat_deg": 34.3, "start_lon_deg": -118.2,
      "heading_deg": 10, "shots": 100, "spacing_m": 172, "start_time": "2005-10-21T12:00:00Z"}})"));
  EXPECT_EQ(c.track.type, TrackType::pass);
  EXPECT_EQ(c.track.start_lat_deg, 34.3);
  EXPECT_EQ(c.track.start_lon_deg, -118.2);
  EXPECT_EQ(c.track.shots, 100);
  EXPECT_EQ(c.track.spacing_m, 172.0);
  EXPECT_EQ(c.track.start_time_s, 183168000.0);
  EXPECT_EQ(
      error_of(doc(R"({"track": {"start_time": "21/10/2005"}})")).rfind("/track/start_time: ", 0),
      0u);
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "spiral"}})")),
            "/track/type: must be one of pass, points, orbit, ephemeris, granule, got \"spiral\"");
}

TEST(Track, GranuleNeedsAFileAndTakesBeamsAsStrings) {
  const Config c = parse_config(
      doc(R"({"track": {"type": "granule", "file": "g.h5", "beams": ["BEAM0101", "BEAM1011"]}})"));
  EXPECT_EQ(c.track.type, TrackType::granule);
  EXPECT_EQ(c.track.granule, "g.h5");
  EXPECT_EQ(c.track.beams, (std::vector<std::string>{"BEAM0101", "BEAM1011"}));
  EXPECT_EQ(c.resolved["track"]["beams"], json::array({"BEAM0101", "BEAM1011"}));
  EXPECT_TRUE(
      parse_config(doc(R"({"track": {"type": "granule", "file": "g.h5"}})")).track.beams.empty());
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "granule"}})")),
            "/track/file: is required when type is \"granule\"");
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "granule", "file": "g.h5", "beams": "BEAM0101"}})"))
                .rfind("/track/beams: must be an array of strings", 0),
            0u);
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "granule", "file": "g.h5", "beams": [3]}})"))
                .rfind("/track/beams: must be an array of non-empty strings", 0),
            0u);
}

TEST(Track, PointsSetTheNumberOfShots) {
  const Config c = parse_config(doc(R"({"track": {"type": "points", "points": [
      {"lat_deg": 10, "lon_deg": 20}, {"lat_deg": -10.5, "lon_deg": 200}]}})"));
  ASSERT_EQ(c.track.points.size(), 2u);
  EXPECT_EQ(c.track.points[1].lat_deg, -10.5);
  EXPECT_EQ(c.track.points[1].lon_deg, 200.0);
  EXPECT_EQ(c.track.shots, 2);
  EXPECT_EQ(c.resolved["track"]["shots"], 2);
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "points", "shots": 3, "points": [
      {"lat_deg": 10, "lon_deg": 20}]}})")),
            "/track/shots: must equal the number of points (1) when type is \"points\", got 3");
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "points"}})")), "/track/points: is required");
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "points", "points": []}})")),
            "/track/points: must not be empty");
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "points", "points": [{"lat_deg": 1}]}})")),
            "/track/points/0/lon_deg: is required");
  EXPECT_EQ(
      error_of(doc(R"({"track": {"type": "points", "points": [{"lat_deg": 100, "lon_deg": 0}]}})")),
      "/track/points/0/lat_deg: must be in [-90, 90], got 100");
}

TEST(Track, OrbitAndEphemeris) {
  const Config c = parse_config(doc(R"({"track": {"type": "orbit", "semi_major_axis_m": 6970000,
      "eccentricity": 0.0013, "inclination_deg": 94, "raan_deg": 12, "arg_perigee_deg": 90,
      "mean_anomaly_deg": 45, "epoch": "2000-01-02T12:00:00Z"}})"));
  EXPECT_EQ(c.track.type, TrackType::orbit);
  EXPECT_EQ(c.track.orbit.semi_major_axis_m, 6970000.0);
  EXPECT_EQ(c.track.orbit.eccentricity, 0.0013);
  EXPECT_EQ(c.track.orbit.inclination_deg, 94.0);
  EXPECT_EQ(c.track.orbit.raan_deg, 12.0);
  EXPECT_EQ(c.track.orbit.arg_perigee_deg, 90.0);
  EXPECT_EQ(c.track.orbit.mean_anomaly_deg, 45.0);
  EXPECT_EQ(c.track.orbit.epoch_s, 86400.0);
  EXPECT_THAT(error_of(doc(R"({"track": {"type": "orbit", "semi_major_axis_m": 7000000,
      "eccentricity": 0.5}})")),
              StartsWith("/track/eccentricity: puts the perigee"));
  EXPECT_EQ(error_of(doc(R"({"track": {"type": "ephemeris"}})")),
            "/track/ephemeris: is required when type is \"ephemeris\"");
  EXPECT_EQ(parse_config(doc(R"({"track": {"type": "ephemeris", "ephemeris": "/e.csv"}})"))
                .track.ephemeris,
            "/e.csv");
}

// ---- overrides ------------------------------------------------------------------------------

TEST(Override, ValuesParseAsJsonElseString) {
  json d = doc(R"({"canopy": {"pai": 3}})");
  apply_override(d, "canopy.pai=2");
  EXPECT_EQ(d["canopy"]["pai"], 2);
  apply_override(d, "canopy.lad={\"ellipsoidal_mean_deg\": 30}");
  EXPECT_EQ(d["canopy"]["lad"], json({{"ellipsoidal_mean_deg", 30}}));
  apply_override(d, "canopy.crown_base_m=[1, 2]");
  EXPECT_EQ(d["canopy"]["crown_base_m"], json::array({1, 2}));
  apply_override(d, "output.plots=true");  // creates `output`
  EXPECT_EQ(d["output"]["plots"], true);
  apply_override(d, "terrain.dem=dems/site 1.tif");  // not JSON: a string
  EXPECT_EQ(d["terrain"]["dem"], "dems/site 1.tif");
  apply_override(d, "track.start_time=2005-10-21T12:00:00Z");
  EXPECT_EQ(d["track"]["start_time"], "2005-10-21T12:00:00Z");
  apply_override(d, "sensor.preset=\"glas\"");  // a JSON string
  EXPECT_EQ(d["sensor"]["preset"], "glas");
  apply_override(d, "a.b=x=y");  // only the first '=' separates
  EXPECT_EQ(d["a"]["b"], "x=y");
  apply_override(d, "a.empty=");
  EXPECT_EQ(d["a"]["empty"], "");
}

TEST(Override, CreatesNestedObjects) {
  json d = json::object();
  apply_override(d, "terrain.plane.slope_deg=20");
  EXPECT_EQ(d, json::parse(R"({"terrain": {"plane": {"slope_deg": 20}}})"));
  json empty;  // null document
  apply_override(empty, "x.y.z=1");
  EXPECT_EQ(empty, json::parse(R"({"x": {"y": {"z": 1}}})"));
}

TEST(Override, NullAndObjectsInPlaceOfNull) {
  json d = doc(R"({"canopy": {"pai": 3}})");
  apply_override(d, "canopy=null");
  EXPECT_TRUE(d["canopy"].is_null());
  EXPECT_FALSE(parse_config(d).canopy.has_value());
  apply_override(d, "canopy.pai=1.5");  // a null canopy becomes a canopy again
  const Config c = parse_config(d);
  ASSERT_TRUE(c.canopy.has_value());
  EXPECT_EQ(c.canopy->pai, 1.5);
}

TEST(Override, ArrayElementsByIndex) {
  json d = doc(R"({"sensor": {"bands": [
      {"name": "532", "wavelength_nm": 532, "pulse_energy_mJ": 32, "atmos_transmission_roundtrip": 0.8},
      {"name": "1064", "wavelength_nm": 1064, "pulse_energy_mJ": 72, "atmos_transmission_roundtrip": 0.9}]}})");
  apply_override(d, "sensor.bands.1.pulse_energy_mJ=10");
  EXPECT_EQ(parse_config(d).sensor.bands[1].pulse_energy_mJ, 10.0);
  EXPECT_THROW(apply_override(d, "sensor.bands.2.name=x"), Error);
  EXPECT_THROW(apply_override(d, "sensor.bands.first.name=x"), Error);
}

TEST(Override, Errors) {
  json d = doc("{}");
  auto what = [&](const std::string& assignment) -> std::string {
    try {
      apply_override(d, assignment);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::config);
      return e.place();
    }
    return "(no error)";
  };
  EXPECT_EQ(what("canopy.pai"), "--set");
  EXPECT_EQ(what("=2"), "--set");
  EXPECT_EQ(what("canopy..pai=2"), "--set");
  EXPECT_EQ(what("canopy.pai.=2"), "--set");
  d["seed"] = 1;
  EXPECT_EQ(what("seed.x=2"), "--set");  // through a number
  EXPECT_EQ(what("canopy.pai=1e999"), "/canopy/pai");
  try {
    apply_override(d, "canopy.pai");
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), "--set: expected KEY=VALUE, got \"canopy.pai\"");
  }
}

TEST(Override, UnknownKeyFromSetIsStillCaught) {
  json d = doc("{}");
  apply_override(d, "canopy.pia=2");
  EXPECT_EQ(place_of(d), "/canopy/pia");
}

// ---- load_config ----------------------------------------------------------------------------

TEST(LoadConfig, OverridesInOrderAndPathsRelativeToTheFile) {
  TempDir dir;
  // The stands file is read with the configuration; the others are opened later by their readers.
  const std::string stands =
      std::filesystem::absolute(
          dir.write("elsewhere/stands.geojson",
                    R"({"type": "FeatureCollection", "features": [{"type": "Feature",
                        "properties": {"pai": 1}, "geometry": {"type": "Polygon", "coordinates":
                        [[[0, 0], [1, 0], [1, 1], [0, 0]]]}}]})"))
          .string();
  const auto file = dir.write("site/config.json", R"({
    "terrain": {"dem": "dems/dem.tif"},
    "canopy": {"pai": 3, "stands": ")" + stands + R"(", "crowns_file": "../crowns.csv"},
    "track": {"type": "ephemeris", "ephemeris": "eph.csv"}
  })");
  const Config c = load_config(file, {"canopy.pai=2", "canopy.cover=0.5", "canopy.pai=4"});
  EXPECT_EQ(c.canopy->pai, 4.0);
  EXPECT_EQ(c.canopy->cover, 0.5);
  const auto site = std::filesystem::absolute(dir.path() / "site");
  EXPECT_EQ(c.terrain.dem, (site / "dems" / "dem.tif").lexically_normal().string());
  EXPECT_EQ(c.canopy->crowns_file,
            (std::filesystem::absolute(dir.path()) / "crowns.csv").lexically_normal().string());
  EXPECT_EQ(c.canopy->stands, stands);
  EXPECT_EQ(c.track.ephemeris, (site / "eph.csv").lexically_normal().string());
  EXPECT_EQ(c.resolved["terrain"]["dem"], c.terrain.dem);
  EXPECT_EQ(c.resolved["canopy"]["crowns_file"], c.canopy->crowns_file);
  EXPECT_EQ(c.resolved["canopy"]["pai"], 4);
}

TEST(LoadConfig, BareGroundResolvedHasNoDanglingPaths) {
  TempDir dir;
  const auto file = dir.write("config.json", R"({"terrain": {"plane": {}}})");
  const Config c = load_config(file, {});
  EXPECT_FALSE(c.resolved["terrain"].contains("dem"));
  EXPECT_FALSE(c.resolved["track"].contains("ephemeris"));
  EXPECT_TRUE(c.resolved["canopy"].is_null());
}

// ---- detector -------------------------------------------------------------------------------

TEST(Detector, OffByDefaultWithNeutralSettings) {
  const Config c = parse_config(doc("{}"));
  EXPECT_FALSE(c.detector.enabled);
  EXPECT_EQ(c.detector.background_W, 0.0);
  EXPECT_FALSE(c.detector.photon_noise);
  EXPECT_EQ(c.detector.quantum_efficiency, 1.0);
  EXPECT_EQ(c.detector.noise_rms_W, 0.0);
  EXPECT_EQ(c.detector.gain, 1.0);
  EXPECT_EQ(c.detector.bits, 0);
  EXPECT_FALSE(c.detector.saturation_W.has_value());
  EXPECT_EQ(c.resolved["detector"],
            json::parse(R"({"enabled": false, "background_W": 0.0, "photon_noise": false,
                            "quantum_efficiency": 1.0, "noise_rms_W": 0.0, "gain": 1.0,
                            "bits": 0, "saturation_W": null})"));
}

TEST(Detector, EveryKeyIsRead) {
  const Config c = parse_config(doc(R"({"detector": {"enabled": true, "background_W": 1e-8,
      "photon_noise": true, "quantum_efficiency": 0.3, "noise_rms_W": 2e-8, "gain": 50,
      "bits": 8, "saturation_W": 1e-4}})"));
  EXPECT_TRUE(c.detector.enabled);
  EXPECT_EQ(c.detector.background_W, 1e-8);
  EXPECT_TRUE(c.detector.photon_noise);
  EXPECT_EQ(c.detector.quantum_efficiency, 0.3);
  EXPECT_EQ(c.detector.noise_rms_W, 2e-8);
  EXPECT_EQ(c.detector.gain, 50.0);
  EXPECT_EQ(c.detector.bits, 8);
  EXPECT_EQ(c.detector.saturation_W, 1e-4);
  EXPECT_EQ(parse_config(c.resolved).resolved, c.resolved);
}

TEST(Detector, Errors) {
  EXPECT_EQ(error_of(doc(R"({"detector": {"bits": 8}})")),
            "/detector/saturation_W: is required when bits > 0: the digitiser's full scale");
  EXPECT_EQ(error_of(doc(R"({"detector": {"noise_rms_W": -1}})")),
            "/detector/noise_rms_W: must be in [0, 1], got -1");
  EXPECT_EQ(error_of(doc(R"({"detector": {"gain": 0}})")),
            "/detector/gain: must be in (0, 1e+12], got 0");
  EXPECT_EQ(place_of(doc(R"({"detector": {"bits": 33, "saturation_W": 1}})")), "/detector/bits");
  EXPECT_EQ(place_of(doc(R"({"detector": {"quantum_efficiency": 0}})")),
            "/detector/quantum_efficiency");
  EXPECT_THAT(error_of(doc(R"({"detector": {"noise_rms": 1e-8}})")),
              HasSubstr("did you mean \"noise_rms_W\"?"));
}

}  // namespace
}  // namespace glaswave
