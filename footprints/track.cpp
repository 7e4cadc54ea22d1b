// Track geometry: the spacecraft position and beam of each shot (pass, points, orbit,
// ephemeris), and its footprint on the terrain.
#include "footprints/track.hpp"

#include <GeographicLib/Constants.hpp>
#include <GeographicLib/Geodesic.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <stdexcept>
#include <string>

#include "core/error.hpp"
#include "core/glas_time.hpp"

namespace glaswave {
namespace {

constexpr double deg = std::numbers::pi / 180.0;

// The spacecraft position at geodetic height `altitude_m` whose tilted beam lands on `target`.
// A fixed point: the beam direction depends on the spacecraft's own geodetic vertical, which moves
// a little with the spacecraft; each pass slides back along the current beam to the altitude.
Vec3 aim_at(const Vec3& target_ecef, double altitude_m, double off_nadir_deg, double azimuth_deg) {
  const Geodetic target = geodetic_from_ecef(target_ecef);
  Vec3 spacecraft = ecef_from_geodetic({target.lat_deg, target.lon_deg, altitude_m});
  for (int iteration = 0; iteration < 50; ++iteration) {
    const Geodetic at = geodetic_from_ecef(spacecraft);
    const Vec3 beam = pointing_direction(at, off_nadir_deg, azimuth_deg);
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
    if (change_m < 1e-6) break;
  }
  return spacecraft;
}

// The ground speed of a circular orbit at this altitude, ignoring the Earth's rotation.
double orbital_ground_speed_m_s(double altitude_m) {
  const double radius_m = GeographicLib::Constants::WGS84_a() + altitude_m;
  return std::sqrt(GeographicLib::Constants::WGS84_GM() / radius_m) *
         GeographicLib::Constants::WGS84_a() / radius_m;
}

}  // namespace

Vec3 pointing_direction(const Geodetic& spacecraft, double off_nadir_deg,
                        double pointing_azimuth_deg) {
  const auto axes = enu_axes(spacecraft.lat_deg, spacecraft.lon_deg);
  const double tilt = std::sin(off_nadir_deg * deg);
  return (tilt * std::sin(pointing_azimuth_deg * deg)) * axes[0] +
         (tilt * std::cos(pointing_azimuth_deg * deg)) * axes[1] +
         (-std::cos(off_nadir_deg * deg)) * axes[2];
}

double off_nadir_angle_deg(const Vec3& spacecraft_ecef, const Vec3& beam_ecef) {
  const Geodetic at = geodetic_from_ecef(spacecraft_ecef);
  const Vec3 down = -1.0 * enu_axes(at.lat_deg, at.lon_deg)[2];
  const Vec3 beam = normalized(beam_ecef);
  // atan2 of sine and cosine keeps its precision near nadir, where acos does not.
  return std::atan2(norm(cross(beam, down)), dot(beam, down)) / deg;
}

Track::Track(const TrackSettings& settings, const Terrain& terrain, const TerrainLimits& limits)
    : settings_(settings), terrain_(terrain), limits_(limits) {
  switch (settings_.type) {
    case TrackType::pass:
      sequence_length_ = settings_.shots;
      pass_spacing_m_ = settings_.spacing_m.value_or(
          orbital_ground_speed_m_s(settings_.altitude_m) / settings_.rate_hz);
      break;
    case TrackType::points:
      sequence_length_ = static_cast<std::int64_t>(settings_.points.size());
      break;
    case TrackType::orbit:
      sequence_length_ = settings_.shots;
      orbit_ = std::make_unique<Orbit>(settings_.orbit);
      break;
    case TrackType::ephemeris:
      ephemeris_ = read_ephemeris(settings_.ephemeris);
      sequence_length_ = static_cast<std::int64_t>(ephemeris_.size());
      break;
    case TrackType::granule:
      granule_ = read_granule(settings_.granule, settings_.beams, &warnings_);
      sequence_length_ = static_cast<std::int64_t>(granule_.size());
      settings_.points.clear();
      for (const GranuleShot& shot : granule_)
        settings_.points.push_back({shot.lat_deg, shot.lon_deg});
      break;
  }

  check_times();

  if (settings_.type == TrackType::orbit) {
    // Locating a shot is a few dozen height queries, against thousands of rays to simulate it,
    // so the whole orbit is screened here to know the records before anything is written.
    for (std::int64_t shot = 0; shot < sequence_length_; ++shot)
      if (locate_shot(shot).on_terrain) kept_shots_.push_back(shot);
    if (kept_shots_.empty()) {
      char rate[32];
      std::snprintf(rate, sizeof rate, "%g", settings_.rate_hz);
      throw setting_error(ErrorKind::input, "",
                          "the orbit never meets the terrain: none of its " +
                              std::to_string(sequence_length_) + " shots from " +
                              format_iso8601_utc(settings_.start_time_s) + " at " + rate +
                              " Hz falls on it");
    }
    return;
  }
  // A track whose every shot misses the terrain is a mistake (the wrong place or the wrong DEM),
  // not a product of flagged shots. The first shot usually meets it, so this costs one shot.
  for (std::int64_t shot = 0; shot < sequence_length_; ++shot)
    if (locate_shot(shot).on_terrain) return;
  throw setting_error(ErrorKind::input, "",
                      "the track never meets the terrain: none of its " +
                          std::to_string(sequence_length_) +
                          " shots' beams reaches ground with data");
}

// Every shot's time within the years a track may have (core/glas_time.hpp): the products'
// times and coverage attributes are written from them. An ephemeris file's rows are checked as
// they are read.
void Track::check_times() const {
  if (settings_.type == TrackType::granule) {
    for (const GranuleShot& shot : granule_)
      if (const std::string why = time_out_of_range(shot.time_s); !why.empty())
        throw input_error(settings_.granule,
                          "shot_number " + std::to_string(shot.shot_number) + ": its time " + why);
    return;
  }
  if (settings_.type == TrackType::ephemeris || sequence_length_ < 1) return;
  const double last_s =
      settings_.start_time_s + static_cast<double>(sequence_length_ - 1) / settings_.rate_hz;
  if (const std::string why = time_out_of_range(last_s); !why.empty())
    throw setting_error(ErrorKind::config, "rate_hz",
                        "too low: the last of the " + std::to_string(sequence_length_) +
                            " shots from start_time comes at a time that " + why);
}

namespace {

// Whether two passes differ in more than their start and heading.
bool same_but_place(TrackSettings a, const TrackSettings& b) {
  a.start_lat_deg = b.start_lat_deg;
  a.start_lon_deg = b.start_lon_deg;
  a.heading_deg = b.heading_deg;
  return a.type == TrackType::pass && b.type == TrackType::pass && a.shots == b.shots &&
         a.rate_hz == b.rate_hz && a.start_time_s == b.start_time_s &&
         a.altitude_m == b.altitude_m && a.spacing_m == b.spacing_m &&
         a.off_nadir_deg == b.off_nadir_deg && a.pointing_azimuth_deg == b.pointing_azimuth_deg;
}

const TrackSettings& first_pass(const std::vector<BeamPass>& beams) {
  if (beams.empty()) throw std::invalid_argument("a pass of several beams needs a beam");
  for (const BeamPass& beam : beams)
    if (!same_but_place(beam.pass, beams.front().pass))
      throw std::invalid_argument(
          "the beams of one pass must be passes differing only in their start and heading");
  return beams.front().pass;
}

}  // namespace

Track::Track(const std::vector<BeamPass>& beams, const Terrain& terrain,
             const TerrainLimits& limits)
    : Track(first_pass(beams), terrain, limits) {
  beams_ = beams;
}

std::int64_t Track::size() const {
  return settings_.type == TrackType::orbit ? static_cast<std::int64_t>(kept_shots_.size())
                                            : sequence_length_ * beams_per_shot();
}

std::int64_t Track::largest_source_shot_number() const {
  std::int64_t largest = std::max<std::int64_t>(0, sequence_length_ - 1);
  if (settings_.type == TrackType::granule)
    for (const GranuleShot& g : granule_) largest = std::max(largest, g.shot_number);
  return largest;
}

std::int64_t Track::shot_number(std::int64_t record) const {
  return settings_.type == TrackType::orbit ? kept_shots_.at(static_cast<std::size_t>(record))
                                            : record / beams_per_shot();
}

std::pair<std::int64_t, std::int64_t> Track::records_of_shots(std::int64_t first_shot,
                                                              std::int64_t last_shot) const {
  first_shot = std::clamp<std::int64_t>(first_shot, 0, sequence_length_);
  last_shot = std::clamp<std::int64_t>(last_shot, first_shot, sequence_length_);
  if (settings_.type != TrackType::orbit)
    return {first_shot * beams_per_shot(), last_shot * beams_per_shot()};
  const auto first = std::lower_bound(kept_shots_.begin(), kept_shots_.end(), first_shot);
  const auto last = std::lower_bound(first, kept_shots_.end(), last_shot);
  return {first - kept_shots_.begin(), last - kept_shots_.begin()};
}

std::vector<Footprint> Track::footprints(std::int64_t first_record,
                                         std::int64_t last_record) const {
  last_record = std::min(last_record, size());
  std::vector<Footprint> out;
  for (std::int64_t record = std::max<std::int64_t>(first_record, 0); record < last_record;
       ++record)
    out.push_back(footprint(record));
  return out;
}

bool Track::place_spacecraft(std::int64_t shot, int beam, Footprint& f) const {
  switch (settings_.type) {
    case TrackType::pass: {
      const TrackSettings& pass =
          beams_.empty() ? settings_ : beams_.at(static_cast<std::size_t>(beam)).pass;
      double lat_deg = 0.0, lon_deg = 0.0;
      GeographicLib::Geodesic::WGS84().Direct(
          pass.start_lat_deg, pass.start_lon_deg, pass.heading_deg,
          static_cast<double>(shot) * pass_spacing_m_, lat_deg, lon_deg);
      f.spacecraft = {lat_deg, lon_deg, settings_.altitude_m};
      f.spacecraft_ecef = ecef_from_geodetic(f.spacecraft);
      break;
    }
    case TrackType::points:
    case TrackType::granule: {
      const GroundPoint& point = settings_.points.at(static_cast<std::size_t>(shot));
      const double height_m = terrain_.height_m(point.lat_deg, point.lon_deg);
      // No ground under the target: the spacecraft is placed as if the ground were the ellipsoid,
      // and the shot is flagged.
      const Vec3 target = ecef_from_geodetic(
          {point.lat_deg, point.lon_deg, std::isfinite(height_m) ? height_m : 0.0});
      f.spacecraft_ecef = aim_at(target, settings_.altitude_m, settings_.off_nadir_deg,
                                 settings_.pointing_azimuth_deg);
      f.spacecraft = geodetic_from_ecef(f.spacecraft_ecef);
      f.beam_ecef = normalized(target - f.spacecraft_ecef);
      return std::isfinite(height_m);
    }
    case TrackType::orbit: {
      f.spacecraft_ecef = orbit_->ecef_position_m(f.time_s);
      f.spacecraft = geodetic_from_ecef(f.spacecraft_ecef);
      break;
    }
    case TrackType::ephemeris: {
      const EphemerisRow& row = ephemeris_.at(static_cast<std::size_t>(shot));
      f.time_s = row.time_s;
      f.spacecraft_ecef = row.spacecraft_ecef;
      f.spacecraft = geodetic_from_ecef(f.spacecraft_ecef);
      if (row.pointing_ecef) {
        f.beam_ecef = *row.pointing_ecef;
        f.off_nadir_deg = off_nadir_angle_deg(f.spacecraft_ecef, f.beam_ecef);
        return true;
      }
      break;
    }
  }
  f.beam_ecef =
      pointing_direction(f.spacecraft, settings_.off_nadir_deg, settings_.pointing_azimuth_deg);
  return true;
}

int Track::beam_index(int beam) const {
  if (beams_.empty()) return 0;
  for (std::size_t k = 0; k < beams_.size(); ++k)
    if (beams_[k].beam == beam) return static_cast<int>(k);
  throw std::out_of_range("beam " + std::to_string(beam) + " does not fly this pass");
}

Footprint Track::locate_shot(std::int64_t shot, int beam) const {
  Footprint f;
  f.shot_number = shot;
  f.source_shot_number = shot;
  f.time_s = settings_.start_time_s + static_cast<double>(shot) / settings_.rate_hz;
  if (settings_.type == TrackType::granule) {
    const GranuleShot& g = granule_.at(static_cast<std::size_t>(shot));
    f.source_shot_number = g.shot_number;
    f.time_s = g.time_s;
    f.beam = g.beam;
    f.degrade_flag = g.degrade_flag;
    f.record_index = g.record_index;
    f.shot_count = g.shot_count;
    if (gedi_coverage_beam(g.beam)) f.pulse_energy_scale = 0.5;
  }
  if (!beams_.empty()) f.beam = beams_.at(static_cast<std::size_t>(beam)).beam;
  f.off_nadir_deg = settings_.off_nadir_deg;
  if (!place_spacecraft(shot, beam, f)) return f;
  if (const auto hit = intersect_terrain(terrain_, f.spacecraft_ecef, f.beam_ecef, limits_)) {
    f.on_terrain = true;
    f.ground = geodetic_from_ecef(*hit);
    f.range_m = norm(*hit - f.spacecraft_ecef);
  }
  return f;
}

}  // namespace glaswave
