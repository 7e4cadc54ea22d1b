// Monte Carlo transport of one shot.
#include "pipeline/transport/shot_transport.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>

#include "core/random.hpp"
#include "pipeline/transport/atmosphere.hpp"
#include "pipeline/transport/sobol_points.hpp"

namespace glaswave {
namespace {

// Rays are tallied in a fixed number of contiguous groups (transport_ray_groups), summed in
// order: the result is the same bits for any thread count, and memory does not grow with the rays.
constexpr std::int64_t ray_groups = transport_ray_groups;
// Shots of fewer rays are traced on the calling thread: the engine runs shots in parallel, and
// splitting a short shot costs more than it saves.
constexpr std::int64_t parallel_rays = 2048;

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

// A thread's two tallies for its shots of few rays, kept between its shots and handed back zero
// (clear() zeroes only where the shot scored): a photon-counting pass's 10,000 shots a second
// would otherwise allocate and zero some 300 kB each. A shot of another shape, or one begun
// while the thread's pair is out, gets its own.
class ThreadTallies {
 public:
  ThreadTallies(std::size_t bands, int size, int orders) {
    thread_local std::unique_ptr<Pair> kept;
    thread_local bool out = false;
    if (out) {
      own_ = std::make_unique<Pair>(bands, size, orders);
      pair_ = own_.get();
      return;
    }
    if (!kept || kept->total.total.size() != bands * static_cast<std::size_t>(size) ||
        kept->total.size != static_cast<std::size_t>(size) || kept->total.orders != orders)
      kept = std::make_unique<Pair>(bands, size, orders);
    pair_ = kept.get();
    out_ = &out;
    out = true;
  }
  ~ThreadTallies() {
    pair_->total.clear();
    pair_->group.clear();
    if (out_) *out_ = false;
  }
  ThreadTallies(const ThreadTallies&) = delete;
  ThreadTallies& operator=(const ThreadTallies&) = delete;

  Tally& total() const { return pair_->total; }
  Tally& group() const { return pair_->group; }

 private:
  struct Pair {
    Pair(std::size_t bands, int size, int orders)
        : total(bands, size, orders), group(bands, size, orders) {}
    Tally total, group;
  };
  std::unique_ptr<Pair> own_;
  Pair* pair_ = nullptr;
  bool* out_ = nullptr;
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

PathTracer::PathTracer(const Scene& scene, const LidarModel& lidar, const ShotGeometry& geometry,
                       const SceneOptics& optics, const TransportOptions& options,
                       std::int64_t shot_number, const RayObserver* observer)
    : scene_(scene),
      lidar_(lidar),
      geometry_(geometry),
      optics_(optics),
      options_(options),
      shot_number_(shot_number),
      observer_(observer),
      beam_(lidar, geometry.axis),
      bands_(lidar.band_count()),
      two_sigma_sq_(2.0 * lidar.beam_sigma_rad() * lidar.beam_sigma_rad()),
      uniform_density_(1.0 / lidar.fov_solid_angle_sr()),
      start_height_m_(scene.top_m() + 1.0),
      foliage_(scene.has_volumes()),
      throughput_(bands_),
      response_(bands_),
      factor_(bands_),
      projection_(optics.foliage.size()),
      points_(options.seed, static_cast<std::uint64_t>(shot_number)) {
  for (const Foliage& f : optics.foliage)
    any_point_leaves_ = any_point_leaves_ || f.leaf_size_m == 0.0;
  if (options.atmosphere)
    atmosphere_.emplace(*options.atmosphere, bands_, geometry.ground_z_m, geometry.ground_height_m,
                        start_height_m_);
}

// Each ray traces two paths. The first, drawn by the beam's irradiance, scores the single
// scattering: the laser lights its first interaction down the very path sampled, so every ray
// carries the same weight and a bare surface's energy comes out to round-off. The second
// scores orders 2 and up: multiply scattered light reaches the detector from anywhere in its
// view, so it is drawn half by the beam and half uniformly over the field of view. Drawn by
// the beam alone, a ray in the beam's tail would weigh exp(theta^2 / 2 sigma^2), without
// bound (e^23 at the edge of GLAS's view); the mixture bounds the weight by 2 Omega_fov.
void PathTracer::trace_ray(std::int64_t ray, Tally& tally) {
  RayRandom random(options_.seed, shot_number_, ray);
  ray_ = ray;
  trace_path(true, random, tally);
  if (options_.max_order >= 2) trace_path(false, random, tally);
  tally_squares(tally);
}

// The ray's score in each bin it reached, squared, into the tally; the ray's list emptied.
void PathTracer::tally_squares(Tally& tally) {
  for (std::size_t entry = 0; entry < ray_bins_.size(); ++entry)
    for (std::size_t band = 0; band < bands_; ++band) {
      const double score = ray_scores_[entry * bands_ + band];
      tally.squares[band * tally.size + ray_bins_[entry]] += score * score;
    }
  ray_bins_.clear();
  ray_scores_.clear();
}

void PathTracer::trace_path(bool beam_path, RayRandom& random, Tally& tally) {
  Path path = sample_beam(beam_path, random);
  if (path.lost) {
    emit(RayEventKind::leave, path, path.position, nullptr);
    return;
  }
  emit(RayEventKind::enter, path, path.position, nullptr);
  for (int order = 1; order <= options_.max_order; ++order) {
    const std::optional<Vertex> vertex = find_vertex(path, random, tally);
    if (!vertex) {
      emit(RayEventKind::leave, path, path.position, nullptr);
      return;
    }
    path.path_m += vertex->segment_m;
    path.order = order;
    if (order == 1) path.canopy_return = vertex->element != RayElement::ground;
    emit(RayEventKind::interaction, path, vertex->point, &*vertex);
    // The second path's first interaction is the beam path's to score.
    if (beam_path || order > 1) score_direct(path, *vertex, order, tally, random);
    if (beam_path || order == options_.max_order) {
      emit(RayEventKind::end, path, vertex->point, &*vertex);
      return;
    }
    if (!scatter(path, *vertex, random) || !survives_roulette(path, random)) {
      emit(RayEventKind::absorbed, path, vertex->point, &*vertex);
      return;
    }
  }
}

// The path's first direction, and where it crosses the top of the scene.
Path PathTracer::sample_beam(bool beam_path, RayRandom& random) {
  const bool by_beam = beam_path || random.uniform() < 0.5;
  // Where in the footprint and the field of view: the ray's own draws or its quasi-random point.
  double u1 = 0.0, u2 = 0.0;
  if (options_.quasi_random) {
    u1 = quasi_random(beam_path ? SobolPoints::beam_u1 : SobolPoints::second_u1, random);
    u2 = quasi_random(beam_path ? SobolPoints::beam_u2 : SobolPoints::second_u2, random);
  } else {
    u1 = random.uniform();
    u2 = random.uniform();
  }
  const Vec3 first_direction = by_beam ? beam_.direction(u1, u2) : beam_.uniform_direction(u1, u2);
  Path path;
  path.beam_path = beam_path;
  // The beam path scores only its first interaction and never needs the density.
  path.density = beam_path ? 0.0 : 0.5 * beam_density(first_direction) + 0.5 * uniform_density_;
  std::fill(throughput_.begin(), throughput_.end(), 1.0);
  if (atmosphere_) {
    // Down through the layers: the beam path is the laser's light, scattered on its way to the
    // scene; the second path the detector's view, scattered on the way back (reciprocity).
    path.position = geometry_.sensor_m;
    path.direction = first_direction;
    int scatterings = 0;
    path.lost = !atmosphere_->cross(
        path.position, path.direction, path.path_m, throughput_,
        [&random] { return random.uniform(); }, &scatterings);
    path.atmosphere_scattered = scatterings > 0;
    if (path.atmosphere_scattered)
      path.atmosphere_extra_m = path.path_m - norm(path.position - geometry_.sensor_m);
    return path;
  }
  const double start_m = (geometry_.sensor_m[2] - start_height_m_) / -first_direction[2];
  path.position = geometry_.sensor_m + start_m * first_direction;
  path.direction = first_direction;
  path.path_m = start_m;
  return path;
}

// The next element along the path: a leaf by free-path sampling through the foliage, but never
// beyond the nearest surface; empty when the path leaves the scene.
std::optional<Vertex> PathTracer::find_vertex(const Path& path, RayRandom& random, Tally& tally) {
  auto uniform = [&random] { return random.uniform(); };
  std::optional<double> target;
  if (foliage_) {
    project(path.direction);
    // The beam path's one free path: the third coordinate of the ray's point, if quasi-random.
    const double u = options_.quasi_random && path.beam_path
                         ? quasi_random(SobolPoints::beam_free_path, random)
                         : random.uniform();
    target = -std::log1p(-u);
  }
  const ElementMet met = element_met(scene_, path.position, path.direction, far_m,
                                     path.min_distance_m, target, spans_, projection_, uniform);
  tally.ray_queries += met.ray_queries;
  const SurfaceHit& hit = met.surface;
  const std::optional<Interaction>& leaf = met.leaf;
  if (!leaf && hit.kind == SurfaceKind::none) return std::nullopt;
  Vertex vertex;
  if (leaf) {
    vertex.element = RayElement::leaf;
    vertex.foliage = leaf->material;
    vertex.crown = leaf->crown;
    vertex.segment_m = leaf->distance_m;
  } else {
    vertex.element = surface_element(hit.kind);
    vertex.foliage = vertex.element == RayElement::ground ? -1 : hit.material;
    vertex.segment_m = hit.distance_m;
  }
  if (vertex.foliage >= 0) vertex.material = &optics_.foliage[vertex.foliage];
  vertex.point = path.position + vertex.segment_m * path.direction;
  vertex.normal =
      leaf ? vertex.material->leaf_angles->sample_normal(path.direction, uniform) : hit.normal;
  return vertex;
}

// Direct laser light at the element, scored toward the detector. The laser sits with the
// detector: at the first interaction its light comes down the very path sampled, and with
// finite leaves it finds the same gaps (the hotspot, PHYSICS.md section 3).
void PathTracer::score_direct(const Path& path, const Vertex& vertex, int order, Tally& tally,
                              RayRandom& random) {
  const Vec3 to_laser = geometry_.sensor_m - vertex.point;
  const double laser_m = norm(to_laser);
  const Vec3 up_to_laser = (1.0 / laser_m) * to_laser;
  const Vec3 laser_light = -1.0 * up_to_laser;  // travel direction of the laser's light
  const double transmission = laser_transmission(path, vertex, order, up_to_laser, tally);
  if (!(transmission > 0.0)) {
    emit(RayEventKind::blocked, path, vertex.point, &vertex);
    return;
  }
  // Beyond the first order, the laser's light at the point over the density of the detector
  // ray that found it.
  const double beam_ratio = order > 1 ? beam_density(laser_light) / path.density : 1.0;
  if (atmosphere_) {
    score_through_atmosphere(path, vertex, order, transmission, beam_ratio, laser_m, up_to_laser,
                             tally, random);
    return;
  }
  const double range_m = geometry_.range_m;
  const double scale = transmission * beam_ratio * (range_m / laser_m) * (range_m / laser_m);
  const double time_ns = (laser_m + path.path_m - 2.0 * range_m) / speed_of_light_m_s * 1e9;
  const int tally_bin = lidar_.tally_index(time_ns);
  const Vec3 toward_detector = -1.0 * path.direction;
  for (std::size_t band = 0; band < bands_; ++band)
    response_[band] = throughput_[band] *
                      element_response(vertex.element, vertex.material, optics_, band,
                                       vertex.normal, laser_light, toward_detector) *
                      scale;
  if (tally_bin >= 0) bin(path, order, tally_bin, tally);
  if (observer_) {
    RayEvent event = event_at(RayEventKind::score, path, vertex.point, &vertex);
    event.weight = response_;
    event.path_m = laser_m + path.path_m;
    event.time_ns = time_ns;
    event.tally_bin = tally_bin;
    event.bin = tally_bin - lidar_.margin_bins();
    (*observer_)(event);
  }
}

// The direct return with the atmosphere's layers above the scene. Beyond the first order the path
// is the detector's view (its scatterings in the layers drawn already) and the laser lights the
// element straight through them. At the first order the path is the laser's light, which may have
// scattered in the layers: the element sends it back straight, seen when it lies in the field of
// view, and once scattered in the layers into the field of view (a point drawn on a detector ray
// uniform over the field of view, at a height drawn by the layers' scattering). The scene is
// crossed on the way back as by the straight return (the scattering angles are small).
void PathTracer::score_through_atmosphere(const Path& path, const Vertex& vertex, int order,
                                          double transmission, double beam_ratio, double laser_m,
                                          const Vec3& up_to_laser, Tally& tally,
                                          RayRandom& random) {
  const AtmosphereModel& atmosphere = *atmosphere_;
  const double range_m = geometry_.range_m;
  const Vec3 laser_light = -1.0 * up_to_laser;
  // A return scored, its light scattered by the layers or not, `extra_m` longer for it.
  auto score = [&](double path_m, bool scattered, double extra_m) {
    const double time_ns = (path_m - 2.0 * range_m) / speed_of_light_m_s * 1e9;
    const int tally_bin = lidar_.tally_index(time_ns);
    if (tally_bin >= 0) {
      bin(path, order, tally_bin, tally);
      for (std::size_t band = 0; band < bands_; ++band) {
        double* sums = &tally.atmosphere[band * Tally::atmosphere_sums];
        sums[0] += response_[band];
        if (!scattered) continue;
        sums[1] += response_[band];
        sums[2] += response_[band] * extra_m;
      }
    }
    if (observer_) {
      RayEvent event = event_at(RayEventKind::score, path, vertex.point, &vertex);
      event.weight = response_;
      event.path_m = path_m;
      event.time_ns = time_ns;
      event.tally_bin = tally_bin;
      event.bin = tally_bin - lidar_.margin_bins();
      (*observer_)(event);
    }
  };
  const double direct_scale = transmission * beam_ratio * (range_m / laser_m) * (range_m / laser_m);
  if (order > 1) {
    const Vec3 toward_detector = -1.0 * path.direction;
    for (std::size_t band = 0; band < bands_; ++band)
      response_[band] = throughput_[band] *
                        element_response(vertex.element, vertex.material, optics_, band,
                                         vertex.normal, laser_light, toward_detector) *
                        direct_scale *
                        std::exp(-atmosphere.column_optical_depth(band) / up_to_laser[2]);
    score(laser_m + path.path_m, path.atmosphere_scattered, path.atmosphere_extra_m);
    return;
  }
  // The element's response is per unit irradiance across the light's path; the light sent
  // toward a direction other than the one it came from is that times cos(out) / cos(in).
  const Vec3& incoming = path.direction;
  const double cos_in = std::abs(dot(vertex.normal, incoming));
  if (!(cos_in > 0.0)) return;
  const Vec3 from_sensor = vertex.point - geometry_.sensor_m;
  const double off_axis_rad =
      std::atan2(norm(cross(from_sensor, geometry_.axis)), dot(from_sensor, geometry_.axis));
  if (off_axis_rad <= lidar_.max_angle_rad() * (1.0 + 1e-9) && up_to_laser[2] > 0.0) {
    const double cos_out = std::abs(dot(vertex.normal, up_to_laser));
    for (std::size_t band = 0; band < bands_; ++band)
      response_[band] = throughput_[band] *
                        element_response(vertex.element, vertex.material, optics_, band,
                                         vertex.normal, incoming, up_to_laser) *
                        (cos_out / cos_in) * direct_scale *
                        std::exp(-atmosphere.column_optical_depth(band) / up_to_laser[2]);
    score(path.path_m + laser_m, path.atmosphere_scattered, path.path_m - laser_m);
  }
  if (!atmosphere.scatters()) return;
  const double u1 = random.uniform(), u2 = random.uniform(), u3 = random.uniform();
  const Vec3 down = beam_.uniform_direction(u1, u2);
  AtmosphereModel::ScatterPoint at;
  if (!atmosphere.scatter_point(geometry_.sensor_m, down, u3, at)) return;
  const Vec3 to_point = at.point - vertex.point;
  const double rise_m = norm(to_point);
  const Vec3 up = (1.0 / rise_m) * to_point;
  if (!(up[2] > 0.0)) return;
  atmosphere.scattering_factor(at, down, dot(up, -1.0 * down), factor_);
  const double cos_out = std::abs(dot(vertex.normal, up));
  const double scale = transmission * (cos_out / cos_in) * range_m * range_m *
                       lidar_.fov_solid_angle_sr() / (rise_m * rise_m);
  const double floor_z = atmosphere.floor_z_m();
  for (std::size_t band = 0; band < bands_; ++band)
    response_[band] =
        throughput_[band] *
        element_response(vertex.element, vertex.material, optics_, band, vertex.normal, incoming,
                         up) *
        scale * factor_[band] *
        std::exp(-atmosphere.optical_depth(band, floor_z, at.z_m) / up[2] -
                 atmosphere.optical_depth(band, at.z_m, std::numeric_limits<double>::infinity()) /
                     -down[2]);
  const double scattered_path_m = path.path_m + rise_m + norm(geometry_.sensor_m - at.point);
  score(scattered_path_m, true, scattered_path_m - 2.0 * laser_m);
}

// Part of the laser's light that reaches the element: surfaces block it (beyond the first
// order: the first interaction is lit down the path that found it), foliage attenuates it.
double PathTracer::laser_transmission(const Path& path, const Vertex& vertex, int order,
                                      const Vec3& up_to_laser, Tally& tally) {
  const double exit_m = (start_height_m_ - vertex.point[2]) / up_to_laser[2];
  double transmission = 1.0;
  if (order > 1) {
    if (scene_.occluded(vertex.point, up_to_laser, exit_m, surface_offset_m)) transmission = 0.0;
    ++tally.ray_queries;
  }
  // At the first interaction with finite leaves only, the way out needs no second look: the
  // light returns through the very gaps it came down.
  if (!foliage_ || !(transmission > 0.0) || (order == 1 && !any_point_leaves_)) return transmission;
  scene_.volume_spans(vertex.point, up_to_laser, exit_m, spans_);
  ++tally.ray_queries;
  // The connection runs beside the segment just sampled (traced back from the point); at the
  // first order all the way, at no angle.
  const double separation_rad =
      order == 1 ? 0.0 : std::acos(std::clamp(dot(up_to_laser, -1.0 * path.direction), -1.0, 1.0));
  const double shared_m = order == 1 ? std::numeric_limits<double>::infinity() : vertex.segment_m;
  project(up_to_laser);
  return transmission * std::exp(-connection_depth(spans_, projection_, optics_.foliage, shared_m,
                                                   separation_rad));
}

// The scored return into its time bin: the total, the canopy or ground part (by the first
// element the path met), and its scattering order when orders are kept apart.
void PathTracer::bin(const Path& path, int order, int bin, Tally& tally) {
  tally.mark(bin);
  // A ray scores a few times at most, mostly into later bins: the list is short.
  std::size_t entry = ray_bins_.size();
  while (entry > 0 && ray_bins_[entry - 1] != bin) --entry;
  if (entry == 0) {
    ray_bins_.push_back(bin);
    ray_scores_.resize(ray_scores_.size() + bands_, 0.0);
    entry = ray_bins_.size();
  }
  for (std::size_t band = 0; band < bands_; ++band)
    ray_scores_[(entry - 1) * bands_ + band] += response_[band];
  for (std::size_t band = 0; band < bands_; ++band) {
    const std::size_t at = band * tally.size + bin;
    tally.total[at] += response_[band];
    (path.canopy_return ? tally.canopy : tally.ground)[at] += response_[band];
    if (order <= tally.orders)
      tally.order[(band * tally.orders + order - 1) * tally.size + bin] += response_[band];
  }
}

// The diffuse light: where the light scattered here toward the detector came from. The next
// direction is drawn by the element's scattering, the throughput carrying the rest; false when
// the element scatters nothing.
bool PathTracer::scatter(Path& path, const Vertex& vertex, RayRandom& random) {
  if (!sample_scattering(vertex.element, vertex.material, optics_, vertex.normal, random,
                         path.direction, throughput_))
    return false;
  // A leaf is no surface; a path leaving a surface starts off it.
  path.min_distance_m = vertex.element == RayElement::leaf ? 0.0 : surface_offset_m;
  path.position = vertex.point;
  emit(RayEventKind::scatter, path, path.position, &vertex);
  return true;
}

// Russian roulette on faint paths keeps the estimate unbiased and the work bounded.
bool PathTracer::survives_roulette(const Path& path, RayRandom& random) {
  const double strongest = *std::max_element(throughput_.begin(), throughput_.end());
  if (strongest <= 0.0) return false;
  if (strongest < 0.05) {
    if (random.uniform() >= 0.5) return false;
    for (double& weight : throughput_) weight *= 2.0;
    emit(RayEventKind::roulette, path, path.position, nullptr);
  }
  return true;
}

void PathTracer::project(const Vec3& direction) {
  project_foliage(optics_, direction[2], projection_);
}

// The beam's irradiance in a direction, as a density over the field of view (per sr): for a
// Gaussian beam exp(-theta^2 / 2 sigma^2) / (2 pi sigma^2 f_fov). The beam path's rays are drawn
// by it.
double PathTracer::beam_density(const Vec3& direction) const {
  const double angle_from_axis =
      std::atan2(norm(cross(direction, geometry_.axis)), dot(direction, geometry_.axis));
  if (lidar_.uniform_beam()) return lidar_.beam_density_sr(angle_from_axis);
  return std::exp(-std::pow(angle_from_axis, 2) / two_sigma_sq_) /
         (std::numbers::pi * two_sigma_sq_ * lidar_.fov_fraction());
}

// An event at `position` that carries the path's throughput.
RayEvent PathTracer::event_at(RayEventKind kind, const Path& path, const Vec3& position,
                              const Vertex* vertex) const {
  RayEvent event;
  event.kind = kind;
  event.single_scattering_path = path.beam_path;
  event.order = path.order;
  event.position_m = position;
  event.direction = path.direction;
  if (vertex) {
    event.element = vertex->element;
    event.foliage = vertex->foliage;
    event.crown = vertex->crown;
  }
  event.weight = throughput_;
  event.path_m = path.path_m;
  return event;
}

// Tells the observer, if any: without one no event is built.
void PathTracer::emit(RayEventKind kind, const Path& path, const Vec3& position,
                      const Vertex* vertex) const {
  if (observer_) (*observer_)(event_at(kind, path, position, vertex));
}

// Row `row` of a tally's `size`-bin rows at the bins `bins`, scaled.
std::vector<double> scored_row(const std::vector<double>& flat, std::size_t size, std::size_t row,
                               const std::vector<std::uint32_t>& bins, double scale) {
  std::vector<double> values;
  values.reserve(bins.size());
  for (const std::uint32_t bin : bins) values.push_back(flat[row * size + bin] * scale);
  return values;
}

// The shot's returns from its tally of normalised returns: each band's scale (section 1 of
// PHYSICS.md: E_t T A_T f_fov / (pi R^2), shared by the rays), then the power through the
// pulse and its integrals, and/or the energies scored before the pulse.
ShotWaveforms shot_waveforms(const Tally& tally, const LidarModel& lidar, double range_m,
                             const TransportOptions& options) {
  // With an atmosphere its layers weigh each return; the bands' fixed transmission is not used.
  const bool layers = options.atmosphere.has_value();
  ShotWaveforms waveforms;
  waveforms.ray_queries = tally.ray_queries;
  const double bin_s = lidar.sensor().bin_ns * 1e-9;
  const auto rays = static_cast<double>(options.rays);
  // The bins scored into, in increasing order.
  std::vector<std::uint32_t> scored_bins(tally.bins.begin(), tally.bins.end());
  std::sort(scored_bins.begin(), scored_bins.end());
  ScoredReturns& scored = waveforms.scored;
  if (options.scored_energies) scored.bins = scored_bins;
  auto slice = [&](const std::vector<double>& flat, std::size_t row, double scale) {
    std::vector<double> energy_J(flat.begin() + row * tally.size,
                                 flat.begin() + (row + 1) * tally.size);
    for (double& value : energy_J) value *= scale;
    return lidar.power_W(energy_J);
  };
  auto integral_J = [&](const std::vector<double>& power_W) {
    double sum = 0.0;
    for (double value : power_W) sum += value * bin_s;
    return sum;
  };
  auto scored_J = [&](const std::vector<double>& flat, std::size_t band, double scale) {
    double sum = 0.0;
    for (const std::uint32_t bin : scored_bins) sum += flat[band * tally.size + bin];
    return sum * scale;
  };
  for (std::size_t band = 0; band < lidar.band_count(); ++band) {
    const LidarBand& b = lidar.sensor().bands[band];
    const double scale = b.pulse_energy_mJ * 1e-3 *
                         (layers ? 1.0 : b.atmos_transmission_roundtrip) *
                         lidar.sensor().telescope_area_m2 * lidar.fov_fraction() /
                         (std::numbers::pi * range_m * range_m) / rays;
    if (options.scored_energies) {
      scored.total_J.push_back(scored_row(tally.total, tally.size, band, scored_bins, scale));
      scored.canopy_J.push_back(scored_row(tally.canopy, tally.size, band, scored_bins, scale));
      scored.ground_J.push_back(scored_row(tally.ground, tally.size, band, scored_bins, scale));
      if (tally.orders > 0) {
        std::vector<std::vector<double>>& orders = scored.order_J.emplace_back();
        for (int k = 0; k < tally.orders; ++k)
          orders.push_back(scored_row(
              tally.order, tally.size,
              band * static_cast<std::size_t>(tally.orders) + static_cast<std::size_t>(k),
              scored_bins, scale));
      }
    }
    if (!options.power_waveforms) {
      waveforms.energy_J.push_back(scored_J(tally.total, band, scale));
      waveforms.canopy_energy_J.push_back(scored_J(tally.canopy, band, scale));
      waveforms.ground_energy_J.push_back(scored_J(tally.ground, band, scale));
      continue;
    }
    waveforms.total_W.push_back(slice(tally.total, band, scale));
    // Variance of the mean of `rays` scores, (sum w^2 - (sum w)^2 / N) / N^2 per bin (scale
    // holds the 1 / N), carried through the pulse like the power.
    std::vector<double> variance_J2(tally.size);
    for (std::size_t i = 0; i < tally.size; ++i) {
      const double sum = tally.total[band * tally.size + i];
      variance_J2[i] =
          scale * scale * std::max(tally.squares[band * tally.size + i] - sum * sum / rays, 0.0);
    }
    waveforms.total_variance_W2.push_back(lidar.power_variance_W2(variance_J2));
    // Where no return came from one part, the other's is the total, bit for bit (the same
    // scores added in the same order): bare ground needs no third convolution.
    auto none = [&](const std::vector<double>& flat) {
      return std::all_of(flat.begin() + band * tally.size, flat.begin() + (band + 1) * tally.size,
                         [](double value) { return value == 0.0; });
    };
    waveforms.canopy_W.push_back(none(tally.ground) ? waveforms.total_W.back()
                                                    : slice(tally.canopy, band, scale));
    waveforms.ground_W.push_back(none(tally.canopy) ? waveforms.total_W.back()
                                                    : slice(tally.ground, band, scale));
    waveforms.energy_J.push_back(integral_J(waveforms.total_W.back()));
    waveforms.canopy_energy_J.push_back(integral_J(waveforms.canopy_W.back()));
    waveforms.ground_energy_J.push_back(integral_J(waveforms.ground_W.back()));
    if (tally.orders > 0) {
      waveforms.order_W.emplace_back();
      for (int k = 0; k < tally.orders; ++k)
        waveforms.order_W.back().push_back(slice(tally.order, band * tally.orders + k, scale));
    }
  }
  return waveforms;
}

// The shot's truth of its atmosphere, when it has one: the layers' direct two-way transmission
// along the beam's axis, and of the returns in the window the part the layers scattered and their
// energy-weighted extra path (NaN without a return).
void add_atmosphere_truth(const Tally& tally, const Scene& scene, const ShotGeometry& geometry,
                          const TransportOptions& options, ShotWaveforms& waveforms) {
  if (!options.atmosphere) return;
  const std::size_t bands = tally.atmosphere.size() / Tally::atmosphere_sums;
  // The layers as the tracer cuts them: above the scene's top, where its rays start.
  const AtmosphereModel layers(*options.atmosphere, bands, geometry.ground_z_m,
                               geometry.ground_height_m, scene.top_m() + 1.0);
  const double mu = -geometry.axis[2];
  for (std::size_t band = 0; band < bands; ++band) {
    const double* sums = &tally.atmosphere[band * Tally::atmosphere_sums];
    waveforms.atmosphere_transmission.push_back(
        std::exp(-2.0 * layers.column_optical_depth(band) / mu));
    const double none = std::numeric_limits<double>::quiet_NaN();
    waveforms.atmosphere_scattered_fraction.push_back(sums[0] > 0.0 ? sums[1] / sums[0] : none);
    waveforms.atmosphere_delay_m.push_back(sums[0] > 0.0 ? sums[2] / sums[0] : none);
  }
}

}  // namespace

const char* to_string(RayEventKind kind) {
  switch (kind) {
    case RayEventKind::enter:
      return "enter";
    case RayEventKind::interaction:
      return "interaction";
    case RayEventKind::score:
      return "score";
    case RayEventKind::blocked:
      return "blocked";
    case RayEventKind::scatter:
      return "scatter";
    case RayEventKind::roulette:
      return "roulette";
    case RayEventKind::absorbed:
      return "absorbed";
    case RayEventKind::leave:
      return "leave";
    case RayEventKind::end:
      return "end";
  }
  return "?";
}

const char* to_string(RayElement element) {
  switch (element) {
    case RayElement::none:
      return "none";
    case RayElement::ground:
      return "ground";
    case RayElement::leaf:
      return "leaf";
    case RayElement::trunk:
      return "trunk";
    case RayElement::facet:
      return "facet";
  }
  return "?";
}

ShotWaveforms simulate_shot(const Scene& scene, const LidarModel& lidar,
                            const ShotGeometry& geometry, const SceneOptics& optics,
                            const TransportOptions& options, std::int64_t shot_number) {
  const int orders = options.per_order ? options.max_order : 0;
  const std::int64_t groups = std::min(ray_groups, options.rays);
  auto first_ray = [&](std::int64_t group) { return group * options.rays / groups; };
  if (options.rays < parallel_rays) {
    // The groups one after the other through one scratch tally, each added as it ends: the
    // same sums in the same order as below, without a tally a group.
    const ThreadTallies tallies(lidar.band_count(), lidar.tally_size(), orders);
    Tally &tally = tallies.total(), &group_tally = tallies.group();
    PathTracer tracer(scene, lidar, geometry, optics, options, shot_number, nullptr);
    for (std::int64_t group = 0; group < groups; ++group) {
      for (std::int64_t ray = first_ray(group); ray < first_ray(group + 1); ++ray)
        tracer.trace_ray(ray, group_tally);
      tally += group_tally;
      group_tally.clear();
    }
    ShotWaveforms waveforms = shot_waveforms(tally, lidar, geometry.range_m, options);
    add_atmosphere_truth(tally, scene, geometry, options, waveforms);
    return waveforms;
  }
  Tally tally(lidar.band_count(), lidar.tally_size(), orders);
  std::vector<Tally> group_tallies(groups, Tally(lidar.band_count(), lidar.tally_size(), orders));
  tbb::parallel_for(std::int64_t{0}, groups, [&](std::int64_t group) {
    PathTracer tracer(scene, lidar, geometry, optics, options, shot_number, nullptr);
    for (std::int64_t ray = first_ray(group); ray < first_ray(group + 1); ++ray)
      tracer.trace_ray(ray, group_tallies[group]);
  });
  for (const Tally& group : group_tallies) tally += group;
  ShotWaveforms waveforms = shot_waveforms(tally, lidar, geometry.range_m, options);
  add_atmosphere_truth(tally, scene, geometry, options, waveforms);
  return waveforms;
}

ShotWaveforms simulate_ray(const Scene& scene, const LidarModel& lidar,
                           const ShotGeometry& geometry, const SceneOptics& optics,
                           const TransportOptions& options, std::int64_t shot_number,
                           std::int64_t ray, const RayObserver& observer) {
  Tally tally(lidar.band_count(), lidar.tally_size(), options.per_order ? options.max_order : 0);
  PathTracer tracer(scene, lidar, geometry, optics, options, shot_number,
                    observer ? &observer : nullptr);
  tracer.trace_ray(ray, tally);
  ShotWaveforms waveforms = shot_waveforms(tally, lidar, geometry.range_m, options);
  add_atmosphere_truth(tally, scene, geometry, options, waveforms);
  return waveforms;
}

}  // namespace glaswave
