// Google Benchmark micro-benchmarks of the transport's and the products' kernels, each through
// the public function the shot calls: the random stream, crown crossings, free-path sampling
// through a crown scene, scattering at a leaf (its normal, the next direction, the response),
// binning, the pulse convolution, the Gaussian decomposition, and a photon-counting shot. Run
// build/tests/benchmarks/kernel_benchmarks (Google Benchmark's flags apply).
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include "canopy/crown.hpp"
#include "canopy/leaf_angles.hpp"
#include "core/random.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/products/gaussian_decomposition.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/photon_counting.hpp"
#include "pipeline/transport/scattering.hpp"

namespace {

glaswave::LidarModel north2010() {
  const nlohmann::json document = {
      {"sensor", {{"preset", "north2010"}}},
      {"terrain", {{"plane", {{"origin_lat_deg", 0.0}, {"origin_lon_deg", 0.0}}}}},
      {"track", {{"type", "points"}, {"points", {{{"lat_deg", 0.0}, {"lon_deg", 0.0}}}}}},
  };
  return glaswave::LidarModel(glaswave::parse_config(document).sensor);
}

void random_stream(benchmark::State& state) {
  std::int64_t ray = 0;
  for (auto _ : state) {
    glaswave::RayRandom random(1, 7, ray++);
    benchmark::DoNotOptimize(random.uniform() + random.uniform());
  }
}
BENCHMARK(random_stream);

void crown_interval(benchmark::State& state) {
  glaswave::Crown crown;
  crown.base_m = {1.0, -2.0, 4.0};
  crown.radius_m = 3.0;
  crown.half_height_m = 5.0;
  glaswave::RayRandom random(1, 0, 0);
  for (auto _ : state) {
    const glaswave::Vec3 origin{8.0 * random.uniform() - 4.0, 8.0 * random.uniform() - 4.0, 40.0};
    benchmark::DoNotOptimize(glaswave::crown_interval(crown, origin, {0.01, -0.02, -1.0}));
  }
}
BENCHMARK(crown_interval);

// A 200 m square of ground under 400 ellipsoidal crowns (about the base case's density): what a
// downward ray meets (its spans through the crowns, a free path sampled along them, the ground
// searched up to the free path's end), as a path's every segment does.
void free_path_sampling(benchmark::State& state) {
  const glaswave::RayDevice device;
  glaswave::GroundMesh ground;
  ground.vertices_m = {-100, -100, 0, 100, -100, 0, 100, 100, 0, -100, 100, 0};
  ground.triangles = {0, 1, 2, 0, 2, 3};
  glaswave::Vegetation vegetation;
  std::mt19937 engine(3);
  std::uniform_real_distribution<double> across(-100.0, 100.0);
  for (int k = 0; k < 400; ++k) {
    glaswave::Crown crown;
    crown.base_m = {across(engine), across(engine), 8.0};
    crown.radius_m = 2.5;
    crown.half_height_m = 3.5;
    crown.area_density_m2_m3 = 1.0;
    vegetation.crowns.push_back(crown);
  }
  const glaswave::Scene scene(device, ground, vegetation);
  const std::vector<double> projection{0.5};  // G of a spherical distribution
  std::vector<glaswave::VolumeSpan> spans;
  glaswave::RayRandom random(1, 0, 0);
  auto uniform = [&random] { return random.uniform(); };
  double depth_m = 0.0;
  for (auto _ : state) {
    const glaswave::Vec3 origin{60.0 * random.uniform() - 30.0, 60.0 * random.uniform() - 30.0,
                                30.0};
    const glaswave::ElementMet met =
        glaswave::element_met(scene, origin, {0.0, 0.0, -1.0}, 40.0, 0.0,
                              -std::log1p(-random.uniform()), spans, projection, uniform);
    depth_m += met.leaf ? met.leaf->distance_m : met.surface.distance_m;
  }
  benchmark::DoNotOptimize(depth_m);
}
BENCHMARK(free_path_sampling);

// Scattering at a leaf: the normal a ray meets (spherical distribution), the next direction
// drawn by the leaf's bi-Lambertian scattering, and the response toward the detector.
void leaf_scattering(benchmark::State& state) {
  const glaswave::LeafAngles angles(glaswave::LeafAngleDistribution::spherical, 57.3);
  glaswave::Foliage foliage;
  foliage.reflectance = {0.08, 0.45};
  foliage.transmittance = {0.05, 0.45};
  foliage.leaf_angles = &angles;
  const glaswave::SceneOptics optics{{0.12, 0.25}, {foliage}};
  glaswave::RayRandom random(1, 0, 0);
  auto uniform = [&random] { return random.uniform(); };
  const glaswave::Vec3 down = glaswave::normalized({0.1, 0.2, -1.0});
  const glaswave::Vec3 up{-down[0], -down[1], -down[2]};
  double response = 0.0;
  for (auto _ : state) {
    const glaswave::Vec3 normal = angles.sample_normal(down, uniform);
    std::array<double, 2> throughput{1.0, 1.0};
    glaswave::Vec3 direction = down;
    glaswave::sample_scattering(glaswave::RayElement::leaf, &optics.foliage[0], optics, normal,
                                random, direction, throughput);
    response += glaswave::element_response(glaswave::RayElement::leaf, &optics.foliage[0], optics,
                                           1, normal, down, up) +
                direction[2];
  }
  benchmark::DoNotOptimize(response);
}
BENCHMARK(leaf_scattering);

// Binning a scored return: its time to a tally bin, its weight added there.
void binning(benchmark::State& state) {
  const glaswave::LidarModel lidar = north2010();
  std::vector<double> tally(2 * lidar.tally_size(), 0.0);
  glaswave::RayRandom random(1, 0, 0);
  for (auto _ : state) {
    const int bin = lidar.tally_index(200.0 * random.uniform() - 100.0);
    if (bin >= 0) {
      tally[bin] += 0.3;
      tally[lidar.tally_size() + bin] += 0.5;
    }
  }
  benchmark::DoNotOptimize(tally.data());
}
BENCHMARK(binning);

// A band's energy tally into power: the convolution with the pulse.
void pulse_convolution(benchmark::State& state) {
  const glaswave::LidarModel lidar = north2010();
  std::vector<double> tally(lidar.tally_size(), 0.0);
  for (std::size_t i = 0; i < tally.size(); ++i) tally[i] = (i % 7 == 0) ? 1e-15 : 0.0;
  for (auto _ : state) benchmark::DoNotOptimize(lidar.power_W(tally));
}
BENCHMARK(pulse_convolution);

// The decomposition's settings in both of its cases: a 1.5-bin narrowest Gaussian, smoothing over
// 3 bins, components below 0.05 of the unit peak dropped.
glaswave::DecompositionSettings decomposition_settings() {
  glaswave::DecompositionSettings settings;
  settings.min_sigma_bins = 1.5;
  settings.smooth_sigma_bins = 3.0;
  settings.significance_level = 0.05;
  return settings;
}

// Three Gaussians with noise over 544 bins (a canopy's two layers and its ground), decomposed.
void decomposition(benchmark::State& state) {
  std::vector<double> waveform(544, 0.0);
  std::mt19937 engine(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (std::size_t i = 0; i < waveform.size(); ++i) {
    const double x = static_cast<double>(i);
    waveform[i] = 1.0 * std::exp(-0.5 * std::pow((x - 200.0) / 4.0, 2)) +
                  0.6 * std::exp(-0.5 * std::pow((x - 230.0) / 6.0, 2)) +
                  2.0 * std::exp(-0.5 * std::pow((x - 300.0) / 3.0, 2)) + noise(engine);
  }
  const glaswave::DecompositionSettings settings = decomposition_settings();
  for (auto _ : state)
    benchmark::DoNotOptimize(glaswave::decompose_waveform(waveform, 180, 320, settings));
}
BENCHMARK(decomposition);

// A bare 20 degree slope's return: one Gaussian some 80 bins wide over a window of 490 bins,
// with Monte Carlo noise of 1 %, its variance known (as the simulation's Sum w^2 gives it).
void decomposition_broad(benchmark::State& state) {
  std::vector<double> waveform(544, 0.0), variance(544, 0.0);
  std::mt19937 engine(5);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (std::size_t i = 0; i < waveform.size(); ++i) {
    const double x = static_cast<double>(i);
    const double truth = std::exp(-0.5 * std::pow((x - 270.0) / 80.0, 2));
    waveform[i] = truth * (1.0 + noise(engine));
    variance[i] = std::pow(0.01 * truth, 2);
  }
  glaswave::DecompositionSettings settings = decomposition_settings();
  settings.error_variance = variance;
  for (auto _ : state)
    benchmark::DoNotOptimize(glaswave::decompose_waveform(waveform, 25, 515, settings));
}
BENCHMARK(decomposition_broad);

}  // namespace

// One ATLAS strong-beam shot's photons: 2500 bins of 0.2 ns, a ground return of 7 photons (the
// 1.5 ns FWHM pulse) under a canopy return of 3 spread over 15 m, a 4.4 MHz background, then
// the dead time of 16 channels. One beam in real time is 10 000 of these a second.
void photon_shot(benchmark::State& state) {
  const std::size_t bins = 2500;
  std::vector<double> ground(bins), canopy(bins);
  for (std::size_t k = 0; k < bins; ++k) {
    const double t = 0.2 * static_cast<double>(k);
    ground[k] = 7.0 * 0.2 / (0.637 * 2.5066) * std::exp(-0.5 * std::pow((t - 333.0) / 0.637, 2));
    canopy[k] = (t > 233.0 && t < 333.0) ? 3.0 / 500.0 : 0.0;
  }
  const glaswave::PhotonSource sources[] = {{ground, glaswave::PhotonTruth::ground, 1},
                                            {canopy, glaswave::PhotonTruth::canopy, 1}};
  std::int64_t shot = 0;
  for (auto _ : state) {
    const auto events = glaswave::draw_photons({1, shot++, 0, 0.2, bins, 4.4e6, 16}, sources);
    benchmark::DoNotOptimize(glaswave::apply_dead_time(events, 3.2).size());
  }
}
BENCHMARK(photon_shot);

BENCHMARK_MAIN();
