// The one GDAL layer: registration once, the error trap, the dataset closer, WGS 84.
#include "core/gdal_layer.hpp"

#include <cpl_error.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cstdint>
#include <mutex>

#include "core/netcdf_lock.hpp"

namespace glaswave {

void prepare_gdal() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    if (!CPLGetConfigOption("GDAL_CACHEMAX", nullptr)) GDALSetCacheMax64(std::int64_t{32} << 20);
  });
}

namespace {

void CPL_STDCALL trap_handler(CPLErr level, CPLErrorNum number, const char* text) {
  GdalErrorTrap::handle_message(static_cast<int>(level), static_cast<int>(number), text);
}

}  // namespace

GdalErrorTrap::GdalErrorTrap() { CPLPushErrorHandlerEx(&trap_handler, this); }

GdalErrorTrap::~GdalErrorTrap() { CPLPopErrorHandler(); }

void GdalErrorTrap::handle_message(int level, int, const char* text) {
  auto* self = static_cast<GdalErrorTrap*>(CPLGetErrorHandlerUserData());
  if (!self || level < CE_Failure || !text) return;
  std::string message = text;
  // One line: GDAL's messages sometimes span several.
  for (char& c : message)
    if (c == '\n' || c == '\r') c = ' ';
  if (self->first_.empty()) self->first_ = message;
  self->last_ = std::move(message);
}

void GdalDatasetCloser::operator()(GDALDataset* dataset) const {
  const std::lock_guard lock(netcdf_library_mutex());
  const GdalErrorTrap trap;
  GDALClose(dataset);
}

std::unique_ptr<OGRCoordinateTransformation> transformation_to_wgs84(
    const OGRSpatialReference& crs) {
  OGRSpatialReference source(crs);
  source.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return std::unique_ptr<OGRCoordinateTransformation>(
      OGRCreateCoordinateTransformation(&source, &wgs84));
}

}  // namespace glaswave
