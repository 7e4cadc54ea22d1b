// The shots of a track: where the spacecraft is, where the laser points, and where the beam
// axis meets the terrain (the footprint centre), as GLAS geolocation did.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "footprints/ephemeris.hpp"
#include "footprints/granule.hpp"
#include "footprints/orbit.hpp"
#include "footprints/terrain_intersection.hpp"
#include "footprints/track_settings.hpp"
#include "terrain/local_frame.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {

struct Footprint {
  std::int64_t shot_number = 0;
  // The instrument's own number of the shot: a granule's (GEDI shot_number, GLAH14
  // i_rec_ndx * 40 + i_shot_count - 1); shot_number for the synthetic tracks.
  std::int64_t source_shot_number = 0;
  double time_s = 0.0;  // seconds since 2000-01-01T12:00:00Z
  // A granule's beam (GEDI: its number, BEAM0101 is 5; -1 for GLAH14 and the synthetic tracks;
  // a pass of several beams: the beam's BeamPass::beam, ATLAS's spot number) and degrade_flag;
  // GLAH14's i_rec_ndx and i_shot_count (-1 and 0 elsewhere).
  int beam = -1;
  std::uint8_t degrade_flag = 0;
  std::int64_t record_index = -1;
  int shot_count = 0;
  // The pulse energy against the sensor's: 0.5 on GEDI's coverage beams, each half a laser's
  // pulse (https://gedi.umd.edu/instrument/specifications/: three 10 mJ lasers, one split in two).
  double pulse_energy_scale = 1.0;
  Geodetic spacecraft;
  Vec3 spacecraft_ecef{};
  Vec3 beam_ecef{};  // unit vector of the beam axis, spacecraft -> ground
  double off_nadir_deg = 0.0;
  bool on_terrain = false;  // false: the beam axis never met the terrain (flagged shot)
  Geodetic ground;          // footprint centre, when on_terrain
  double range_m = 0.0;     // spacecraft to footprint centre, when on_terrain
};

// Unit vector (ECEF) of a beam tilted `off_nadir_deg` from the geodetic nadir at the
// spacecraft, toward the azimuth `pointing_azimuth_deg` (clockwise from north).
Vec3 pointing_direction(const Geodetic& spacecraft, double off_nadir_deg,
                        double pointing_azimuth_deg);

// Angle (deg) between a beam direction and the geodetic nadir at the spacecraft.
double off_nadir_angle_deg(const Vec3& spacecraft_ecef, const Vec3& beam_ecef);

// One beam of a pass flown by several at once (ICESat-2's six, footprints/atlas_beams.hpp): its
// own pass (the shared pass moved to the beam's start and heading) and the number its footprints
// carry as Footprint::beam.
struct BeamPass {
  TrackSettings pass;
  int beam = -1;
};

// A planned track. Shot numbers count the track's shots in time order, from 0:
//   pass, points  shot k is the k-th shot of `track.shots` (the k-th point), at start_time + k /
//   rate_hz; orbit         shot k is at start_time + k / rate_hz, k < track.shots; only the shots
//   whose
//                 footprint falls on the terrain become records, the others are skipped;
//   ephemeris     shot k is the file's k-th row, at its time;
//   granule       shot k is the granule's k-th footprint with a position (beam by beam), at its
//                 time, aimed at its latitude and longitude as a point is.
// A shot number is the same whichever part of the track a run simulates (`--shots A:B`).
// Records are the shots a run writes, in shot order: every shot of pass, points and ephemeris
// (those that miss the terrain flagged), the kept shots of an orbit. A pass flown by several
// beams has one record per shot and beam, a shot's beams together in the beams' order: record
// shot * beams + k is shot `shot` of beam k.
class Track {
 public:
  // Plans the geometry (no simulation): reads an ephemeris file and, for an orbit, locates every
  // shot to keep those on the terrain. The terrain must outlive the track.
  // Throws an input Error when no shot of the track meets the terrain, or for a bad ephemeris file.
  Track(const TrackSettings& settings, const Terrain& terrain, const TerrainLimits& limits = {});
  // A pass flown by every beam of `beams` at once: each its own pass (type pass, all with the
  // same shots, rate, times and altitude), its footprints carrying its number. Throws
  // std::invalid_argument when there is no beam or a beam's pass differs in more than its place.
  Track(const std::vector<BeamPass>& beams, const Terrain& terrain,
        const TerrainLimits& limits = {});

  // Number of records.
  std::int64_t size() const;
  // Number of shot numbers in the track's time sequence (shot numbers are below it).
  std::int64_t sequence_length() const { return sequence_length_; }
  // The shot number of a record, 0 <= record < size().
  std::int64_t shot_number(std::int64_t record) const;
  // The records [first, last) whose shot numbers lie in [first_shot, last_shot).
  std::pair<std::int64_t, std::int64_t> records_of_shots(std::int64_t first_shot,
                                                         std::int64_t last_shot) const;
  // What the planning found that a user should know (a granule's skipped footprints), one line
  // each.
  const std::vector<std::string>& warnings() const { return warnings_; }

  // The largest instrument's shot number of the track (Footprint::source_shot_number): a
  // granule's, or the sequence's last.
  std::int64_t largest_source_shot_number() const;

  // The beams that fire each shot: 1 but for a pass flown by several.
  std::int64_t beams_per_shot() const {
    return beams_.empty() ? 1 : static_cast<std::int64_t>(beams_.size());
  }

  // The footprint of a record, and of the records [first, last).
  Footprint footprint(std::int64_t record) const {
    return locate_shot(shot_number(record), static_cast<int>(record % beams_per_shot()));
  }
  std::vector<Footprint> footprints(std::int64_t first_record, std::int64_t last_record) const;
  // The footprint of any shot of the sequence, kept or not, 0 <= shot_number < sequence_length(),
  // by the beam of index `beam` (0 <= beam < beams_per_shot()).
  Footprint locate_shot(std::int64_t shot_number, int beam = 0) const;
  // The index of the beam whose footprints carry `beam` (Footprint::beam), for locate_shot: 0 on
  // a track of one beam. Throws std::out_of_range for a beam the pass has not.
  int beam_index(int beam) const;

 private:
  // Refuses a shot whose time is not finite or outside the years a track may have.
  void check_times() const;
  // The spacecraft and the beam of a shot; false when the shot is flagged before any search for
  // the ground (a target point over no data).
  bool place_spacecraft(std::int64_t shot, int beam, Footprint& f) const;

  TrackSettings settings_;
  const Terrain& terrain_;
  TerrainLimits limits_;
  std::int64_t sequence_length_ = 0;
  std::unique_ptr<Orbit> orbit_;         // orbit
  std::vector<EphemerisRow> ephemeris_;  // ephemeris
  std::vector<GranuleShot> granule_;     // granule
  std::vector<std::string> warnings_;
  std::vector<std::int64_t> kept_shots_;  // orbit: shot numbers of the records, ascending
  double pass_spacing_m_ = 0.0;           // pass
  std::vector<BeamPass> beams_;           // a pass flown by several beams; empty otherwise
};

}  // namespace glaswave
