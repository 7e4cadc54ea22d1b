// Facet trees (PRODUCT.md section 8, canopy.facets): triangle meshes read with Assimp (OBJ,
// PLY, glTF, ...: model units metres, z up, the stem's foot at the origin), each triangle with
// the name of its mesh material; and the trees that place them, from a CSV
// (`lon,lat,model,rotation_deg,scale` or `x,y,model,rotation_deg,scale`) or any OGR point layer
// in any CRS with those attributes. Every error is an input error naming the file.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "terrain/terrain_settings.hpp"

namespace glaswave {

// One model's triangles in its own frame, single precision as Embree holds them.
struct FacetMesh {
  std::vector<float> vertices_m;         // x, y, z per vertex
  std::vector<std::uint32_t> triangles;  // three vertex indices per triangle
  std::vector<std::uint16_t> materials;  // per triangle: an index into material_names
  std::vector<std::string> material_names;
};

// At most this many triangles a model (a few GB of Embree's BVH): beyond, a file is refused.
inline constexpr std::size_t max_facet_triangles = std::size_t{1} << 26;

// Reads the mesh file of model `model` (for messages). Triangles of zero area are dropped
// (their normal is undefined); a file with none left, a vertex beyond 1 km of the origin or a
// coordinate not finite is refused.
FacetMesh read_facet_mesh(const std::filesystem::path& file, const std::string& model);

// A tree of the trees file: where its stem stands, which model, turned by rotation_deg about the
// vertical (the model's +y axis to that azimuth, clockwise from north) and scaled by `scale`.
struct FacetTree {
  double lat_deg = 0.0, lon_deg = 0.0;
  int model = 0;  // an index into the model names given to read_facet_trees
  double rotation_deg = 0.0;
  double scale = 1.0;
};

// Reads the trees file: a `.csv` with a header `lon,lat,model,rotation_deg,scale` (degrees) or
// `x,y,model,rotation_deg,scale` (metres east and north of the plane terrain's origin), or any
// other file OGR reads as point layers (every layer, points in the layer's CRS, taken as
// longitude and latitude without one) with the attributes model, rotation_deg and scale. A
// model not in `models`, a scale not in (0, 100] or no tree at all is refused, naming the row.
std::vector<FacetTree> read_facet_trees(const std::filesystem::path& file,
                                        const std::vector<std::string>& models,
                                        const std::optional<PlaneSettings>& plane);

}  // namespace glaswave
