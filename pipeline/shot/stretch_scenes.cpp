// The scenes of stretches of track, built once and shared by their shots.
#include "pipeline/shot/stretch_scenes.hpp"

#include <tbb/collaborative_call_once.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <stdexcept>

#include "pipeline/shot/footprint_geometry.hpp"

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
                             const Track& track, double margin_m, std::int64_t shots)
    : scenes_(scenes), lidar_(lidar), track_(track), margin_m_(margin_m), shots_(shots) {
  if (shots_ < 1) throw std::invalid_argument("a stretch holds at least one shot");
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
      const auto kept = static_cast<std::size_t>(3 * track_.beams_per_shot() + 2);
      if (recent_.size() >= kept) recent_.erase(recent_.begin());
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

std::shared_ptr<const StretchScene> StretchScenes::build(int beam_index,
                                                         std::int64_t stretch) const {
  const Terrain& terrain = scenes_.terrain();
  const std::int64_t first = stretch * shots_;
  const std::int64_t last = std::min(first + shots_, track_.sequence_length());
  std::vector<Footprint> held;  // the footprints whose beams fall on the terrain's data
  std::vector<bool> on_data;
  for (std::int64_t shot = first; shot < last; ++shot) {
    Footprint footprint = track_.locate_shot(shot, beam_index);
    on_data.push_back(beam_on_terrain_data(terrain, lidar_, footprint));
    if (on_data.back()) held.push_back(std::move(footprint));
  }
  if (held.empty()) return nullptr;
  const Footprint& middle = held[held.size() / 2];
  auto stretch_scene = std::make_shared<StretchScene>(
      StretchScene{LocalFrame(middle.ground), {}, {}, {}, first, std::move(on_data)});
  const LocalFrame& frame = stretch_scene->frame;
  double reach_m = 0.0;  // of the footprint centres from the middle one
  for (const Footprint& footprint : held) {
    const Vec3 centre = frame.to_local(footprint.ground);
    reach_m = std::max(reach_m, std::hypot(centre[0], centre[1]));
  }
  if (reach_m > max_stretch_reach_m) return nullptr;
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
  stretch_scene->sun = stretch_sun(held.front(), held.back());
  const VegetationSource* vegetation = scenes_.vegetation();
  if (!vegetation || vegetation->measured_on_volumes())
    stretch_scene->truth = std::make_unique<TruthGrid>(
        *stretch_scene->built.scene, 0.15 * middle.range_m * lidar_.beam_sigma_rad());
  return stretch_scene;
}

}  // namespace glaswave
