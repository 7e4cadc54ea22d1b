// `glaswave check`'s outline of a run, read from the resolved configuration (every default filled
// in, as the products' `config` attribute holds it) and the engine's estimates.
#include "pipeline/app/run_outline.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/engine/machine.hpp"

namespace glaswave {
namespace {

using nlohmann::json;

// A number as a person writes it: at most `digits` significant digits, no trailing zeros.
std::string number(double value, int digits = 3) {
  char text[64];
  std::snprintf(text, sizeof text, "%.*g", digits, value);
  return text;
}

std::string plural(double count, const std::string& one, const std::string& many) {
  return number(count, 12) + " " + (count == 1 ? one : many);
}

std::string duration(double seconds) {
  if (seconds < 1.0) return "under a second";
  if (seconds < 120.0) return "about " + number(seconds, 2) + " s";
  if (seconds < 7200.0) return "about " + number(seconds / 60.0, 2) + " min";
  if (seconds < 2.0 * 86400.0) return "about " + number(seconds / 3600.0, 2) + " h";
  return "about " + number(seconds / 86400.0, 2) + " days";
}

std::string bytes(double value) {
  if (value < 1024.0 * 1024.0 * 1024.0) return number(value / (1024.0 * 1024.0), 3) + " MiB";
  return number(value / (1024.0 * 1024.0 * 1024.0), 3) + " GiB";
}

// A value of the resolved configuration: a string as it is, anything else as JSON.
std::string text(const json& value) {
  return value.is_string() ? value.get<std::string>() : value.dump();
}

// A per-band value (a number or an object keyed by band) in a few characters.
std::string per_band(const json& value) {
  if (!value.is_object()) return text(value);
  std::string out;
  for (const auto& [band, v] : value.items())
    out += (out.empty() ? "" : ", ") + band + ": " + text(v);
  return out;
}

// The spacecraft's height above the ground, roughly: an orbit's from its semi-major axis.
double height_m(const json& track) {
  if (track.value("type", "pass") == "orbit")
    return track.value("semi_major_axis_m", 6978137.0) - 6378137.0;
  return track.value("altitude_m", 600000.0);
}

std::string track_line(const json& track, const CheckSummary& summary) {
  const std::string type = track.value("type", "pass");
  std::string line = type;
  if (type == "pass") {
    line += " from " + number(track.value("start_lat_deg", 0.0), 7) + ", " +
            number(track.value("start_lon_deg", 0.0), 7) + " heading " +
            number(track.value("heading_deg", 0.0)) + " deg";
    if (track.contains("spacing_m") && track["spacing_m"].is_number())
      line += ", shots " + number(track["spacing_m"].get<double>()) + " m apart";
  } else if (type == "granule" || type == "ephemeris") {
    line += " " + text(track.value(type == "granule" ? "file" : "ephemeris", json("")));
  }
  if (type == "orbit")
    line += " of " + number(track.value("inclination_deg", 0.0)) + " deg inclination, from about " +
            number(height_m(track) / 1000.0) + " km";
  else
    line += ", from " + number(height_m(track) / 1000.0) + " km";
  if (track.value("off_nadir_deg", 0.0) != 0.0)
    line += ", " + number(track.value("off_nadir_deg", 0.0)) + " deg off nadir";
  line += ": " + plural(static_cast<double>(summary.shots), "shot", "shots");
  if (summary.shots_off_terrain > 0)
    line += " (" + number(static_cast<double>(summary.shots_off_terrain), 12) +
            " off the terrain, flagged)";
  return line;
}

std::string sensor_line(const json& sensor, const json& track) {
  std::string line = sensor.contains("preset") ? text(sensor["preset"]) : "custom";
  std::vector<std::string> bands;
  for (const json& band : sensor.value("bands", json::array()))
    bands.push_back(number(band.value("wavelength_nm", 0.0), 6));
  line += ", " + plural(static_cast<double>(bands.size()), "band", "bands") + " (";
  for (std::size_t i = 0; i < bands.size(); ++i) line += (i ? ", " : "") + bands[i];
  line += " nm)";
  // The beam's 1/e^2 diameter on level ground below, 4 sigma_theta H: a uniform beam's edge.
  const double diameter_m = 4.0 * sensor.value("divergence_sigma_rad", 0.0) * height_m(track);
  const bool uniform = sensor.value("beam_profile", "gaussian") == "uniform";
  line += std::string(uniform ? ", a uniform beam about " : ", a beam about ") +
          number(std::round(diameter_m), 12) + (uniform ? " m across, " : " m across at 1/e2, ") +
          number(sensor.value("bins", 0.0), 12) + " bins of " +
          number(sensor.value("bin_ns", 1.0)) + " ns";
  return line;
}

// The layers and each band's two-way transmission through their column.
std::string atmosphere_line(const Config& config) {
  const AtmosphereSettings& a = *config.atmosphere;
  std::string line = (a.preset.empty() ? std::string("") : a.preset + ", ") +
                     plural(static_cast<double>(a.layers.size()), "layer", "layers") +
                     ", two-way transmission";
  for (std::size_t b = 0; b < config.sensor.bands.size(); ++b)
    line += (b ? ", " : " ") + number(config.sensor.bands[b].atmos_transmission_roundtrip, 2) +
            " (" + config.sensor.bands[b].name + ")";
  return line;
}

std::string terrain_line(const json& terrain) {
  std::string line;
  if (terrain.contains("dem")) {
    const std::string datum = text(terrain.value("vertical_datum", json("ellipsoid")));
    line = "DEM " + std::filesystem::path(text(terrain["dem"])).filename().string() +
           " (heights above " +
           (datum == "ellipsoid" ? std::string("the WGS84 ellipsoid")
            : datum == "egm96"   ? std::string("the EGM96 geoid")
                                 : datum) +
           ")";
  } else {
    const json plane = terrain.value("plane", json::object());
    line = "plane at " + number(plane.value("elevation_m", 0.0)) + " m, slope " +
           number(plane.value("slope_deg", 0.0)) + " deg facing " +
           number(plane.value("aspect_deg", 0.0)) + " deg";
  }
  const json roughness = terrain.value("roughness", json::object());
  if (roughness.value("rms_m", 0.0) > 0.0)
    line += ", roughness " + number(roughness.value("rms_m", 0.0)) + " m RMS over " +
            number(roughness.value("correlation_m", 0.0)) + " m";
  line += ", soil reflectance " + per_band(terrain.value("soil_reflectance", json(0.15)));
  return line;
}

std::string vegetation_line(const json& canopy) {
  if (canopy.is_null()) return "none (bare ground)";
  auto file_name = [](const json& path) {
    return std::filesystem::path(text(path)).filename().string();
  };
  if (canopy.contains("facets")) {
    // Facet trees: their models, meshes or disc leaves, and the file that places them.
    const json& facets = canopy["facets"];
    int meshes = 0, discs = 0;
    const json models = facets.value("models", json::object());
    for (const auto& [name, file] : models.items()) {
      std::string extension = std::filesystem::path(text(file)).extension().string();
      for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      ++(extension == ".def" ? discs : meshes);
    }
    std::string line = "facet trees from " + file_name(facets.value("trees_file", json(""))) +
                       ": " + std::to_string(meshes) + " mesh model" + (meshes == 1 ? "" : "s");
    if (discs > 0)
      line += ", " + std::to_string(discs) + " disc leaf model" + (discs == 1 ? "" : "s");
    return line;
  }
  if (canopy.contains("voxels"))
    return "a voxel grid of plant area density from " +
           file_name(canopy["voxels"].value("file", json("")));
  if (canopy.contains("point_cloud"))
    return "a point cloud from " + file_name(canopy["point_cloud"].value("file", json(""))) +
           ", voxelised at " + number(canopy["point_cloud"].value("voxel_size_m", 1.0)) + " m";
  std::string line;
  if (canopy.contains("crowns_file")) {
    line = "explicit crowns from " +
           std::filesystem::path(text(canopy["crowns_file"])).filename().string();
  } else {
    const std::string shape = canopy.value("crown_shape", "ellipsoid");
    line = shape == "layer" ? "a homogeneous layer"
                            : shape + " crowns of " + number(canopy.value("crown_radius_m", 0.0)) +
                                  " m radius at cover " + number(canopy.value("cover", 0.0));
  }
  line += ", PAI " + number(canopy.value("pai", 0.0)) + ", " +
          text(canopy.value("lad", json("spherical"))) + " leaves";
  if (canopy.contains("stands"))
    line += "; stands from " + std::filesystem::path(text(canopy["stands"])).filename().string();
  return line;
}

std::string products_line(const json& output, const std::string& config_file) {
  std::vector<std::string> products;
  if (output.value("netcdf", true)) products.push_back("shots.nc");
  if (output.value("footprints", true))
    products.push_back(output.value("footprints_format", "GeoJSON") == "GPKG"
                           ? "footprints.gpkg"
                           : "footprints.geojson");
  if (output.value("plots", false)) products.push_back("plots/");
  std::string line;
  for (std::size_t i = 0; i < products.size(); ++i) line += (i ? ", " : "") + products[i];
  if (output.value("per_order", false)) line += " (with per-order waveforms)";
  if (!output.value("metrics", true)) line += " (no waveform metrics)";
  const auto folder = std::filesystem::path("out") / std::filesystem::path(config_file).stem();
  return line + " into " + folder.string() + " (or --out DIR)";
}

}  // namespace

double estimated_run_s(double shots, double rays_per_shot, int max_order, bool vegetation,
                       int threads) {
  constexpr double shot_s = 3e-4;       // geometry, processing and writing of a shot
  constexpr double writing_s = 2.5e-4;  // a shot's writing, on one thread whatever the threads
  const double ray_s = vegetation ? 1.0e-6 + 0.78e-6 * (std::max(max_order, 1) - 1) : 0.7e-6;
  const double cpu_s = shot_s + rays_per_shot * ray_s;
  return 0.2 + shots * std::max(cpu_s / std::max(threads, 1), writing_s);
}

std::string run_outline(const Config& config, const CheckSummary& summary,
                        const std::string& config_file) {
  const json& resolved = config.resolved;
  const json simulation = resolved.value("simulation", json::object());
  const json canopy = resolved.value("canopy", json());
  const double rays = simulation.value("rays_per_shot", 10000.0);
  const int max_order = simulation.value("max_order", 8);
  const RunMemory memory =
      estimate_run_memory(config, summary.shared_scenes ? &*summary.shared_scenes : nullptr);
  const double shots = static_cast<double>(summary.shots - summary.shots_off_terrain);

  std::string out;
  const auto line = [&](const char* label, const std::string& text) {
    char head[32];
    std::snprintf(head, sizeof head, "  %-12s", label);
    out += head + text + "\n";
  };
  line("track:", track_line(resolved.value("track", json::object()), summary));
  line("sensor:", sensor_line(resolved.value("sensor", json::object()),
                              resolved.value("track", json::object())));
  if (config.atmosphere) line("atmosphere:", atmosphere_line(config));
  line("terrain:", terrain_line(resolved.value("terrain", json::object())));
  line("vegetation:", vegetation_line(canopy));
  line("rays:", number(rays, 12) + " a shot, up to " + number(max_order, 12) +
                    " scattering orders, " + text(simulation.value("sampling", json("random"))) +
                    " sampling");
  line("time:",
       duration(estimated_run_s(shots, rays, max_order, !canopy.is_null(), memory.threads)) +
           " on " + plural(memory.threads, "thread", "threads") +
           " (scaled from the benchmark; expect within about 2x)");
  // A forest's scene in trees; a measured source's in bytes, with what it holds once.
  const bool forest = memory.vegetation.empty() || memory.tree_bytes > 0.0;
  const std::string scene = forest ? number(std::round(memory.trees), 12) + " trees"
                                   : bytes(memory.scene_bytes) + " of " + memory.vegetation;
  const std::string once =
      memory.source_bytes > 0.0 ? ", and the source's " + bytes(memory.source_bytes) + " once" : "";
  // Strips' scenes, shared by their shots, are held a few at once beside each thread's waveforms.
  const std::string scenes =
      memory.strips ? number(memory.scenes, 12) + " x a strip's scene of " +
                          number(static_cast<double>(memory.strips->shots), 12) + " shots (" +
                          scene + ", " + number(std::round(memory.strips->length_m), 12) + " by " +
                          number(std::round(memory.strips->width_m), 12) + " m, its ground's " +
                          bytes(memory.ground_bytes) + "), " + number(memory.threads, 12) +
                          " x a shot's waveforms"
                    : number(memory.threads, 12) + " x a scene of " + scene + " and its waveforms";
  line("memory:", "about " + bytes(memory.bytes) + " (the program's " +
                      bytes(memory.program_bytes) + ", " + scenes + once + "), of " +
                      bytes(memory.available_bytes) + " available");
  line("products:", products_line(resolved.value("output", json::object()), config_file));
  return out;
}

}  // namespace glaswave
