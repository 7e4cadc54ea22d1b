// The footprints through GDAL/OGR: footprints.geojson (RFC 7946) or footprints.gpkg, one
// Feature per shot, the footprint's 1/e^2 contour on the terrain as a Polygon (a MultiPolygon
// where it crosses the antimeridian) with the properties product_fields.hpp gives it (the shot's
// scalars and every band's values, suffixed with the band's name; PRODUCT.md section 4). Shots
// may come in any order; Features come out in record order.
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "pipeline/products/product_writer.hpp"
#include "pipeline/products/shot_record.hpp"

namespace glaswave {

// The footprints' properties, checked before anything is created: in a GeoPackage (SQLite) two
// whose names differ only in case (the bands "x" and "X": reflectance_x, reflectance_X) are one
// column, which failed inside SQLite with the whole CREATE TABLE as its message (issue 28).
// Throws Error (config) at "/sensor/bands/N/name" of the later band. GeoJSON keeps them apart.
void check_footprint_properties(const std::vector<std::string>& band_names,
                                FootprintsFormat format);

class OgrWriter final : public ProductWriter {
 public:
  // Creates final_path + ".part" in `format`. Throws Error (run) when it cannot be created.
  OgrWriter(std::filesystem::path final_path, FootprintsFormat format, const RunInfo& info);

  // An unfinished writer is aborted.
  ~OgrWriter() override;

  OgrWriter(const OgrWriter&) = delete;
  OgrWriter& operator=(const OgrWriter&) = delete;

  // As ProductWriter says. Features come out in record order: a record goes to the file as
  // soon as all those before it have come, so only early ones are held in memory. An empty
  // footprint ring (a flagged shot) gives a null geometry; a non-empty one must be closed, with
  // at least 4 positions, all finite. Exterior rings are written counter-clockwise.
  void write(std::int64_t index, const ShotRecord& shot) override;
  // The statistics are not part of this product.
  void finish(const RunStats& stats) override;
  void abort() noexcept override;

 private:
  struct Impl;
  Impl& impl();  // throws Error (run) after abort()
  std::filesystem::path final_path_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace glaswave
