// What one ray does, event by event, for `glaswave run --debug-ray SHOT:RAY`: the transport
// tells an observer each step of the ray's two paths (where it entered the scene, what it met,
// what it scored toward the detector, where it scattered and why it stopped). The observer is
// optional; when none is given the transport builds no event at all.
#pragma once

#include <functional>
#include <limits>
#include <span>

#include "core/vec3.hpp"

namespace glaswave {

enum class RayEventKind {
  enter,        // the path starts just above the scene, in its first direction
  interaction,  // the path meets an element (position: the point met)
  score,        // the laser's light at the element, scored toward the detector and binned
  blocked,      // the laser does not reach the element (a surface between): nothing scored
  scatter,      // the next direction is chosen (weight: the path's throughput after)
  roulette,     // a faint path survives Russian roulette (weight: doubled)
  absorbed,     // the path ends: nothing scattered, or Russian roulette
  leave,        // the path leaves the scene without meeting anything
  end,          // the path ends: the single-scattering path's first element, or max_order
};

// leaf: a leaf of turbid foliage (met by free-path sampling); facet: a leaf facet of a facet
// tree, a surface, two-sided bi-Lambertian; trunk: bark, Lambertian (a trunk or a wood facet).
enum class RayElement { none, ground, leaf, trunk, facet };

struct RayEvent {
  RayEventKind kind = RayEventKind::enter;
  // Each ray traces two paths: the first (drawn by the beam's irradiance) scores the single
  // scattering, the second orders 2 and up (shot_transport.cpp says why).
  bool single_scattering_path = true;
  int order = 0;      // scattering order of the element met (0 before the first)
  Vec3 position_m{};  // in the shot's local east-north-up frame
  Vec3 direction{};   // unit, the path's travel direction (after a scatter: the new one)
  RayElement element = RayElement::none;
  int foliage = -1;  // which foliage (stand) a leaf or a trunk belongs to
  int crown = -1;    // which crown of the scene a leaf is in; -1 for the layer
  // Per band. A score's normalised return: its part of E_t T A_T f_fov / (pi R^2) (a
  // Lambertian surface of reflectance rho seen square-on at the reference range weighs rho);
  // for the other events the path's throughput.
  std::span<const double> weight;
  // From the detector to the position along the path; for a score, the whole way detector ->
  // path -> element -> laser, whose length sets the return's time.
  double path_m = 0.0;
  // A score's two-way time after the reference return, and where it is binned: its tally bin
  // (LidarModel's tally: the window's bins plus a margin of pulse width on each side; -1 outside
  // the tally, so not scored), and the window's bin that is (tally_bin - LidarModel::margin_bins,
  // an index into bin_time_ns; below 0 or past the last bin within the margin, from where the
  // pulse still spreads it into the window).
  double time_ns = std::numeric_limits<double>::quiet_NaN();
  int tally_bin = -1;
  int bin = -1;
};

const char* to_string(RayEventKind kind);
const char* to_string(RayElement element);

// Called for each event, in order; it must not keep the event's weight beyond the call.
using RayObserver = std::function<void(const RayEvent&)>;

}  // namespace glaswave
