// Track geometry: pass and points tracks, pointing, and the beam against the terrain.
#include "footprints/track.hpp"

#include <cmath>
#include <numbers>

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/Geodesic.hpp>

#include "terrain/error.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;
constexpr double earth_gm_m3_s2 = 3.986004418e14;

// Smallest t >= 0 where origin + t * direction meets the ellipsoid raised by height_m.
std::optional<double> ellipsoid_crossing(const Vec3& origin, const Vec3& direction, double height_m) {
  const double a = GeographicLib::Constants::WGS84_a() + height_m;
  const double b = GeographicLib::Constants::WGS84_a() * (1.0 - GeographicLib::Constants::WGS84_f()) + height_m;
  const Vec3 o{origin[0] / a, origin[1] / a, origin[2] / b};
  const Vec3 d{direction[0] / a, direction[1] / a, direction[2] / b};
  const double qa = dot(d, d), qb = 2.0 * dot(o, d), qc = dot(o, o) - 1.0;
  const double discriminant = qb * qb - 4.0 * qa * qc;
  if (discriminant < 0.0) return std::nullopt;
  // The nearer root, written to avoid cancellation.
  const double q = -0.5 * (qb + std::copysign(std::sqrt(discriminant), qb));
  double t0 = q / qa, t1 = qc / q;
  if (t0 > t1) std::swap(t0, t1);
  if (t1 < 0.0) return std::nullopt;
  return t0 >= 0.0 ? t0 : t1;
}

// The spacecraft position at geodetic height `altitude_m` whose tilted beam lands on `target`.
Vec3 aim_at(const Vec3& target_ecef, double altitude_m, double off_nadir_deg, double azimuth_deg) {
  const Geodetic target = geodetic_from_ecef(target_ecef);
  Vec3 spacecraft = ecef_from_geodetic({target.lat_deg, target.lon_deg, altitude_m});
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Geodetic at = geodetic_from_ecef(spacecraft);
    const Vec3 beam = pointing_direction(at, off_nadir_deg, azimuth_deg);
    // Slide back along the beam from the target until the height is the altitude.
    double range_m = norm(spacecraft - target_ecef);
    for (int step = 0; step < 20; ++step) {
      const Geodetic p = geodetic_from_ecef(target_ecef - range_m * beam);
      const Vec3 up = enu_axes(p.lat_deg, p.lon_deg)[2];
      const double correction_m = (altitude_m - p.h_m) / -dot(beam, up);
      range_m += correction_m;
      if (std::abs(correction_m) < 1e-6) break;
    }
    const Vec3 moved = target_ecef - range_m * beam;
    const double change_m = norm(moved - spacecraft);
    spacecraft = moved;
    if (change_m < 1e-5) break;
  }
  return spacecraft;
}

Footprint locate(std::int64_t shot_number, double time_s, const Vec3& spacecraft_ecef, const Vec3& beam,
                 double off_nadir_deg, const Terrain& terrain) {
  Footprint footprint;
  footprint.shot_number = shot_number;
  footprint.time_s = time_s;
  footprint.spacecraft_ecef = spacecraft_ecef;
  footprint.spacecraft = geodetic_from_ecef(spacecraft_ecef);
  footprint.beam_ecef = beam;
  footprint.off_nadir_deg = off_nadir_deg;
  if (const auto hit = intersect_terrain(terrain, spacecraft_ecef, beam)) {
    footprint.on_terrain = true;
    footprint.ground = geodetic_from_ecef(*hit);
    footprint.range_m = norm(*hit - spacecraft_ecef);
  }
  return footprint;
}

}  // namespace

Vec3 pointing_direction(const Geodetic& spacecraft, double off_nadir_deg, double pointing_azimuth_deg) {
  const auto axes = enu_axes(spacecraft.lat_deg, spacecraft.lon_deg);
  const double tilt = std::sin(off_nadir_deg * deg);
  return (tilt * std::sin(pointing_azimuth_deg * deg)) * axes[0] +
         (tilt * std::cos(pointing_azimuth_deg * deg)) * axes[1] + (-std::cos(off_nadir_deg * deg)) * axes[2];
}

std::optional<Vec3> intersect_terrain(const Terrain& terrain, const Vec3& origin_ecef,
                                      const Vec3& direction_ecef) {
  const Vec3 direction = normalized(direction_ecef);
  // Height of the point at distance t above the terrain below it.
  auto clearance_m = [&](double t) {
    const Geodetic p = geodetic_from_ecef(origin_ecef + t * direction);
    return p.h_m - terrain.height_m(p.lat_deg, p.lon_deg);
  };
  const auto start = ellipsoid_crossing(origin_ecef, direction, 0.0);
  if (!start) return std::nullopt;
  // First guess: the ellipsoid raised to the terrain's height at the ellipsoid crossing.
  const Geodetic on_ellipsoid = geodetic_from_ecef(origin_ecef + *start * direction);
  const double guess_height_m = terrain.height_m(on_ellipsoid.lat_deg, on_ellipsoid.lon_deg);
  if (!std::isfinite(guess_height_m)) return std::nullopt;
  auto t = ellipsoid_crossing(origin_ecef, direction, guess_height_m);
  if (!t) return std::nullopt;
  // Secant iterations on the clearance, started with the slope of a level surface.
  double t0 = *t, f0 = clearance_m(t0);
  if (!std::isfinite(f0)) return std::nullopt;
  const Vec3 up = enu_axes(on_ellipsoid.lat_deg, on_ellipsoid.lon_deg)[2];
  double t1 = t0 + f0 / -dot(direction, up);
  for (int iteration = 0; iteration < 60; ++iteration) {
    const double f1 = clearance_m(t1);
    if (!std::isfinite(f1)) return std::nullopt;
    if (std::abs(t1 - t0) < 1e-3 || f1 == 0.0) return origin_ecef + t1 * direction;
    const double t2 = (f1 == f0) ? t1 : t1 - f1 * (t1 - t0) / (f1 - f0);
    t0 = t1;
    f0 = f1;
    t1 = t2;
  }
  return std::nullopt;
}

std::int64_t track_length(const TrackSettings& track) {
  if (track.type == TrackType::points) return static_cast<std::int64_t>(track.points.size());
  return track.shots;
}

std::vector<Footprint> plan_track(const TrackSettings& track, const Terrain& terrain, std::int64_t first,
                                  std::int64_t last) {
  last = std::min(last, track_length(track));
  std::vector<Footprint> footprints;
  for (std::int64_t shot = first; shot < last; ++shot) {
    const double time_s = track.start_time_s + shot / track.rate_hz;
    switch (track.type) {
      case TrackType::points: {
        const GroundPoint& point = track.points[shot];
        const double height_m = terrain.height_m(point.lat_deg, point.lon_deg);
        if (!std::isfinite(height_m)) {
          // No ground under the target: the spacecraft is placed as if the ground were the ellipsoid.
          const Vec3 target = ecef_from_geodetic({point.lat_deg, point.lon_deg, 0.0});
          const Vec3 spacecraft = aim_at(target, track.altitude_m, track.off_nadir_deg, track.pointing_azimuth_deg);
          Footprint footprint = locate(shot, time_s, spacecraft, normalized(target - spacecraft),
                                       track.off_nadir_deg, terrain);
          footprint.on_terrain = false;
          footprints.push_back(footprint);
          break;
        }
        const Vec3 target = ecef_from_geodetic({point.lat_deg, point.lon_deg, height_m});
        const Vec3 spacecraft = aim_at(target, track.altitude_m, track.off_nadir_deg, track.pointing_azimuth_deg);
        footprints.push_back(locate(shot, time_s, spacecraft, normalized(target - spacecraft), track.off_nadir_deg,
                                    terrain));
        break;
      }
      case TrackType::pass: {
        // The ground speed of a circular orbit at this altitude, when no spacing is given.
        const double radius_m = GeographicLib::Constants::WGS84_a() + track.altitude_m;
        const double ground_speed_m_s =
            std::sqrt(earth_gm_m3_s2 / radius_m) * GeographicLib::Constants::WGS84_a() / radius_m;
        const double spacing_m = track.spacing_m.value_or(ground_speed_m_s / track.rate_hz);
        double lat_deg = 0.0, lon_deg = 0.0;
        GeographicLib::Geodesic::WGS84().Direct(track.start_lat_deg, track.start_lon_deg, track.heading_deg,
                                                shot * spacing_m, lat_deg, lon_deg);
        const Geodetic spacecraft{lat_deg, lon_deg, track.altitude_m};
        footprints.push_back(locate(shot, time_s, ecef_from_geodetic(spacecraft),
                                    pointing_direction(spacecraft, track.off_nadir_deg, track.pointing_azimuth_deg),
                                    track.off_nadir_deg, terrain));
        break;
      }
      case TrackType::orbit:
        throw config_error("/track/type", "orbit tracks are not available in this version yet; use pass or points");
      case TrackType::ephemeris:
        throw config_error("/track/type",
                           "ephemeris tracks are not available in this version yet; use pass or points");
    }
  }
  return footprints;
}

}  // namespace glaswave
