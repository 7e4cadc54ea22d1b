// The scenes of stretches of track, built once and shared by their shots.
#include "pipeline/shot/stretch_scenes.hpp"

#include <tbb/collaborative_call_once.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <stdexcept>

#include "pipeline/shot/footprint_geometry.hpp"
#include "pipeline/transport/scattering.hpp"

namespace glaswave {

SolarPosition StretchSun::at(std::int64_t shot) const {
  const double t = last_shot == first_shot ? 0.0
                                           : static_cast<double>(shot - first_shot) /
                                                 static_cast<double>(last_shot - first_shot);
  SolarPosition sun;
  sun.elevation_deg = first.elevation_deg + t * (last.elevation_deg - first.elevation_deg);
  sun.azimuth_deg =
      first.azimuth_deg + t * std::remainder(last.azimuth_deg - first.azimuth_deg, 360.0);
  if (sun.azimuth_deg < 0.0) sun.azimuth_deg += 360.0;
  if (sun.azimuth_deg >= 360.0) sun.azimuth_deg -= 360.0;
  return sun;
}

namespace {

// Where the sun stands over a stretch held between the footprints `a` and `b`; none where ERFA
// cannot place it or it turns by over a degree (near the zenith the azimuth swings).
std::optional<StretchSun> stretch_sun(const Footprint& a, const Footprint& b) {
  try {
    StretchSun sun{a.shot_number, b.shot_number,
                   solar_position(a.time_s, a.ground.lat_deg, a.ground.lon_deg, a.ground.h_m),
                   solar_position(b.time_s, b.ground.lat_deg, b.ground.lon_deg, b.ground.h_m)};
    if (std::abs(sun.last.elevation_deg - sun.first.elevation_deg) > 1.0 ||
        std::abs(std::remainder(sun.last.azimuth_deg - sun.first.azimuth_deg, 360.0)) > 1.0)
      return std::nullopt;
    return sun;
  } catch (const std::invalid_argument&) {
    return std::nullopt;  // a time outside 1900-2100
  }
}

}  // namespace

struct StretchScenes::Entry {
  int beam_index = 0;
  std::int64_t stretch = 0;
  tbb::collaborative_once_flag built;
  std::shared_ptr<const StretchScene> scene;
  std::exception_ptr failure;
};

StretchScenes::StretchScenes(const SceneBuilder& scenes, const LidarModel& lidar,
                             const Track& track, double margin_m, std::int64_t shots,
                             StretchShape shape)
    : scenes_(scenes),
      lidar_(lidar),
      track_(track),
      margin_m_(margin_m),
      shots_(shots),
      shape_(shape) {
  if (shots_ < 1) throw std::invalid_argument("a stretch holds at least one shot");
}

std::size_t StretchScenes::kept() const {
  return static_cast<std::size_t>(3 * track_.beams_per_shot() + 2);
}

std::shared_ptr<const StretchScene> StretchScenes::find(const Footprint& footprint) const {
  const int beam_index = track_.beam_index(footprint.beam);
  const std::int64_t stretch = footprint.shot_number / shots_;
  std::shared_ptr<const StretchScene> scene = find(beam_index, stretch);
  // Halfway through a stretch its shot builds the next one, while the other threads go on with
  // this stretch's shots: when they reach the next, none waits for its build. A build that fails
  // keeps its failure for the next stretch's own shots.
  if (footprint.shot_number % shots_ == shots_ / 2 &&
      (stretch + 1) * shots_ < track_.sequence_length()) {
    try {
      find(beam_index, stretch + 1);
    } catch (...) {
    }
  }
  return scene;
}

std::shared_ptr<const StretchScene> StretchScenes::find(int beam_index,
                                                        std::int64_t stretch) const {
  std::shared_ptr<Entry> entry;
  {
    const std::lock_guard lock(mutex_);
    const auto found = std::find_if(recent_.begin(), recent_.end(), [&](const auto& e) {
      return e->beam_index == beam_index && e->stretch == stretch;
    });
    if (found != recent_.end()) {
      entry = *found;
      recent_.erase(found);
    } else {
      entry = std::make_shared<Entry>();
      entry->beam_index = beam_index;
      entry->stretch = stretch;
      if (recent_.size() >= kept()) recent_.erase(recent_.begin());
    }
    recent_.push_back(entry);
  }
  // The first shot to need it builds it; the others that need it meanwhile help (Embree's build
  // runs on TBB) or wait.
  tbb::collaborative_call_once(entry->built, [&] {
    try {
      entry->scene = build(beam_index, stretch);
    } catch (...) {
      entry->failure = std::current_exception();
    }
  });
  if (entry->failure) std::rethrow_exception(entry->failure);
  return entry->scene;
}

namespace {

// How far the footprints' centres lie from the frame's origin (the middle one's).
double reach_from_middle_m(const LocalFrame& frame, const std::vector<Footprint>& held) {
  double reach_m = 0.0;
  for (const Footprint& footprint : held) {
    const Vec3 centre = frame.to_local(footprint.ground);
    reach_m = std::max(reach_m, std::hypot(centre[0], centre[1]));
  }
  return reach_m;
}

// Whether a strip's rectangle is smaller than its footprints' own scenes together: footprints
// along a line (a pass's, an orbit's, 60 m apart: a quarter) share it; points scattered about
// would share a larger scene than they build alone. A lone footprint's strip (a track's last)
// is its own scene's size, and stays a strip.
bool smaller_than_own_scenes(const StripPlan& plan, std::size_t footprints) {
  if (footprints < 2) return true;
  const RegionStrip& r = plan.strip;
  const double own_m = 2.0 * plan.shot_reach_m;
  return (r.along1_m - r.along0_m) * (r.across1_m - r.across0_m) <
         static_cast<double>(footprints) * own_m * own_m;
}

}  // namespace

// The stretch's footprints whose beams fall on the terrain's data; `on_data` says which of its
// shots those are, from the first.
std::vector<Footprint> StretchScenes::held_footprints(int beam_index, std::int64_t stretch,
                                                      std::vector<bool>& on_data) const {
  const std::int64_t first = stretch * shots_;
  const std::int64_t last = std::min(first + shots_, track_.sequence_length());
  std::vector<Footprint> held;
  on_data.clear();
  for (std::int64_t shot = first; shot < last; ++shot) {
    Footprint footprint = track_.locate_shot(shot, beam_index);
    on_data.push_back(beam_on_terrain_data(scenes_.terrain(), lidar_, footprint));
    if (on_data.back()) held.push_back(std::move(footprint));
  }
  return held;
}

std::optional<StripPlan> StretchScenes::plan_strip(int beam_index, std::int64_t stretch) const {
  if (shape_ != StretchShape::strip) return std::nullopt;
  std::vector<bool> on_data;
  const std::vector<Footprint> held = held_footprints(beam_index, stretch, on_data);
  if (held.empty()) return std::nullopt;
  const LocalFrame frame(held[held.size() / 2].ground);
  if (reach_from_middle_m(frame, held) > max_stretch_reach_m) return std::nullopt;
  return plan_strip(frame, held);
}

std::shared_ptr<const StretchScene> StretchScenes::build(int beam_index,
                                                         std::int64_t stretch) const {
  const Terrain& terrain = scenes_.terrain();
  std::vector<bool> on_data;
  const std::vector<Footprint> held = held_footprints(beam_index, stretch, on_data);
  if (held.empty()) return nullptr;
  const Footprint& middle = held[held.size() / 2];
  auto stretch_scene = std::make_shared<StretchScene>(
      StretchScene{LocalFrame(middle.ground), {}, {}, {}, stretch * shots_, std::move(on_data)});
  const LocalFrame& frame = stretch_scene->frame;
  const double reach_m = reach_from_middle_m(frame, held);
  if (reach_m > max_stretch_reach_m) return nullptr;
  if (shape_ == StretchShape::strip) {
    const std::optional<StripPlan> plan = plan_strip(frame, held);
    if (!plan) return nullptr;
    build_strip(*stretch_scene, held, *plan);
    return stretch_scene;
  }
  // The patch a shot's rays land on changes only with the ground's slope under it: every 32nd
  // shot's and the last's (their 8 directions traced to the terrain), 22 m apart.
  double patch_m = 0.0;
  std::vector<std::size_t> sampled;
  for (std::size_t k = 0; k < held.size(); k += 32) sampled.push_back(k);
  sampled.push_back(held.size() - 1);
  for (const std::size_t k : sampled)
    patch_m = std::max(
        patch_m, traced_patch_half_size_m(terrain, lidar_, held[k], LocalFrame(held[k].ground),
                                          lidar_.max_angle_rad()));
  // The middle footprint's ground for what follows it (no source that shares scenes does).
  const FootprintFrame where = footprint_frame(terrain, lidar_, middle);
  stretch_scene->built =
      scenes_.build(frame, where.orientation, reach_m + patch_m + margin_m_, 0.0);
  finish(*stretch_scene, held);
  return stretch_scene;
}

// The strip's rectangle, in the frame of its middle footprint: along the line from its first
// footprint to its last, as long and wide as every footprint's own scene (its traced patch and
// the margin about its centre), the roughness under each beam as a shot's own scene has it; none
// where the rectangle is no smaller than the footprints' own scenes together.
std::optional<StripPlan> StretchScenes::plan_strip(const LocalFrame& frame,
                                                   const std::vector<Footprint>& held) const {
  const Terrain& terrain = scenes_.terrain();
  std::vector<Vec3> centres;
  for (const Footprint& footprint : held) centres.push_back(frame.to_local(footprint.ground));
  RegionStrip strip;
  const Vec3 run = centres.back() - centres.front();
  if (std::hypot(run[0], run[1]) > 1e-3) {
    const double length_m = std::hypot(run[0], run[1]);
    strip.axis_x = run[0] / length_m;
    strip.axis_y = run[1] / length_m;
  }
  double reach_m = 0.0;  // of a footprint's scene about its centre
  std::vector<RoughSquare> rough;
  const bool roughness = scenes_.roughness().enabled();
  const double rough_angle_rad = std::min(lidar_.max_angle_rad(), 4.5 * lidar_.beam_sigma_rad());
  for (std::size_t k = 0; k < held.size(); ++k) {
    const LocalFrame own(held[k].ground);
    reach_m = std::max(
        reach_m, traced_patch_half_size_m(terrain, lidar_, held[k], own, lidar_.max_angle_rad()) +
                     margin_m_);
    // Roughness is meshed only where the beam is, as in the shot's own scene.
    if (roughness)
      rough.push_back({centres[k][0], centres[k][1],
                       traced_patch_half_size_m(terrain, lidar_, held[k], own, rough_angle_rad)});
  }
  strip.along0_m = strip.across0_m = std::numeric_limits<double>::infinity();
  strip.along1_m = strip.across1_m = -std::numeric_limits<double>::infinity();
  for (const Vec3& c : centres) {
    const double along = c[0] * strip.axis_x + c[1] * strip.axis_y;
    const double across = c[1] * strip.axis_x - c[0] * strip.axis_y;
    strip.along0_m = std::min(strip.along0_m, along - reach_m);
    strip.along1_m = std::max(strip.along1_m, along + reach_m);
    strip.across0_m = std::min(strip.across0_m, across - reach_m);
    strip.across1_m = std::max(strip.across1_m, across + reach_m);
  }
  // The square about the middle footprint that holds the rectangle.
  double half_size_m = 0.0;
  for (const double along : {strip.along0_m, strip.along1_m})
    for (const double across : {strip.across0_m, strip.across1_m})
      half_size_m = std::max({half_size_m, std::abs(along * strip.axis_x - across * strip.axis_y),
                              std::abs(along * strip.axis_y + across * strip.axis_x)});
  StripPlan plan{strip, half_size_m, std::move(rough), reach_m};
  if (!smaller_than_own_scenes(plan, held.size())) return std::nullopt;
  return plan;
}

void StretchScenes::build_strip(StretchScene& scene, const std::vector<Footprint>& held,
                                const StripPlan& plan) const {
  const FootprintFrame where = footprint_frame(scenes_.terrain(), lidar_, held[held.size() / 2]);
  scene.built =
      scenes_.build(scene.frame, where.orientation, plan.half_size_m, plan.strip, plan.rough);
  finish(scene, held);
}

// The sun over the stretch, and the truth's grid where the vegetation's truth is measured on
// its volumes.
void StretchScenes::finish(StretchScene& scene, const std::vector<Footprint>& held) const {
  scene.sun = stretch_sun(held.front(), held.back());
  const VegetationSource* vegetation = scenes_.vegetation();
  const Footprint& middle = held[held.size() / 2];
  if (!vegetation || vegetation->measured_on_volumes())
    scene.truth = std::make_unique<TruthGrid>(*scene.built.scene,
                                              0.15 * middle.range_m * lidar_.beam_sigma_rad(),
                                              nadir_projection(scene.built.optics));
}

}  // namespace glaswave
