// The footprint's geometry in its local frame: where the beam points, the ground patch its rays
// and their diffuse light reach (the scene's size, which the memory estimate calls too), and the
// beam's outline on the scene.
#pragma once

#include <array>
#include <vector>

#include "footprints/track.hpp"
#include "pipeline/scene/scene.hpp"
#include "pipeline/transport/lidar_model.hpp"
#include "pipeline/transport/shot_transport.hpp"
#include "terrain/ground_mesh.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

// Points of the beam outline: each is one ray query of the shot.
inline constexpr int outline_vertices = 36;
// With vegetation, diffuse light wanders beyond the beam: the ground reaches this much further.
inline constexpr double vegetation_margin_m = 100.0;

// Half-width of the ground patch for rays that land up to `reach_m` from the footprint centre:
// 1.2 times that, plus 2 m.
double patch_half_size_m(double reach_m);

// The same, before any footprint is traced: the field of view's edge at `range_m`, longer along
// a plane sloped by `slope_deg`, with the vegetation's margin when there is vegetation. What a
// shot's scene spans at most, for the memory estimate.
double estimated_patch_half_size_m(double range_m, double ifov_rad, double slope_deg,
                                   bool vegetation);

// The copies of a shot's waveforms its transport tallies in (the ray groups and their sum), for
// the memory estimate.
inline constexpr double shot_waveform_copies = transport_waveform_copies;

// Half-width of `glaswave brf`'s scene around its tile: the crowns reaching into a periodic
// tile (5 m), or the light wandering out over a DEM (100 m).
double brf_scene_half_size_m(double tile_half_size_m, bool periodic);

// The part of the beam's energy the detector's field of view holds (LidarModel::fov_fraction),
// for what normalises a return beyond the shot (RAMI's lidar files).
double beam_fraction_in_view(const LidarSettings& lidar);

// One footprint in its local east-north-up frame.
struct FootprintFrame {
  LocalFrame frame;
  ShotGeometry geometry;
  SurfaceOrientation orientation;  // the ground's, fitted over the beam's RMS width
};
FootprintFrame footprint_frame(const Terrain& terrain, const LidarModel& lidar,
                               const Footprint& footprint);

// Half-width of the ground patch that every ray sampled within `angle_rad` of the beam's axis
// lands on: those rays traced to the terrain in a few directions (patch_half_size_m of the
// farthest).
double traced_patch_half_size_m(const Terrain& terrain, const LidarModel& lidar,
                                const Footprint& footprint, const LocalFrame& frame,
                                double angle_rad);

// A beam over a hole in the DEM or its edge (3 sigma: 99 % of its energy) gives no waveform
// worth having: false there, as off the terrain.
bool beam_on_terrain_data(const Terrain& terrain, const LidarModel& lidar,
                          const Footprint& footprint);

// The beam's 1/e^2 contour (2 sigma from the axis, within the field of view) traced on the
// scene, counter-clockwise in longitude and latitude, closed; empty when under 3 points hit.
std::vector<std::array<double, 2>> beam_outline(const Scene& scene, const LidarModel& lidar,
                                                const ShotGeometry& geometry,
                                                const LocalFrame& frame);

}  // namespace glaswave
