// The factory of a run's product writers: the one place that knows which writers exist.
#include "pipeline/products/product_writer.hpp"

#include <algorithm>

#include "core/error.hpp"
#include "pipeline/products/gedi_granule.hpp"
#include "pipeline/products/glas_granule.hpp"
#include "pipeline/products/icesat2_writer.hpp"
#include "pipeline/products/netcdf_writer.hpp"
#include "pipeline/products/ogr_writer.hpp"

namespace glaswave {

RecordLedger::RecordLedger(std::filesystem::path product, std::int64_t shots)
    : product_(std::move(product)),
      written_(static_cast<std::size_t>(std::max<std::int64_t>(0, shots))) {}

void RecordLedger::fail(const std::string& message) const {
  throw run_error(product_.string(), message);
}

void RecordLedger::check_write(std::int64_t index) const {
  if (finished_) fail("write after finish");
  if (index < 0 || index >= shots())
    fail("record index " + std::to_string(index) + " outside [0, " + std::to_string(shots()) + ")");
  if (written_[static_cast<std::size_t>(index)])
    fail("record " + std::to_string(index) + " written twice");
}

void RecordLedger::check_finish() const {
  if (finished_) fail("finished twice");
  for (std::size_t i = 0; i < written_.size(); ++i)
    if (!written_[i]) fail("record " + std::to_string(i) + " was never written");
}

std::vector<std::unique_ptr<ProductWriter>> make_writers(const std::filesystem::path& out_dir,
                                                         const ProductSettings& settings,
                                                         const RunInfo& info,
                                                         const Icesat2ProductSettings& icesat2) {
  std::vector<std::unique_ptr<ProductWriter>> writers;
  if (settings.netcdf)
    writers.push_back(std::make_unique<NetcdfWriter>(out_dir / "shots.nc", info));
  if (settings.footprints) {
    const bool gpkg = settings.footprints_format == FootprintsFormat::gpkg;
    writers.push_back(
        std::make_unique<OgrWriter>(out_dir / (gpkg ? "footprints.gpkg" : "footprints.geojson"),
                                    settings.footprints_format, info));
  }
  if (settings.gedi_l1b)
    writers.push_back(
        std::make_unique<GediGranuleWriter>(out_dir / "gedi_l1b.h5", GediLevel::l1b, info));
  if (settings.gedi_l2a)
    writers.push_back(
        std::make_unique<GediGranuleWriter>(out_dir / "gedi_l2a.h5", GediLevel::l2a, info));
  if (settings.glah01)
    writers.push_back(std::make_unique<GlasGranuleWriter>(out_dir / "glah01.h5", GlasLevel::glah01,
                                                          settings.glas_topex, info));
  if (settings.glah14)
    writers.push_back(std::make_unique<GlasGranuleWriter>(out_dir / "glah14.h5", GlasLevel::glah14,
                                                          settings.glas_topex, info));
  if (icesat2.atl03 || icesat2.atl08)
    writers.push_back(std::make_unique<Icesat2Writer>(out_dir, icesat2, info));
  return writers;
}

}  // namespace glaswave
