// What the benchmarks read of this process's memory.
#pragma once

#include <fstream>
#include <string>

namespace glaswave::benchmarks {

// A line of /proc/self/status ("VmRSS", "VmHWM") in MiB.
inline double status_mib(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  const std::string key = std::string(field) + ":";
  while (std::getline(in, line))
    if (line.rfind(key, 0) == 0) return std::stod(line.substr(key.size())) / 1024.0;
  return 0.0;
}

}  // namespace glaswave::benchmarks
