// Fuzzes the facet models' mesh reader (canopy/facet_trees: read_facet_mesh through Assimp, with
// glaswave's checks before and after it: PLY headers counted, glTF nesting scanned, files Assimp
// opens itself under the regular-file rule, indices and materials checked). The input's first
// byte picks the format (its extension: PLY, OBJ, glTF, GLB, STL, OFF); the rest is the file. An
// input Error is a refusal; anything else (a crash, a read out of bounds, a hang past -timeout,
// an allocation beyond -rss_limit_mb) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "canopy/facet_trees.hpp"
#include "core/error.hpp"
#include "tests/fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  glaswave::fuzz::keep_only_gdal_drivers({});  // meshes do not go through GDAL
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace glaswave;
  static const char* const extensions[] = {".ply", ".obj", ".gltf", ".glb", ".stl", ".off"};
  if (size == 0) return 0;
  const std::string name = std::string("model") + extensions[data[0] % 6];
  const auto file = fuzz::write_input(name, data + 1, size - 1);
  try {
    const FacetMesh mesh = read_facet_mesh(file, "tree");
    // What the scene relies on: every index names a vertex, every material index a name.
    const std::size_t vertices = mesh.vertices_m.size() / 3;
    for (std::uint32_t index : mesh.triangles)
      if (index >= vertices) __builtin_trap();
    for (std::uint16_t material : mesh.materials)
      if (material >= mesh.material_names.size()) __builtin_trap();
    if (mesh.materials.size() * 3 != mesh.triangles.size()) __builtin_trap();
  } catch (const Error& e) {
    fuzz::refused(e);
  }
  std::filesystem::remove(file);
  return 0;
}
