// Facet trees (PRODUCT.md sections 8 and 13, canopy.facets): triangle meshes read with Assimp
// (OBJ, PLY, glTF, ...: model units metres, z up, the stem's foot at the origin), each triangle
// with the name of its mesh material, or leaves as oriented discs from RAMI's one-disc-a-line
// text (`*.def`); and the trees that place them, from a CSV
// (`lon,lat,model,rotation_deg,scale[,z_m]` or `x,y,model,rotation_deg,scale[,z_m]`) or any OGR
// point layer in any CRS with those attributes. Every error is an input error naming the file.
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

// One model's leaves as oriented discs in its own frame (RAMI's scenes, librat's and eradiate's
// leaves), single precision as Embree holds them: all of one material.
struct DiscLeaves {
  std::vector<float> discs_m;  // x, y, z of the centre and the radius, per disc
  std::vector<float> normals;  // unit nx, ny, nz per disc
  std::size_t size() const { return discs_m.size() / 4; }
};

// Whether `file` is a disc leaf file rather than a mesh: its extension `.def` (any case).
bool is_disc_leaf_file(const std::filesystem::path& file);

// Reads a disc leaf file of model `model` (for messages): one disc a line, seven numbers apart by
// spaces or tabs, `radius x y z nx ny nz` (metres, the model's frame; the normal need not be
// unit, it is normalised); blank lines and lines starting with '#' skipped. A line that is not
// seven finite numbers, a radius not in (0, 1000] m, a centre beyond 1 km of the origin, a normal
// of zero length, more than max_facet_triangles discs or none at all is refused, naming the file
// and line.
DiscLeaves read_disc_leaves(const std::filesystem::path& file, const std::string& model);

// A tree of the trees file: where its stem stands, which model, turned by rotation_deg about the
// vertical (the model's +y axis to that azimuth, clockwise from north) and scaled by `scale`.
struct FacetTree {
  double lat_deg = 0.0, lon_deg = 0.0;
  int model = 0;  // an index into the model names given to read_facet_trees
  double rotation_deg = 0.0;
  double scale = 1.0;
  double z_m = 0.0;  // the model's origin above the ground under it (a floating crown)
};

// Reads the trees file: a `.csv` with a header `lon,lat,model,rotation_deg,scale` (degrees) or
// `x,y,model,rotation_deg,scale` (metres east and north of the plane terrain's origin), either
// with an optional last column `z_m`, or any other file OGR reads as point layers (every layer,
// points in the layer's CRS, taken as longitude and latitude without one) with the attributes
// model, rotation_deg and scale (and optionally z_m). A model not in `models`, a scale not in
// (0, 100], a z_m not in [0, 1000] m or no tree at all is refused, naming the row.
std::vector<FacetTree> read_facet_trees(const std::filesystem::path& file,
                                        const std::vector<std::string>& models,
                                        const std::optional<PlaneSettings>& plane);

}  // namespace glaswave
