// One ray of one shot, re-run alone for --debug-ray.
#include "pipeline/engine/ray_debug.hpp"

#include <memory>

#include "core/error.hpp"
#include "footprints/track.hpp"
#include "pipeline/engine/inputs.hpp"

namespace glaswave {

RayDebug debug_ray(const Config& config, std::int64_t shot_number, std::int64_t ray,
                   const RayObserver& observer) {
  const std::unique_ptr<Terrain> terrain = open_terrain(config);
  const std::unique_ptr<Track> planned = plan_track(config, *terrain);
  const Track& track = *planned;
  const auto [first, last] = track.records_of_shots(shot_number, shot_number + 1);
  if (shot_number < 0 || first >= last)
    throw config_error(
        "--debug-ray",
        "shot " + std::to_string(shot_number) + " is not a shot of the track (shot numbers 0 to " +
            std::to_string(track.sequence_length() - 1) +
            (track.size() < track.sequence_length() ? ", those on the terrain only)" : ")"));
  const std::int64_t rays = config.simulation.rays_per_shot;
  if (ray < 0 || ray >= rays)
    throw config_error("--debug-ray", "ray " + std::to_string(ray) + " is not one of the shot's " +
                                          std::to_string(rays) + " rays (0 to " +
                                          std::to_string(rays - 1) + ")");
  const std::unique_ptr<ShotSimulator> simulator = make_shot_simulator(config, *terrain);
  simulator->share_scenes_along(track);  // the ray as it ran in the shot
  RayDebug debug;
  debug.shot_number = shot_number;
  debug.ray = ray;
  debug.rays_per_shot = rays;
  for (const LidarBand& band : config.sensor.bands) debug.band_names.push_back(band.name);
  std::optional<ShotWaveforms> waveforms = at_section("/terrain", [&, record = first] {
    return simulator->simulate_ray(track.footprint(record), ray, observer);
  });
  if (!waveforms)
    throw config_error("--debug-ray", "shot " + std::to_string(shot_number) +
                                          " is flagged: its beam does not fall on the terrain's "
                                          "data, so it has no rays");
  debug.waveforms = std::move(*waveforms);
  return debug;
}

}  // namespace glaswave
