// The registry of vegetation sources, with the forest registered from the start.
#include "pipeline/shot/vegetation_source.hpp"

#include <map>
#include <mutex>

#include "core/error.hpp"
#include "pipeline/shot/facet_source.hpp"
#include "pipeline/shot/forest_source.hpp"
#include "pipeline/shot/voxel_source.hpp"

namespace glaswave {
namespace {

struct Registry {
  std::mutex mutex;
  std::map<std::string, VegetationKind> kinds;
};

Registry& registry() {
  static Registry sources{
      {},
      {{"forest",
        {[](const VegetationSettings& s) { return std::make_unique<ForestSource>(s); },
         &ForestSource::region_bytes, nullptr, "/canopy/crown_radius_m"}},
       {"voxels",
        {[](const VegetationSettings& s) { return std::make_unique<VoxelSource>(s); },
         &VoxelSource::region_bytes, &VoxelSource::source_bytes, "/canopy/voxels/file"}},
       {"point_cloud",
        {[](const VegetationSettings& s) { return std::make_unique<VoxelSource>(s); },
         &VoxelSource::region_bytes, &VoxelSource::source_bytes,
         "/canopy/point_cloud/voxel_size_m"}},
       {"facets",
        {[](const VegetationSettings& s) { return std::make_unique<FacetSource>(s); },
         &FacetSource::region_bytes, &FacetSource::source_bytes, "/canopy/facets/models"}}}};
  return sources;
}

VegetationKind kind_of(const std::string& name) {
  Registry& sources = registry();
  const std::lock_guard lock(sources.mutex);
  const auto found = sources.kinds.find(name);
  if (found != sources.kinds.end()) return found->second;
  std::string known;
  for (const auto& [registered, kind] : sources.kinds)
    known += (known.empty() ? "" : ", ") + registered;
  throw setting_error(ErrorKind::config, "kind",
                      "no vegetation source \"" + name + "\" (there are: " + known + ")");
}

}  // namespace

VegetationTruth VegetationSource::truth(const Scene& scene, const BeamSpot& spot) const {
  return measure_vegetation(scene, spot);
}

void register_vegetation_source(const std::string& name, VegetationKind kind) {
  Registry& sources = registry();
  const std::lock_guard lock(sources.mutex);
  if (!sources.kinds.emplace(name, std::move(kind)).second)
    throw run_error("vegetation source \"" + name + "\"", "registered twice");
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

}  // namespace glaswave
