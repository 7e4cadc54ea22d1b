// What the libFuzzer targets of tests/fuzz share: one scratch folder per fuzzing process (the
// only place they write), the input written there as a file, and GDAL narrowed to the drivers
// a target is about, so that its inputs reach glaswave's code rather than GDAL's format probes.
#pragma once

#include <cpl_conv.h>
#include <gdal.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

namespace glaswave::fuzz {

// <temp>/glaswave_fuzz_<pid>, made on first use, removed when the process exits normally (a
// crash leaves it for inspection).
inline const std::filesystem::path& scratch_dir() {
  struct Dir {
    std::filesystem::path path =
        std::filesystem::temp_directory_path() / ("glaswave_fuzz_" + std::to_string(::getpid()));
    Dir() {
      std::filesystem::remove_all(path);
      std::filesystem::create_directories(path);
    }
    ~Dir() {
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static const Dir dir;
  return dir.path;
}

// Writes the input, byte for byte, to `name` in the scratch folder; its path.
inline std::filesystem::path write_input(const std::string& name, const std::uint8_t* data,
                                         std::size_t size) {
  const std::filesystem::path file = scratch_dir() / name;
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return file;
}

// Registers GDAL's drivers, then drops every one but `keep` (GDAL_SKIP, which a later
// GDALAllRegister of the code under test honours too).
inline void keep_only_gdal_drivers(const std::set<std::string>& keep) {
  GDALAllRegister();
  std::string skip;
  for (int i = GDALGetDriverCount() - 1; i >= 0; --i) {
    const std::string name = GDALGetDriverShortName(GDALGetDriver(i));
    // GDAL_SKIP is split at spaces: the few names with one ("ESRI Shapefile") stay.
    if (!keep.count(name) && name.find(' ') == std::string::npos) skip += name + " ";
  }
  CPLSetConfigOption("GDAL_SKIP", skip.c_str());
  GDALAllRegister();  // ends by dropping the drivers GDAL_SKIP names
}

// A refusal of the code under test: printed when GLASWAVE_FUZZ_VERBOSE is set (to see what a
// corpus reaches), else nothing.
inline void refused(const std::exception& error) {
  static const bool verbose = std::getenv("GLASWAVE_FUZZ_VERBOSE") != nullptr;
  if (verbose) std::fprintf(stderr, "refused: %s\n", error.what());
}

}  // namespace glaswave::fuzz
