// `glaswave sweep`: the seed's sensitivity study (its Table 3). The base case and each varied
// value, one key at a time with the others at base, are simulated over the track; the mean TR,
// CR and GR of each band go to sensitivity.csv and, as the seed lays them out, sensitivity.md.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace glaswave {

struct Variation {
  std::string key;                  // dotted configuration path, as for --set
  std::vector<std::string> values;  // each parsed as JSON when it parses, else a string
};

// "KEY=V1,V2,..." -> a variation; commas inside brackets or quotes belong to the value.
Variation parse_variation(const std::string& text);

struct SweepRequest {
  std::filesystem::path config_file;
  std::vector<std::string> overrides;  // --set, applied to every case
  std::vector<Variation> variations;
  std::filesystem::path out_dir;
  int threads = 0;
};

// `progress`, when set, is told (shots done, shots in all) over every case.
void run_sweep(const SweepRequest& request,
               const std::function<void(std::int64_t, std::int64_t)>& progress = {});

}  // namespace glaswave
