// Looking a vegetation source up by its kind among those registered (each from its own .cpp).
#include "pipeline/shot/vegetation_source.hpp"

#include "core/error.hpp"

namespace glaswave {
namespace {

VegetationKind kind_of(const std::string& name) {
  const Registry<VegetationSource>& sources = Registry<VegetationSource>::instance();
  if (std::optional<VegetationKind> kind = sources.find(name)) return *std::move(kind);
  std::string known;
  for (const auto& entry : sources.entries()) known += (known.empty() ? "" : ", ") + entry.name;
  throw setting_error(ErrorKind::config, "kind",
                      "no vegetation source \"" + name + "\" (there are: " + known + ")");
}

}  // namespace

VegetationTruth VegetationSource::truth(const Scene& scene, const BeamSpot& spot,
                                        const std::vector<double>& nadir_projection) const {
  return measure_vegetation(scene, spot, nadir_projection);
}

std::unique_ptr<VegetationSource> make_vegetation_source(const VegetationSettings& settings) {
  return kind_of(settings.canopy.kind).make(settings);
}

double vegetation_region_bytes(const VegetationSettings& settings, double side_m) {
  return kind_of(settings.canopy.kind).region_bytes(settings, side_m);
}

double vegetation_source_bytes(const VegetationSettings& settings) {
  const VegetationKind kind = kind_of(settings.canopy.kind);
  return kind.source_bytes ? kind.source_bytes(settings) : 0.0;
}

std::string vegetation_memory_key(const VegetationSettings& settings) {
  return kind_of(settings.canopy.kind).memory_key;
}

double vegetation_plant_bytes(const VegetationSettings& settings) {
  return kind_of(settings.canopy.kind).plant_bytes;
}

}  // namespace glaswave
