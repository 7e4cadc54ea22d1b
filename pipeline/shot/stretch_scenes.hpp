// Consecutive shots of a beam share one scene (issue 25). ATLAS fires 10,000 shots a second, its
// footprints 0.7 m apart and about 11 m across: a shot's scene (the ground its light reaches and
// what grows on it, some 250 m across with vegetation) is nearly its neighbours'. A stretch, a
// fixed block of shot numbers of one beam, builds one scene in the frame of its middle footprint,
// wide enough for every one of its shots' patches, and each of its shots is traced through it.
// The scene depends on the stretch alone, never on which thread, batch, --shots part, process or
// --resume met it first, so the products are the same bits for any of them.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "footprints/solar_position.hpp"
#include "footprints/track.hpp"
#include "pipeline/scene/vegetation.hpp"
#include "pipeline/shot/scene_builder.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "terrain/local_frame.hpp"

namespace glaswave {

// Shots of a stretch: 256 at 0.7 m are 179 m of track, whose scene (with vegetation's 100 m
// margin) is about 2.6 times a shot's in area, built once for 256 shots.
inline constexpr std::int64_t stretch_shots = 256;
// Shots of a waveform pass's strip (GEDI's footprints 60 m apart, about 25 m across, each
// scene some 360 m across with vegetation): a strip of 8 shots, 420 m of track, is one
// rectangle along it as wide as a shot's scene, 0.27 times the area of 8 shots' own scenes.
// 4, 8 and 16 shots cost the same within 2 % on the GEDI demo (docs/performance.md: what stays
// is per shot, the roughness under each beam and the rays); 8 keep within 500 m. GLAS's footprints,
// 172 m apart, reach farther than max_stretch_reach_m from a strip's middle and build their own.
inline constexpr std::int64_t strip_shots = 8;
// A stretch whose footprints lie farther than this from its middle one (consecutive shots far
// apart: points, a granule's beams one after another) shares no scene: its shots build their own.
inline constexpr double max_stretch_reach_m = 500.0;

// The sun over a stretch: ERFA's place at its first and last footprints, interpolated in shot
// number between them. The sun moves 0.004 deg in a second, the footprint 0.0016 deg of latitude
// over a stretch: the interpolation's error is under 1e-6 deg, far below ERFA's 0.001 deg against
// SPA.
struct StretchSun {
  std::int64_t first_shot = 0, last_shot = 0;
  SolarPosition first, last;
  // The sun at shot `shot` of the stretch.
  SolarPosition at(std::int64_t shot) const;
};

// One stretch's scene, in the frame of its middle footprint.
struct StretchScene {
  LocalFrame frame;
  BuiltScene built;
  // Absent when the sun's place is not known at an end, or turns fast (near the zenith): each
  // shot then asks ERFA.
  std::optional<StretchSun> sun;
  // The truth's vertical lines on one grid for every shot (the middle one's spacing); absent
  // when the vegetation measures its own truth (facets).
  std::unique_ptr<TruthGrid> truth;
  // The stretch's first shot number, and which of its shots' beams fall on the terrain's data
  // (beam_on_terrain_data), from the first.
  std::int64_t first_shot = 0;
  std::vector<bool> on_data;

  bool holds(std::int64_t shot) const {
    return shot >= first_shot && shot - first_shot < static_cast<std::int64_t>(on_data.size()) &&
           on_data[static_cast<std::size_t>(shot - first_shot)];
  }
};

// A stretch's scene: a square about its middle footprint (ICESat-2's 0.7 m spacing), or a strip,
// a rectangle along the track holding each footprint's scene, the roughness meshed under each
// beam (waveform passes).
enum class StretchShape { square, strip };

// What a strip's scene is built over, in the frame of its middle footprint: the rectangle
// holding each footprint's own scene, the square about the middle that holds the rectangle (its
// ground is meshed over it and cut to the rectangle), and the roughness's square under each beam.
struct StripPlan {
  RegionStrip strip;
  double half_size_m = 0.0;
  std::vector<RoughSquare> rough;
  // How far the largest of the footprints' own scenes reaches from its centre.
  double shot_reach_m = 0.0;
};

class StretchScenes {
 public:
  // The builder, lidar and track outlive this. `margin_m`: how far beyond a shot's traced patch
  // its scene reaches (vegetation's diffuse light). `shots`: shots a stretch.
  StretchScenes(const SceneBuilder& scenes, const LidarModel& lidar, const Track& track,
                double margin_m, std::int64_t shots = stretch_shots,
                StretchShape shape = StretchShape::square);

  // The scene of the footprint's stretch, built at its first use (or ahead, by its predecessor's
  // middle shot) and kept while the run is near it; null when the stretch shares none (its
  // footprints spread too far). Thread-safe; a footprint the stretch's scene holds is on the
  // terrain's data (beam_on_terrain_data).
  std::shared_ptr<const StretchScene> find(const Footprint& footprint) const;

  // What the strip `stretch` of the beam of index `beam_index` is built over (a strip-shaped
  // stretch's), as its build plans it, building nothing; none where it shares no scene (its
  // footprints spread too far, or scattered so that its rectangle would outgrow their own scenes
  // together). For the memory estimate.
  std::optional<StripPlan> plan_strip(int beam_index, std::int64_t stretch) const;

  std::int64_t shots() const { return shots_; }
  StretchShape shape() const { return shape_; }
  // Stretches kept at once, the most recent (their scenes held while the run is near them).
  std::size_t kept() const;

 private:
  struct Entry;
  std::shared_ptr<const StretchScene> find(int beam_index, std::int64_t stretch) const;
  std::shared_ptr<const StretchScene> build(int beam_index, std::int64_t stretch) const;
  std::vector<Footprint> held_footprints(int beam_index, std::int64_t stretch,
                                         std::vector<bool>& on_data) const;
  std::optional<StripPlan> plan_strip(const LocalFrame& frame,
                                      const std::vector<Footprint>& held) const;
  void build_strip(StretchScene& scene, const std::vector<Footprint>& held,
                   const StripPlan& plan) const;
  void finish(StretchScene& scene, const std::vector<Footprint>& held) const;

  const SceneBuilder& scenes_;
  const LidarModel& lidar_;
  const Track& track_;
  double margin_m_;
  std::int64_t shots_;
  StretchShape shape_;
  // The stretches met last, the most recent last: a run walks the track in order, so three a
  // beam (the one a batch ends in, the one it starts, the next one built ahead) are all it meets
  // again.
  mutable std::mutex mutex_;
  mutable std::vector<std::shared_ptr<Entry>> recent_;
};

}  // namespace glaswave
