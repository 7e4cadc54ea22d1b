// The forward table of the `rt` retrieval (`glaswave table`, PRODUCT.md section 11): forests
// named by a configuration's `table` section, each simulated through the engine's library API
// (the configuration with the entry's values set as --set sets them, its terrain, track and shot
// simulator), keeping per entry the mean received waveform of its first shots on an axis of
// height above the footprint's ground, their scatter (the table's Monte Carlo noise) and the
// truths under the beam. Written to and read from a CF NetCDF file that carries the
// configuration it came from.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace glaswave {

// One varied key: a range sampled by the design, or a list of values it chooses among.
struct TableParameter {
  std::string key;                  // a dotted path, as --set names it ("canopy.pai")
  double low = 0.0, high = 0.0;     // a range
  std::vector<std::string> values;  // or the values, each read as --set reads VALUE
  bool is_range() const { return values.empty(); }
};

// The design: entry e's coordinate of parameter p, in [0, 1): the Halton sequence (the p-th
// prime base), shifted modulo 1 by a per-parameter offset drawn from (seed, p) (a Cranley-
// Patterson rotation), so that two seeds give two independent designs, each as even as Halton's.
double design_coordinate(std::uint64_t seed, std::int64_t entry, std::size_t parameter);

struct ForwardTable {
  std::vector<TableParameter> parameters;
  // [entry][parameter]: the value of a range, the index in `values` of a list.
  std::vector<std::vector<double>> parameter_values;
  std::vector<std::string> band_names;  // the sensor's, in its order
  double bin_ns = 0.0;
  double pulse_sigma_ns = 0.0;
  double off_nadir_deg = 0.0;    // of the table's shots
  std::vector<double> height_m;  // [bin] centre above the footprint's ground, decreasing
  std::vector<std::vector<std::vector<double>>> waveform_W;  // [entry][band][bin] mean of shots
  std::vector<std::vector<double>> mc_sd_W;  // [entry][band] one shot's per-bin Monte Carlo sd
  // [entry][band][bin] the entry's first shot alone (empty in a version-1 table or with one shot
  // an entry): beside the mean, it gives the Monte Carlo noise's per-bin variance and a held-out
  // shot of known truth, from which the rt likelihood is calibrated (rt_inversion.hpp).
  std::vector<std::vector<std::vector<double>>> shot0_W;
  // One shot's Monte Carlo sd over its waveform's peak: the median over entries and bands of
  // mc_sd_W / peak; NaN with one shot an entry.
  double mc_relative_sd = 0.0;
  std::int64_t shots_per_entry = 1;
  std::int64_t rays_per_shot = 0;
  std::vector<double> pai_true, cover_true, canopy_height_true_m;  // [entry]
  std::vector<double> pgap_true;  // [entry] the vertical gap probability (NaN in older tables)
  // [entry][band]: the energies of the returns last scattered by vegetation and by the ground (J).
  std::vector<std::vector<double>> energy_canopy_J, energy_ground_J;
  // [entry] the canopy-to-ground reflectance ratio the forest implies at the first band: the one
  // that makes GEDI L2B's Pgap = 1 - Rv / (Rv + r Rg) equal 1 - cover_true, r = Ec (1 - C) / (C Eg)
  // (NaN where cover is 0 or 1 or a return is empty).
  std::vector<double> rhov_rhog;
  std::string config_json;  // the configuration the table came from (table section included)
  std::uint64_t seed = 0;

  std::size_t entries() const { return waveform_W.size(); }
  std::size_t bands() const { return band_names.size(); }
};

struct TableRequest {
  nlohmann::json document;       // the configuration, --set applied
  std::filesystem::path folder;  // where its relative paths are taken from
  int threads = 0;               // 0: every core
};

// Called after each entry with (entries done, entries in all).
using TableProgress = std::function<void(std::int64_t, std::int64_t)>;

// Simulates the table. Every varied key's values are checked (each applied to the configuration
// and parsed) before anything is simulated; an error names the key.
ForwardTable build_table(const TableRequest& request, const TableProgress& progress);

// The implied ratio of canopy to ground reflectance (see ForwardTable::rhov_rhog).
double implied_rhov_rhog(double energy_canopy, double energy_ground, double cover);

void write_table(const ForwardTable& table, const std::filesystem::path& path,
                 const std::string& command_line);
// An input error (exit status 3) naming the file when it is not a table glaswave wrote.
ForwardTable read_table(const std::filesystem::path& path);

}  // namespace glaswave
