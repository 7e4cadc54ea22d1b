// What a kind of vegetation source is (CanopySettings::kind), as the configuration asks it instead
// of naming it: each source declares it beside its registration
// (Registry<PartKind<VegetationTraits>>, core/part_kind.hpp; pipeline/shot/vegetation_source.hpp),
// on a floor that the configuration and the sources both see.
#pragma once

namespace glaswave {

struct VegetationTraits {
  // The keys the configuration reads for it. `crowns`: the canopy's own (crowns, stands, a layer),
  // for a canopy that gives no kind's object. The others: the object `canopy.<kind>`, alone in the
  // canopy, of a file of measured vegetation and its leaves' keys (the configuration declares
  // each such object's keys), of facet trees' keys, or of no key the configuration declares
  // (`{}`: a kind whose settings are its own).
  enum class Keys { crowns, measured, facets, none };
  Keys keys = Keys::none;
  bool ground_points = false;  // its file's ground points may be the terrain (terrain.point_cloud)
};

}  // namespace glaswave
