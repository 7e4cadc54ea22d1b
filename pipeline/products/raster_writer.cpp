// GeoTIFF writing through the one GDAL layer (core/gdal_layer.hpp).
#include "pipeline/products/raster_writer.hpp"

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "core/gdal_layer.hpp"

namespace glaswave {

void write_geotiff(const std::filesystem::path& path, const RasterImage& image) {
  prepare_gdal();
  GdalErrorTrap trap;
  auto fail = [&](const std::string& what) { throw run_error(path.string(), trap.failure(what)); };
  OGRSpatialReference crs;
  if (crs.SetFromUserInput(image.crs.c_str()) != OGRERR_NONE) fail("bad CRS " + image.crs);
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (!driver) fail("GDAL has no GTiff driver");
  AtomicFile file(path);
  {
    const int bands = static_cast<int>(image.bands.size());
    char** options = CSLSetNameValue(nullptr, "COMPRESS", "DEFLATE");
    GDALDatasetUniquePtr dataset(driver->Create(file.part_path().c_str(), image.columns, image.rows,
                                                bands, GDT_Float32, options));
    CSLDestroy(options);
    if (!dataset) fail("cannot create");
    std::array<double, 6> transform = image.geotransform;
    dataset->SetGeoTransform(transform.data());
    dataset->SetSpatialRef(&crs);
    for (int b = 0; b < bands; ++b) {
      std::vector<float> values(image.bands[b].begin(), image.bands[b].end());
      GDALRasterBand* band = dataset->GetRasterBand(b + 1);
      if (b < static_cast<int>(image.band_names.size()))
        band->SetDescription(image.band_names[b].c_str());
      if (band->RasterIO(GF_Write, 0, 0, image.columns, image.rows, values.data(), image.columns,
                         image.rows, GDT_Float32, 0, 0) != CE_None)
        fail("cannot write");
    }
    // Closing writes what GDAL still holds: a full disk shows up here.
    trap.reset();
    dataset.reset();
    if (trap.failed()) fail("cannot write");
  }
  file.commit();
}

}  // namespace glaswave
