// The lidar shot's ray tracer (PathTracer: one ray's paths, the steps pbrt's integrators take)
// and the tally of normalised returns it scores into, shared by lidar_path_tracer.cpp (the
// steps) and shot_transport.cpp (a shot's rays in groups over threads, the tally read out as
// its waveforms). The transport's own files only; other code calls shot_transport.hpp.
#pragma once

#include <algorithm>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/random.hpp"
#include "pipeline/transport/atmosphere.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "pipeline/transport/sobol_points.hpp"

namespace glaswave::lidar_paths {

// Normalised returns of a group of rays, per band and tally bin. A return's weight is its
// part of E_t T A_T f_fov / (pi R^2) per ray: a Lambertian surface of reflectance rho seen
// square-on at the reference range weighs rho. `squares` sums each ray's score in a bin
// squared (the ray's scores in that bin added first), for the Monte Carlo variance.
struct Tally {
  Tally(std::size_t bands, int size, int orders)
      : size(size),
        orders(orders),
        total(bands * size, 0.0),
        canopy(bands * size, 0.0),
        ground(bands * size, 0.0),
        squares(bands * size, 0.0),
        order(bands * orders * size, 0.0),
        atmosphere(bands * atmosphere_sums, 0.0),
        marked(size, 0) {}

  // Only the bins `other` scored into are added: elsewhere it holds zeros, and adding a zero
  // changes no bit. A group of a few rays scores into a few bins, however far apart (a slope's
  // returns spread over hundreds).
  Tally& operator+=(const Tally& other) {
    ray_queries += other.ray_queries;
    // Where it scored into most bins (many rays), every bin: one pass over contiguous memory.
    const bool most = other.scored_most();
    auto add = [&](std::vector<double>& sum, const std::vector<double>& part) {
      if (most) {
        for (std::size_t i = 0; i < sum.size(); ++i) sum[i] += part[i];
        return;
      }
      for (std::size_t row = 0; row * size < sum.size(); ++row)
        for (int bin : other.bins) sum[row * size + bin] += part[row * size + bin];
    };
    add(total, other.total);
    add(canopy, other.canopy);
    add(ground, other.ground);
    add(squares, other.squares);
    add(order, other.order);
    for (std::size_t i = 0; i < atmosphere.size(); ++i) atmosphere[i] += other.atmosphere[i];
    for (int bin : other.bins) mark(bin);
    return *this;
  }

  // Back to zeros, as constructed.
  void clear() {
    const bool most = scored_most();
    for (std::vector<double>* part : {&total, &canopy, &ground, &squares, &order}) {
      if (most) {
        std::fill(part->begin(), part->end(), 0.0);
        continue;
      }
      for (std::size_t row = 0; row * size < part->size(); ++row)
        for (int bin : bins) (*part)[row * size + bin] = 0.0;
    }
    std::fill(atmosphere.begin(), atmosphere.end(), 0.0);
    for (int bin : bins) marked[bin] = 0;
    bins.clear();
    ray_queries = 0;
  }

  // Scored into more than half of the bins: faster over all of them than by the list.
  bool scored_most() const { return 2 * bins.size() > size; }

  void mark(int bin) {
    if (marked[bin]) return;
    marked[bin] = 1;
    bins.push_back(bin);
  }

  std::size_t size;
  int orders;
  std::vector<double> total, canopy, ground, squares, order;
  // With an atmosphere, per band: the returns' weight in the window, its part whose light the
  // layers scattered, and the weight times the extra path the scattering made (m).
  static constexpr std::size_t atmosphere_sums = 3;
  std::vector<double> atmosphere;
  std::int64_t ray_queries = 0;
  std::vector<char> marked;  // per bin: scored into
  std::vector<int> bins;     // those bins, in the order first scored
};

// One path of a ray, between two interactions.
struct Path {
  bool beam_path = true;  // the first path: drawn by the beam, scores the single scattering
  double density = 0.0;   // of the second path's first direction (the mixture), per sr
  Vec3 position{}, direction{};
  double path_m = 0.0;  // from the detector to `position` along the path
  double min_distance_m = 0.0;
  bool canopy_return = false;  // whether the first element met is foliage or a trunk
  int order = 0;               // of the last element met
  bool lost = false;           // scattered out of the atmosphere before reaching the scene
  // Whether the layers turned the path on its way to the scene, and how much longer that made it
  // than the straight line from the sensor to where it reached the scene.
  bool atmosphere_scattered = false;
  double atmosphere_extra_m = 0.0;
};

// The element a path meets.
struct Vertex {
  RayElement element = RayElement::none;
  const Foliage* material = nullptr;  // of a leaf or a trunk
  int foliage = -1, crown = -1;
  double segment_m = 0.0;  // from the path's position
  Vec3 point{}, normal{};  // a leaf's normal is drawn for the arriving direction
};

// The steps of one ray's paths, in the way pbrt splits an integrator: sample the beam, find
// the next element (a free path through the foliage, or the next surface), score the direct
// return toward the detector, bin it, scatter. One tracer serves a group of rays in turn and
// keeps their scratch space; the ray's random numbers are drawn in the order the steps run.
class PathTracer {
 public:
  PathTracer(const Scene& scene, const LidarModel& lidar, const ShotGeometry& geometry,
             const SceneOptics& optics, const TransportOptions& options, std::int64_t shot_number,
             const RayObserver* observer);
  void trace_ray(std::int64_t ray, Tally& tally);

 private:
  void trace_path(bool beam_path, RayRandom& random, Tally& tally);
  Path sample_beam(bool beam_path, RayRandom& random);
  std::optional<Vertex> find_vertex(const Path& path, RayRandom& random, Tally& tally);
  void score_direct(const Path& path, const Vertex& vertex, int order, Tally& tally,
                    RayRandom& random);
  void score_through_atmosphere(const Path& path, const Vertex& vertex, int order,
                                double transmission, double beam_ratio, double laser_m,
                                const Vec3& up_to_laser, Tally& tally, RayRandom& random);
  double laser_transmission(const Path& path, const Vertex& vertex, int order,
                            const Vec3& up_to_laser, Tally& tally);
  void bin(const Path& path, int order, int bin, Tally& tally);
  void tally_squares(Tally& tally);
  bool scatter(Path& path, const Vertex& vertex, RayRandom& random);
  bool survives_roulette(const Path& path, RayRandom& random);
  void project(const Vec3& direction);
  double quasi_random(SobolPoints::Use use, RayRandom& random) const {
    return points_.coordinate(static_cast<std::uint64_t>(ray_), use, random);
  }
  double beam_density(const Vec3& direction) const;
  RayEvent event_at(RayEventKind kind, const Path& path, const Vec3& position,
                    const Vertex* vertex) const;
  void emit(RayEventKind kind, const Path& path, const Vec3& position, const Vertex* vertex) const;

  const Scene& scene_;
  const LidarModel& lidar_;
  const ShotGeometry& geometry_;
  const SceneOptics& optics_;
  const TransportOptions& options_;
  const std::int64_t shot_number_;
  const RayObserver* observer_;  // null: no events are built
  const BeamSampler beam_;
  const std::size_t bands_;
  const double two_sigma_sq_;
  const double uniform_density_;  // over the field of view, per sr
  // Rays start just above the scene, so Embree's float coordinates stay small.
  const double start_height_m_;
  const bool foliage_;
  bool any_point_leaves_ = false;
  std::vector<VolumeSpan> spans_;
  std::vector<double> throughput_, response_;
  // The layers above the scene, when the shot has an atmosphere, and a band's scratch.
  std::optional<AtmosphereModel> atmosphere_;
  std::vector<double> factor_;
  std::vector<double> projection_;  // G of each foliage for one direction
  const SobolPoints points_;        // the shot's quasi-random points
  std::int64_t ray_ = 0;            // the ray being traced
  // The current ray's scores by tally bin ([entry][band] weights), for the squares.
  std::vector<int> ray_bins_;
  std::vector<double> ray_scores_;
};

}  // namespace glaswave::lidar_paths
