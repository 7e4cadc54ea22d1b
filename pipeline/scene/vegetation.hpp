// The vegetation of one shot in its local frame: the stand's trees near the footprint as
// crowns on their trunks, each standing on the terrain under its stem, or a homogeneous layer
// following the footprint's mean ground.
#pragma once

#include "canopy/stand.hpp"
#include "pipeline/scene/scene.hpp"
#include "terrain/ground_mesh.hpp"

namespace glaswave {

Vegetation build_vegetation(const CanopySettings& canopy, const Stand& stand, const Terrain& terrain,
                            const LocalFrame& frame, double half_size_m, const SurfaceOrientation& ground);

}  // namespace glaswave
