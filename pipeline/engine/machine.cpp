// What the machine gives a run (its cores, its memory) and what a run or `brf` will take of it,
// estimated from the configuration before anything is allocated.
#include "pipeline/engine/machine.hpp"

#include <sched.h>
#include <sys/resource.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <vector>

#include "core/error.hpp"
#include "footprints/ephemeris.hpp"
#include "footprints/track.hpp"
#include "pipeline/config/json_reader.hpp"
#include "pipeline/engine/inputs.hpp"
#include "pipeline/engine/rami_measurements.hpp"
#include "pipeline/products/ogr_writer.hpp"
#include "pipeline/shot/brf_shot.hpp"
#include "pipeline/shot/footprint_geometry.hpp"
#include "pipeline/shot/photon_receiver.hpp"
#include "pipeline/shot/receiver.hpp"
#include "pipeline/shot/shot_simulator.hpp"
#include "pipeline/shot/stretch_scenes.hpp"
#include "pipeline/shot/vegetation_source.hpp"
#include "terrain/terrain.hpp"

namespace glaswave {
namespace {

constexpr double wgs84_equatorial_radius_m = 6378137.0;

// The highest the spacecraft flies: the track's altitude, an orbit's apogee, an ephemeris's
// highest row. An ephemeris that cannot be read is left to the track, which names its fault.
double highest_spacecraft_m(const Config& c) {
  const TrackSettings& t = c.track;
  if (t.type == TrackType::orbit)
    return t.orbit.semi_major_axis_m * (1.0 + t.orbit.eccentricity) - wgs84_equatorial_radius_m;
  if (t.type != TrackType::ephemeris || t.ephemeris.empty()) return t.altitude_m;
  double height_m = 0.0;
  try {
    for (const EphemerisRow& row : read_ephemeris(t.ephemeris))
      height_m = std::max(height_m, geodetic_from_ecef(row.spacecraft_ecef).h_m);
  } catch (const Error&) {
    return t.altitude_m;
  }
  return height_m;
}

// What a run's vegetation takes: a region `side_m` across (which every thread's shot holds),
// what its source holds once, the plants on the region where its source counts them (a forest's
// trees, for the message) and the bytes of one, and the key that makes it large. None without a
// canopy.
struct VegetationMemory {
  double region_bytes = 0.0, source_bytes = 0.0, trees = 0.0, tree_bytes = 0.0;
  std::string key = "/canopy", kind;
};

VegetationMemory vegetation_memory(const Config& c, double side_m) {
  VegetationMemory m;
  if (!c.canopy) return m;
  const VegetationSettings settings = vegetation_settings(c);
  m.region_bytes = vegetation_region_bytes(settings, side_m);
  m.source_bytes = vegetation_source_bytes(settings);
  m.key = vegetation_memory_key(settings);
  m.kind = c.canopy->kind;
  m.tree_bytes = vegetation_plant_bytes(settings);
  if (m.tree_bytes > 0.0) m.trees = m.region_bytes / m.tree_bytes;
  return m;
}

// A scene's vegetation in words: its plants where its source counts them (a forest's trees),
// else its source's bytes in a region; none on bare ground.
std::string scene_words(const std::string& kind, double trees, double tree_bytes,
                        double region_bytes, double side_m) {
  const std::string across = " over " + format_number(std::round(side_m)) + " m across";
  if (kind.empty()) return "no vegetation" + across;
  if (tree_bytes > 0.0)
    return format_number(std::round(trees)) + " trees" + across + ", at " +
           format_number(tree_bytes / 1024.0) + " KiB a tree";
  return mebibytes(region_bytes) + " of " + kind + across;
}

// The patch a shot's rays reach, as the shot layer sizes it before any terrain is opened: over a
// plane's slope (capped at 85 deg, where the patch is already 11 times as long) or level ground.
double shot_patch_half_size_m(const Config& c, double range_m) {
  const double slope_deg = c.terrain.plane ? std::min(c.terrain.plane->slope_deg, 85.0) : 0.0;
  return estimated_patch_half_size_m(range_m, c.sensor.ifov_rad, slope_deg, c.canopy.has_value());
}

// The cores this process may run on: a run's threads unless --threads says fewer.
int usable_cores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1u, std::thread::hardware_concurrency());
}

// The memory this process may have: the machine's, or less under a cgroup's limit or ulimit -v.
double available_memory_bytes() {
  double bytes = static_cast<double>(sysconf(_SC_PHYS_PAGES)) * sysconf(_SC_PAGE_SIZE);
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  std::string limit;
  if (cgroup >> limit && limit != "max") {
    double value = 0.0;
    const auto [end, error] = std::from_chars(limit.data(), limit.data() + limit.size(), value);
    if (error == std::errc() && value > 0.0) bytes = std::min(bytes, value);
  }
  rlimit address_space{};
  if (getrlimit(RLIMIT_AS, &address_space) == 0 && address_space.rlim_cur != RLIM_INFINITY)
    bytes = std::min(bytes, static_cast<double>(address_space.rlim_cur));
  return bytes;
}

std::string gibibytes(double bytes) {
  return format_number(std::round(bytes / 1073741824.0 * 10) / 10) + " GiB";
}

}  // namespace

int threads_of_process(int threads, int processes_here) {
  // More threads than cores would only wait for each other (and TBB would warn on stderr).
  const int cores = tbb::this_task_arena::max_concurrency();
  return threads > 0 ? std::min(threads, cores) : std::max(1, cores / std::max(1, processes_here));
}

// The ICESat-2 granules (ATL03, ATL08) hold every shot's photons and records until the run
// ends, to write them in beam groups: 0.8 kB a shot and beam, as issue 42 measured it (a run's
// peak RSS against its shots). A track whose shots are not known before it is planned (an
// ephemeris's or a granule's rows) counts none here.
constexpr double icesat2_bytes_per_shot = 800.0;

double icesat2_granule_bytes(const Config& c) {
  const OutputSettings& o = c.output;
  if (!receiver_traits(c.sensor.receiver).atlas_beams ||
      !(o.atl03.value_or(true) || o.atl08.value_or(true)))
    return 0.0;
  const TrackSettings& t = c.track;
  double shots = 0.0;
  if (t.type == TrackType::pass || t.type == TrackType::orbit) shots = double(t.shots);
  if (t.type == TrackType::points) shots = double(t.points.size());
  const double beams = t.type == TrackType::pass ? double(c.sensor.beams.size()) : 1.0;
  return icesat2_bytes_per_shot * shots * beams;
}

namespace {

// The area of the union of squares, on the grid their edges make.
double union_area_m2(const std::vector<RoughSquare>& squares) {
  std::vector<double> xs, ys;
  for (const RoughSquare& s : squares) {
    xs.insert(xs.end(), {s.x_m - s.half_size_m, s.x_m + s.half_size_m});
    ys.insert(ys.end(), {s.y_m - s.half_size_m, s.y_m + s.half_size_m});
  }
  std::sort(xs.begin(), xs.end());
  std::sort(ys.begin(), ys.end());
  double area_m2 = 0.0;
  for (std::size_t i = 0; i + 1 < xs.size(); ++i)
    for (std::size_t j = 0; j + 1 < ys.size(); ++j) {
      const double x = 0.5 * (xs[i] + xs[i + 1]), y = 0.5 * (ys[j] + ys[j + 1]);
      if (std::any_of(squares.begin(), squares.end(), [&](const RoughSquare& s) {
            return std::abs(x - s.x_m) < s.half_size_m && std::abs(y - s.y_m) < s.half_size_m;
          }))
        area_m2 += (xs[i + 1] - xs[i]) * (ys[j + 1] - ys[j]);
    }
  return area_m2;
}

// The triangles of a strip's ground: the terrain's mesh over the square holding the rectangle
// (cells of its detail, 2 to 4096 a side), the part within the rectangle kept, and the
// roughness's lattice under the beams (the finest whose nodes over each square stay within the
// limit, two triangles a cell), which Embree holds as grids.
StripGround strip_ground(const StripPlan& plan, const Terrain& terrain,
                         const RoughnessField& roughness) {
  const double side_m = 2.0 * plan.half_size_m;
  const double cells =
      std::clamp(std::ceil(side_m / terrain.detail_m()), 2.0, static_cast<double>(4096));
  const RegionStrip& r = plan.strip;
  const double kept = (r.along1_m - r.along0_m) * (r.across1_m - r.across0_m) / (side_m * side_m);
  StripGround ground;
  ground.terrain_triangles = 2.0 * cells * cells * std::min(1.0, kept);
  if (!roughness.enabled() || plan.rough.empty()) return ground;
  double widest_m = 0.0;
  for (const RoughSquare& square : plan.rough) widest_m = std::max(widest_m, square.half_size_m);
  double spacing_m = 0.0;
  for (const int nodes : RoughnessField::nodes_per_correlation) {
    spacing_m = roughness.correlation_m() / nodes;
    if (2.0 * widest_m / spacing_m + 1.0 <= RoughnessField::max_nodes_a_side) break;
  }
  ground.rough_triangles = 2.0 * union_area_m2(plan.rough) / (spacing_m * spacing_m);
  return ground;
}

}  // namespace

std::optional<SharedScenes> shared_scenes(const ShotSimulator& simulator, const Track& track) {
  const StretchScenes* strips = simulator.stretches();
  if (!strips || strips->shape() != StretchShape::strip) return std::nullopt;
  SharedScenes shared;
  shared.shots = std::min(strips->shots(), track.sequence_length());
  // The strips of the track's first, middle and last records: an orbit's time sequence runs
  // mostly off the terrain, where no strip is built.
  std::vector<std::int64_t> stretches;
  for (const std::int64_t record : {std::int64_t{0}, track.size() / 2, track.size() - 1})
    stretches.push_back(track.shot_number(record) / strips->shots());
  const std::int64_t per_beam = stretches.back() - stretches.front() + 1;
  shared.held = static_cast<double>(std::min<std::int64_t>(
      static_cast<std::int64_t>(strips->kept()), per_beam * track.beams_per_shot()));
  // The largest of each beam's first, middle and last strips (a slope widens the patches).
  const VegetationSource* vegetation = simulator.vegetation();
  double largest_m2 = -1.0;
  for (int beam = 0; beam < static_cast<int>(track.beams_per_shot()); ++beam)
    for (const std::int64_t stretch : stretches) {
      const std::optional<StripPlan> plan = strips->plan_strip(beam, stretch);
      if (!plan) continue;
      const RegionStrip& r = plan->strip;
      const double area_m2 = (r.along1_m - r.along0_m) * (r.across1_m - r.across0_m);
      if (area_m2 <= largest_m2) continue;
      largest_m2 = area_m2;
      shared.length_m = r.along1_m - r.along0_m;
      shared.width_m = r.across1_m - r.across0_m;
      shared.vegetation_side_m = vegetation && !vegetation->grows_within_strips()
                                     ? 2.0 * plan->half_size_m
                                     : std::sqrt(area_m2);
      shared.ground =
          strip_ground(*plan, simulator.scenes().terrain(), simulator.scenes().roughness());
    }
  if (largest_m2 < 0.0) return std::nullopt;
  return shared;
}

RunMemory estimate_run_memory(const Config& c, const SharedScenes* shared) {
  RunMemory m;
  const double range_m =
      highest_spacecraft_m(c) / std::cos(c.track.off_nadir_deg * std::numbers::pi / 180.0);
  m.scene_half_size_m = shot_patch_half_size_m(c, range_m);
  const VegetationMemory vegetation =
      vegetation_memory(c, shared ? shared->vegetation_side_m : 2.0 * m.scene_half_size_m);
  m.trees = vegetation.trees;
  m.tree_bytes = vegetation.tree_bytes;
  m.scene_bytes = vegetation.region_bytes;
  m.source_bytes = vegetation.source_bytes;
  m.vegetation = vegetation.kind;
  m.waveform_bytes = shot_size(c).bytes * shot_waveform_copies;
  m.threads = usable_cores();
  m.scenes = m.threads;
  if (shared) {
    m.strips = *shared;
    m.scenes = shared->held;
    m.ground_bytes = shared->ground.terrain_triangles * ground_triangle_bytes +
                     shared->ground.rough_triangles * rough_triangle_bytes;
  }
  m.granule_bytes = icesat2_granule_bytes(c);
  m.program_bytes = program_resident_bytes;
  const double scenes_bytes = m.scenes * (m.scene_bytes + m.ground_bytes);
  m.bytes = m.program_bytes + m.source_bytes + m.granule_bytes + scenes_bytes +
            m.threads * m.waveform_bytes;
  m.available_bytes = available_memory_bytes();
  // The key to change: the vegetation's when what its source holds weighs most, or when its
  // region does on a scene of a usual size; the waveforms when they weigh most; else what makes
  // the scene wide.
  if (m.granule_bytes > m.source_bytes + scenes_bytes + m.threads * m.waveform_bytes)
    m.place = "/track/shots";
  else if (m.source_bytes > scenes_bytes + m.threads * m.waveform_bytes)
    m.place = vegetation.key;
  else if (m.waveform_bytes > m.scene_bytes)
    m.place = "/sensor/bins";
  else if (m.scene_half_size_m < 1000.0)
    m.place = vegetation.key;
  else if (range_m > 2.0e6)
    m.place = c.track.type == TrackType::orbit       ? "/track/semi_major_axis_m"
              : c.track.type == TrackType::ephemeris ? "/track/ephemeris"
                                                     : "/track/altitude_m";
  else
    m.place = "/sensor/ifov_rad";
  return m;
}

// The photon-counting receiver draws every background photon of a shot's window (a time, a
// channel, the dead time, a record in the granules): about 0.2 us each, so 10^6 MHz over ATLAS's
// 500 ns window is 0.1 s a shot, minutes a pass. The sun's rate is bounded by its worst case:
// overhead, over a white scene. The sun at ATLAS's 500 ns gives a few photons; 10^4 cost about
// 2 ms a shot.
constexpr double max_background_photons = 1.0e4;

void check_background(const Config& c) {
  if (c.sensor.bands.empty()) return;
  const ReceiverSettings settings = receiver_settings(c);  // photons for ATLAS's beams alone
  const double window_ns = static_cast<double>(c.sensor.bins) * c.sensor.bin_ns;
  for (const PhotonCountingSettings& p : settings.photons) {
    const double rate_Hz = most_background_rate_Hz(settings, p);
    const double photons = rate_Hz * window_ns * 1e-9;
    if (photons <= max_background_photons) continue;
    const bool sun = p.background == BackgroundSource::sun;
    throw config_error(
        sun ? "/sensor/filter_bandwidth_nm" : "/simulation/background/rate_MHz",
        std::string(sun ? "the sun overhead over a white scene" : "the background rate") +
            " gives " + format_number(std::round(rate_Hz * 1e-6)) +
            " MHz: " + format_number(std::round(photons)) +
            " background photons in a shot's window of " + format_number(window_ns) +
            " ns, more than the limit of " + format_number(max_background_photons) + " a shot");
  }
}

void check_run_memory(const RunMemory& memory) {
  if (memory.bytes <= memory.available_bytes) return;
  std::ostringstream why;
  why << "a run would hold about " << gibibytes(memory.bytes) << " (";
  if (memory.strips) {
    const SharedScenes& strips = *memory.strips;
    why << format_number(memory.scenes) << " strips' scenes of " << strips.shots << " shots, each "
        << scene_words(memory.vegetation, memory.trees, memory.tree_bytes, memory.scene_bytes,
                       strips.vegetation_side_m)
        << " (a rectangle " << format_number(std::round(strips.length_m)) << " by "
        << format_number(std::round(strips.width_m)) << " m) and its ground's "
        << mebibytes(memory.ground_bytes) << "; " << memory.threads
        << " threads x a shot's waveforms' " << mebibytes(memory.waveform_bytes);
  } else {
    why << memory.threads << " threads x a shot's scene of "
        << scene_words(memory.vegetation, memory.trees, memory.tree_bytes, memory.scene_bytes,
                       2.0 * memory.scene_half_size_m)
        << ", and its waveforms' " << mebibytes(memory.waveform_bytes);
  }
  if (memory.source_bytes > 0.0)
    why << "; the " << memory.vegetation << " source's " << mebibytes(memory.source_bytes)
        << " once";
  if (memory.granule_bytes > 0.0)
    why << "; the ICESat-2 granules' photons, " << mebibytes(memory.granule_bytes)
        << " held to the end";
  why << "), more than the " << gibibytes(memory.available_bytes)
      << " of memory this process may have";
  throw config_error(memory.place, why.str());
}

void check_run(const Config& config) {
  check_background(config);
  check_run_memory(estimate_run_memory(config));
  check_outputs(config);
  if (config.output.footprints) {
    std::vector<std::string> band_names;
    for (const LidarBand& band : config.sensor.bands) band_names.push_back(band.name);
    check_footprint_properties(band_names, config.output.footprints_format == "GPKG"
                                               ? FootprintsFormat::gpkg
                                               : FootprintsFormat::geojson);
  }
}

BrfMemory estimate_brf_memory(const Config& c) {
  BrfMemory m;
  m.pixels = c.brf.pixels();
  const double tile_m = m.pixels * c.brf.image_resolution_m;
  m.scene_side_m = 2.0 * brf_scene_half_size_m(0.5 * tile_m, c.terrain.plane.has_value());
  const VegetationMemory vegetation = vegetation_memory(c, m.scene_side_m);
  m.trees = vegetation.trees;
  m.tree_bytes = vegetation.tree_bytes;
  m.scene_bytes = vegetation.region_bytes + vegetation.source_bytes;
  m.vegetation = vegetation.kind;
  m.image_bytes = static_cast<double>(c.sensor.bands.size()) * m.pixels * m.pixels * 8.0 *
                  run_limits::brf_image_copies;
  m.program_bytes = program_resident_bytes;
  m.bytes = m.program_bytes + m.scene_bytes + m.image_bytes;
  m.available_bytes = available_memory_bytes();
  // The key to change: the pixels when the image weighs most, else the tile when it is wide,
  // else the vegetation that crowds it.
  m.place = m.image_bytes > m.scene_bytes ? "/brf/image_resolution_m"
            : tile_m > 1000.0             ? "/brf/scene_size_m"
                                          : vegetation.key;
  return m;
}

void check_brf(const Config& config) {
  const BrfSettings& b = config.brf;
  if (b.rami) check_rami_request(*b.rami, config.sensor.bands.size());
  const double pixels = b.pixels();
  if (pixels > run_limits::brf_image_pixels)
    throw config_error("/brf/image_resolution_m",
                       "scene.tif would be " + format_number(pixels) + " pixels across (" +
                           format_number(b.scene_size_m) + " m at " +
                           format_number(b.image_resolution_m) + " m a pixel); at most " +
                           format_number(run_limits::brf_image_pixels));
  const BrfMemory memory = estimate_brf_memory(config);
  if (memory.bytes <= memory.available_bytes) return;
  std::ostringstream why;
  why << "brf's scene would hold about " << gibibytes(memory.bytes) << " ("
      << scene_words(memory.vegetation, memory.trees, memory.tree_bytes, memory.scene_bytes,
                     memory.scene_side_m)
      << ", and scene.tif's " << config.sensor.bands.size() << " bands of "
      << format_number(memory.pixels) << " x " << format_number(memory.pixels) << " pixels, "
      << mebibytes(memory.image_bytes) << "), more than the " << gibibytes(memory.available_bytes)
      << " of memory this process may have";
  throw config_error(memory.place, why.str());
}

std::optional<Error> brf_tile_error(const Config& config, const Terrain& terrain,
                                    const Footprint& footprint) {
  // The layers are level: so must a periodic tile under them be.
  if (config.terrain.plane && config.atmosphere && config.terrain.plane->slope_deg != 0.0)
    return config_error(
        "/terrain/plane/slope_deg",
        "brf through the atmosphere's layers needs a level plane (its periodic tile "
        "under level layers cannot slope), got " +
            format_number(config.terrain.plane->slope_deg) + " degrees; a level plane, or a DEM");
  if (config.terrain.plane) return std::nullopt;  // a plane is everywhere, and its tile periodic
  const double tile_half_size_m = config.brf.tile_half_size_m();
  const auto off = tile_off_terrain(terrain, LocalFrame(footprint.ground), tile_half_size_m);
  if (!off) return std::nullopt;
  char where[96];
  std::snprintf(where, sizeof where, "%.0f m %s and %.0f m %s of it", std::abs((*off)[0]),
                (*off)[0] < 0.0 ? "west" : "east", std::abs((*off)[1]),
                (*off)[1] < 0.0 ? "south" : "north");
  return config_error("/brf/scene_size_m",
                      "the tile of " + format_number(2.0 * tile_half_size_m) +
                          " m around the track's first footprint reaches beyond the terrain's "
                          "data (none at " +
                          where +
                          "): the sunlight falling there would be lost, not reflected; a smaller "
                          "tile, or a terrain that covers it");
}

}  // namespace glaswave
