// The factory of a run's product writers: the one place that knows which writers exist.
#include "pipeline/products/product_writer.hpp"

#include "pipeline/products/netcdf_writer.hpp"
#include "pipeline/products/ogr_writer.hpp"

namespace glaswave {

std::vector<std::unique_ptr<ProductWriter>> make_writers(const std::filesystem::path& out_dir,
                                                         const ProductSettings& settings,
                                                         const RunInfo& info) {
  std::vector<std::unique_ptr<ProductWriter>> writers;
  if (settings.netcdf)
    writers.push_back(std::make_unique<NetcdfWriter>(out_dir / "shots.nc", info));
  if (settings.footprints) {
    const bool gpkg = settings.footprints_format == FootprintsFormat::gpkg;
    writers.push_back(
        std::make_unique<OgrWriter>(out_dir / (gpkg ? "footprints.gpkg" : "footprints.geojson"),
                                    settings.footprints_format, info));
  }
  return writers;
}

}  // namespace glaswave
