// What the transport tests share: the lidar of the seed's Table 2, typed from the table, and
// crowns over level ground seen from 600 km at nadir.
#pragma once

#include <memory>
#include <vector>

#include "canopy/leaf_angles.hpp"
#include "footprints/atmosphere_settings.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/terrain.hpp"

namespace glaswave::test_support {

// A layer of the same optical depth in every band, with each band's single-scattering albedo.
inline AtmosphereLayer uniform_layer(double base_m, double top_m, double tau,
                                     std::vector<double> albedo, AtmospherePhase phase) {
  AtmosphereLayer l;
  l.base_m = base_m;
  l.top_m = top_m;
  l.optical_depth.assign(albedo.size(), tau);
  l.single_scattering_albedo = std::move(albedo);
  l.phase = phase;
  return l;
}

// Table 2 of the seed: a 5 ns pulse, 0.11 mrad beam, 0.4 mrad field of view, a 0.95 m telescope
// (0.709 m^2), 1 ns bins, 544 of them; 32 mJ at 532 nm and 72 mJ at 1064 nm with round-trip
// transmissions 0.8 and 0.9.
inline LidarSettings table2_sensor() {
  LidarSettings sensor;
  sensor.pulse_sigma_ns = 5.0;
  sensor.divergence_sigma_rad = 0.00011;
  sensor.ifov_rad = 0.0004;
  sensor.telescope_area_m2 = 0.709;
  sensor.bin_ns = 1.0;
  sensor.bins = 544;
  sensor.bands = {{532.0, 32.0, 0.8, "532"}, {1064.0, 72.0, 0.9, "1064"}};
  return sensor;
}

// Crowns over level ground (150 m around the origin), seen from 600 km at nadir, with spherical
// leaves; `foliage` gives each crown material its optics (reflectance, transmittance, trunk
// reflectance and leaf size per kind) and `soil` the ground's reflectance per band.
struct CrownScene {
  struct Kind {
    std::vector<double> reflectance, transmittance, trunk_reflectance;
    double leaf_size_m = 0.0;
  };

  CrownScene(std::vector<Crown> crowns, const std::vector<Kind>& kinds, std::vector<double> soil) {
    vegetation.crowns = std::move(crowns);
    scene =
        std::make_unique<Scene>(device, build_ground_mesh(plane, frame, 150.0, 1.0e9), vegetation);
    geometry.sensor_m = {0.0, 0.0, 600000.0};
    geometry.axis = {0.0, 0.0, -1.0};
    geometry.range_m = 600000.0;
    optics.soil_reflectance = std::move(soil);
    for (const Kind& kind : kinds)
      optics.foliage.push_back({kind.reflectance, kind.transmittance, kind.trunk_reflectance,
                                &angles, kind.leaf_size_m});
  }

  PlaneTerrain plane{{0.0, 0.0, 0.0, 0.0, 0.0}};
  LocalFrame frame{{0.0, 0.0, 0.0}};
  RayDevice device;
  Vegetation vegetation;
  std::unique_ptr<Scene> scene;
  ShotGeometry geometry;
  LeafAngles angles{LeafAngleDistribution::spherical, 0.0};
  SceneOptics optics;
};

}  // namespace glaswave::test_support
