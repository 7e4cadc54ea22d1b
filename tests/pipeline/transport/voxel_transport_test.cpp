// A voxel grid of uniform plant area density, wider than the beam, is the homogeneous turbid
// layer of PHYSICS.md section 3: single scattering against the closed forms of both columns
// (point leaves, and finite leaves with the hotspot), to 2 % at 40 000 rays as the layer's own
// test; orders 2 and 3 against the `layer` source itself.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <numbers>
#include <vector>

#include "pipeline/transport/shot_transport.hpp"
#include "tests/pipeline/transport/transport_test_support.hpp"

namespace glaswave {
namespace {

// L = 3 in a 10 m slab of density 0.3 as 3 m x 3 m columns of 2 m layers, 300 m across.
std::shared_ptr<VoxelField> uniform_field() {
  auto f = std::make_shared<VoxelField>();
  f->nx = f->ny = 100;
  f->nz = 5;
  f->origin_m = {-150.0, -150.0};
  f->axis_i_m = {3.0, 0.0};
  f->axis_j_m = {0.0, 3.0};
  f->z_edges_m = {0.0, 2.0, 4.0, 6.0, 8.0, 10.0};
  f->ground_m.assign(100 * 100, 0.0);
  f->pad.assign(100 * 100 * 5, 0.3f);
  return f;
}

struct LayerScene : test_support::CrownScene {
  LayerScene(double leaf_size_m, bool voxels)
      : CrownScene({}, {{{0.45, 0.45}, {0.45, 0.45}, {0.3, 0.3}, leaf_size_m}}, {0.3, 0.3}) {
    Vegetation v;
    if (voxels)
      v.voxels = uniform_field();
    else
      v.layer = TurbidLayer{0.0, 0.0, 0.0, 10.0, 0.3, 0};
    scene = std::make_unique<Scene>(device, build_ground_mesh(plane, frame, 150.0, 1.0e9), v);
  }
};

double normalisation_J() {
  const double f_fov = 1.0 - std::exp(-0.0004 * 0.0004 / (8.0 * 0.00011 * 0.00011));
  return 32e-3 * 0.8 * 0.709 * f_fov / (std::numbers::pi * 600000.0 * 600000.0);
}

TEST(VoxelTransport, UniformGridGivesTheTurbidLayersSingleScattering) {
  const double L = 3.0, rho = 0.45, soil = 0.3;
  struct Case {
    double leaf_size_m, canopy, ground;
  };
  const Case cases[] = {
      {0.0, rho / 3.0 * (1.0 - std::exp(-L)), soil * std::exp(-L)},                    // 0.1425
      {0.05, 2.0 * rho / 3.0 * (1.0 - std::exp(-L / 2.0)), soil * std::exp(-L / 2.0)}  // hotspot
  };
  const LidarModel lidar(test_support::table2_sensor());
  TransportOptions options;
  options.rays = 40000;
  options.max_order = 1;
  for (const Case& c : cases) {
    const LayerScene s(c.leaf_size_m, true);
    const ShotWaveforms w = simulate_shot(*s.scene, lidar, s.geometry, s.optics, options, 1);
    const double canopy = w.canopy_energy_J[0] / normalisation_J();
    const double ground = w.ground_energy_J[0] / normalisation_J();
    EXPECT_NEAR(canopy / c.canopy, 1.0, 0.02) << "leaf size " << c.leaf_size_m << ": " << canopy;
    EXPECT_NEAR(ground / c.ground, 1.0, 0.02) << "leaf size " << c.leaf_size_m << ": " << ground;
    EXPECT_NEAR(s.scene->top_m(), 10.0, 1e-9);
  }
}

TEST(VoxelTransport, HigherOrdersEqualTheLayers) {
  const LidarModel lidar(test_support::table2_sensor());
  TransportOptions options;
  options.rays = 20000;
  options.max_order = 3;
  options.per_order = true;
  const LayerScene voxels(0.05, true), layer(0.05, false);
  const ShotWaveforms a =
      simulate_shot(*voxels.scene, lidar, voxels.geometry, voxels.optics, options, 2);
  const ShotWaveforms b =
      simulate_shot(*layer.scene, lidar, layer.geometry, layer.optics, options, 3);
  for (int order = 1; order < 3; ++order) {
    double ea = 0.0, eb = 0.0;
    for (double p : a.order_W[1][order]) ea += p;
    for (double p : b.order_W[1][order]) eb += p;
    EXPECT_NEAR(ea / eb, 1.0, 0.04) << "order " << order + 1;
  }
}

}  // namespace
}  // namespace glaswave
