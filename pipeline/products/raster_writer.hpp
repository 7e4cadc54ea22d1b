// An image product as a georeferenced GeoTIFF through GDAL (the `scene.tif` of `glaswave brf`),
// written under a temporary name and renamed when complete.
#pragma once

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace glaswave {

struct RasterImage {
  int columns = 0, rows = 0;
  // GDAL's affine transform: x = g0 + column g1 + row g2, y = g3 + column g4 + row g5 (pixel
  // corners), in the CRS's units.
  std::array<double, 6> geotransform{};
  std::string crs;  // any definition OGRSpatialReference::SetFromUserInput takes
  std::vector<std::string> band_names;
  std::vector<std::vector<double>> bands;  // [band][row * columns + column], stored as float32
};

// Throws a run error naming the file when GDAL cannot write it; nothing is left under `path`.
void write_geotiff(const std::filesystem::path& path, const RasterImage& image);

}  // namespace glaswave
