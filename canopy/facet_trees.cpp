// Facet tree models through Assimp, disc leaf files, and the trees file through the CSV reader or
// OGR.
#include "canopy/facet_trees.hpp"

#include <assimp/DefaultIOSystem.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <gdal_priv.h>
#include <ogrsf_frmts.h>
#include <sys/stat.h>

#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <assimp/Importer.hpp>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include "core/csv.hpp"
#include "core/error.hpp"
#include "core/gdal_layer.hpp"
#include "core/input_file.hpp"

namespace glaswave {
namespace {

// No tree reaches beyond this from its foot: a vertex farther is a model in other units.
constexpr double max_model_reach_m = 1000.0;
constexpr double max_scale = 100.0;
constexpr double max_offset_m = 1.0e6;

void add_mesh(const aiMesh& mesh, const std::string& material, FacetMesh& out,
              std::map<std::string, std::uint16_t>& material_numbers, const std::string& place) {
  const auto first = static_cast<std::uint32_t>(out.vertices_m.size() / 3);
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    const aiVector3D& p = mesh.mVertices[v];
    for (double c : {double{p.x}, double{p.y}, double{p.z}})
      if (!std::isfinite(c) || std::abs(c) > max_model_reach_m)
        throw input_error(place,
                          "a vertex lies beyond 1 km of the model's origin or is not "
                          "finite (model units are metres, the stem's foot at 0, 0, 0)");
    out.vertices_m.insert(out.vertices_m.end(), {p.x, p.y, p.z});
  }
  // A triangle's material is a 16-bit index: one more would wrap onto the first.
  constexpr std::size_t kMostMaterials = std::numeric_limits<std::uint16_t>::max();
  if (out.material_names.size() >= kMostMaterials && !material_numbers.count(material))
    throw input_error(place, "the mesh names more than " + std::to_string(kMostMaterials) +
                                 " materials, the most a model may hold (its triangles' "
                                 "material index has 16 bits)");
  const auto [entry, added] =
      material_numbers.emplace(material, static_cast<std::uint16_t>(out.material_names.size()));
  if (added) out.material_names.push_back(material);
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices != 3) continue;  // points and lines are no facets
    const unsigned* i = face.mIndices;
    // Assimp's validation refuses these; a face naming a vertex the mesh lacks is never used.
    for (int c = 0; c < 3; ++c)
      if (i[c] >= mesh.mNumVertices)
        throw input_error(place, "a face names vertex " + std::to_string(i[c]) + " of " +
                                     std::to_string(mesh.mNumVertices));
    const aiVector3D e1 = mesh.mVertices[i[1]] - mesh.mVertices[i[0]];
    const aiVector3D e2 = mesh.mVertices[i[2]] - mesh.mVertices[i[0]];
    if ((e1 ^ e2).SquareLength() <= 0.0f) continue;  // no area, no normal
    out.triangles.insert(out.triangles.end(), {first + i[0], first + i[1], first + i[2]});
    out.materials.push_back(entry->second);
  }
  if (out.triangles.size() / 3 > max_facet_triangles)
    throw input_error(place,
                      "holds more than " + std::to_string(max_facet_triangles) + " triangles");
}

// Every file Assimp opens itself (the model, an OBJ's mtllib, a glTF's buffers and images) under
// the regular-file rule: a FIFO would be waited on for ever, a device read for ever. The first
// file refused is kept, and read_facet_mesh refuses the model naming it, whether Assimp then
// failed or went on without the file (an OBJ without its materials).
class CheckedIOSystem : public Assimp::DefaultIOSystem {
 public:
  // Assimp's own Exists opens the file (and would wait on a FIFO); stat(2) opens nothing.
  bool Exists(const char* file) const override {
    struct stat status {};
    if (::stat(file, &status) != 0) return false;
    return S_ISREG(status.st_mode) || allowed(file);  // a FIFO's refusal kept
  }

  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!allowed(file)) return nullptr;
    return Assimp::DefaultIOSystem::Open(file, mode);
  }

  const std::string& refused() const { return refused_; }

 private:
  // False, with the refusal kept, unless `file` is a regular file to read.
  bool allowed(const char* file) const {
    try {
      require_input_file(file, "a file the mesh names");
      return true;
    } catch (const Error& error) {
      if (refused_.empty()) refused_ = error.what();
      return false;
    }
  }

  mutable std::string refused_;
};

// The least bytes a PLY element's properties take: binary, their sizes (a list, its count
// alone); ASCII, a character and a separator each.
std::uint64_t ply_property_bytes(const std::string& type, bool ascii) {
  if (ascii) return 2;
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "double" || type == "float64") return 8;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" ||
      type == "float32")
    return 4;
  return 1;
}

// An OFF header's counts (vertices, faces) are checked before Assimp reserves memory for them, as
// PLY's are: a header declaring 6.7e99 vertices in 300 bytes (found by mesh_fuzzer; Assimp wraps
// the count to 2.9e9 and asks for 34 GB) is refused. A vertex takes at least 6 bytes ("0 0 0\n"),
// a face at least 4 ("1 0\n").
void check_off_counts(const std::string& place, const std::string& model) {
  std::ifstream in(place, std::ios::binary);
  std::string line;
  if (!std::getline(in, line)) return;
  // An OFF file: its keyword (OFF, COFF, NOFF, CNOFF, STOFF, 4OFF, nOFF) in its first word, or the
  // extension .off, with which Assimp reads the counts without a keyword (mesh_fuzzer). The
  // numbers start after the keyword ("OFF02" declares 2 vertices to Assimp).
  std::string upper = line.substr(0, line.find_first_of(" \t\r"));
  std::transform(upper.begin(), upper.end(), upper.begin(),
                 [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
  const std::size_t keyword = upper.find("OFF");
  std::string extension = std::filesystem::path(place).extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if ((keyword == std::string::npos || keyword > 2) && extension != ".off") return;
  // The header's numbers (vertices, faces, edges; nOFF's dimension first) are its first three
  // runs of digits after the keyword, comments (# to the line's end) left out, whatever else lies
  // between them: Assimp reads "3#1 2\n\n6000..." as 3 and 6000... (mesh_fuzzer). Where it reads
  // them differs by variant, so each alone must fit in the file, and the first two as vertices and
  // faces together.
  std::string text = keyword == std::string::npos || keyword > 2 ? line : line.substr(keyword + 3);
  std::vector<std::string> counts;
  std::string run;
  for (std::size_t n = 0; counts.size() < 3 && n < 4096;) {
    n += text.size() + 1;
    text = text.substr(0, text.find('#'));  // a comment, to the line's end
    for (const char c : text) {
      if (std::isdigit(static_cast<unsigned char>(c))) {
        run += c;
      } else if (!run.empty()) {
        counts.push_back(run);
        run.clear();
        if (counts.size() == 3) break;
      }
    }
    if (counts.size() == 3 || !std::getline(in, text)) break;
    if (!run.empty()) counts.push_back(run);  // a run ends with its line
    run.clear();
  }
  if (!run.empty() && counts.size() < 3) counts.push_back(run);
  std::error_code error;
  const std::uint64_t size = std::filesystem::file_size(place, error);
  if (error || counts.empty()) return;
  const auto declared = [&](const std::string& what) {
    return input_error(place, "the mesh of model \"" + model + "\" declares " + what +
                                  " in its OFF header, more than its " + std::to_string(size) +
                                  " bytes hold (cut short or corrupt)");
  };
  for (const std::string& count : counts)
    if (count.size() > 20 || std::stold(count) > static_cast<long double>(size))
      throw declared(count.size() > 20
                         ? count.substr(0, 20) + "... (" + std::to_string(count.size()) + " digits)"
                         : count);
  if (counts.size() >= 2 &&
      std::stold(counts[0]) * 6.0L + std::stold(counts[1]) * 4.0L > static_cast<long double>(size))
    throw declared(counts[0] + " vertices and " + counts[1] + " faces");
}

// A PLY header's elements are counted before Assimp reserves memory for them: a header that
// declares more elements than the bytes after it can hold (10^9 faces in 200 bytes) is refused.
void check_ply_counts(const std::string& place, const std::string& model) {
  std::ifstream in(place, std::ios::binary);
  std::string line;
  // Assimp reads as PLY any file whose first three bytes are "ply" in either case ("plyply", a
  // header it then read for ever, found by mesh_fuzzer): such a file is checked here too, and its
  // first line must be that word alone.
  if (!std::getline(in, line) || line.size() < 3) return;
  std::transform(line.begin(), line.end(), line.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (line.compare(0, 3, "ply") != 0) return;
  while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back()))) line.pop_back();
  if (line != "ply")
    throw input_error(place, "the mesh of model \"" + model +
                                 "\": its PLY header's first line is not the word ply alone");
  bool ascii = false;
  std::vector<std::pair<std::string, std::uint64_t>> elements;  // name, count
  std::vector<std::uint64_t> element_bytes;
  constexpr std::size_t max_header_lines = 100000;
  for (std::size_t n = 0; n < max_header_lines && std::getline(in, line); ++n) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    // Assimp's reader does not see a keyword after a space or carriage return ("\rend_header":
    // it read past the file's end for ever, found by mesh_fuzzer), where the words below do.
    if (!line.empty() && (std::isspace(static_cast<unsigned char>(line.front())) ||
                          line.find('\r') != std::string::npos))
      throw input_error(place, "the mesh of model \"" + model +
                                   "\": a line of its PLY header begins with a space or holds a "
                                   "carriage return before its end");
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (keyword == "end_header") {
      const std::uint64_t header = static_cast<std::uint64_t>(in.tellg());
      std::error_code error;
      const std::uint64_t size = std::filesystem::file_size(place, error);
      if (error) return;
      const std::uint64_t data = size > header ? size - header : 0;
      long double needed = 0.0L;
      for (std::size_t e = 0; e < elements.size(); ++e) {
        needed += static_cast<long double>(elements[e].second) * element_bytes[e];
        if (needed > static_cast<long double>(data))
          throw input_error(place, "the mesh of model \"" + model + "\" declares " +
                                       std::to_string(elements[e].second) + " " +
                                       elements[e].first.substr(0, 40) +
                                       " elements, more than its " + std::to_string(data) +
                                       " bytes after the header hold (cut short or corrupt)");
      }
      return;
    }
    if (keyword == "format") {
      std::string format;
      words >> format;
      ascii = format == "ascii";
    } else if (keyword == "element") {
      std::string name, count;
      words >> name >> count;
      std::uint64_t value = 0;
      const auto [end, status] = std::from_chars(count.data(), count.data() + count.size(), value);
      if (status != std::errc() || end != count.data() + count.size())
        throw input_error(place, "the mesh of model \"" + model + "\": element " +
                                     name.substr(0, 40) + "'s count is not a whole number");
      elements.emplace_back(name, value);
      element_bytes.push_back(0);
    } else if (keyword == "property" && !elements.empty()) {
      std::string type;
      words >> type;
      if (type == "list") words >> type;  // the count's type: the items may be none
      element_bytes.back() += ply_property_bytes(type, ascii);
    } else if (!keyword.empty() && keyword != "comment" && keyword != "obj_info" &&
               keyword != "property") {
      // Assimp's PLY reader ran past 60 s on a header of such lines (found by mesh_fuzzer).
      throw input_error(place, "the mesh of model \"" + model +
                                   "\": a line of its PLY header begins with none of PLY's "
                                   "keywords (format, comment, element, property, end_header)");
    }
  }
  throw input_error(place, "the mesh of model \"" + model + "\": its PLY header has no end_header");
}

// glTF's JSON (a .gltf, or a .glb's first chunk, whose declared length is checked first) nested
// deeper than this is refused before Assimp's recursive parser overflows its stack on it
// (200 000 levels of arrays: a crash). glTF itself nests a few levels; extras may nest more.
constexpr int max_gltf_depth = 256;

void check_gltf_depth(const std::string& place, const std::string& model) {
  std::ifstream in(place, std::ios::binary);
  char magic[12] = {};
  in.read(magic, 12);
  std::uint64_t length = std::numeric_limits<std::uint64_t>::max();
  if (in.gcount() == 12 && std::string_view(magic, 4) == "glTF") {
    unsigned char chunk[8] = {};
    in.read(reinterpret_cast<char*>(chunk), 8);
    if (in.gcount() != 8) return;
    length = chunk[0] | chunk[1] << 8 | chunk[2] << 16 | std::uint64_t{chunk[3]} << 24;
    // Assimp reserves the JSON's declared length (glTF 2's first chunk, glTF 1's scene: the same
    // four bytes) before reading it: 1.7 GB for a file of 105 bytes (mesh_fuzzer).
    std::error_code error;
    const std::uint64_t size = std::filesystem::file_size(place, error);
    if (!error && length > (size > 20 ? size - 20 : 0))
      throw input_error(place, "the mesh of model \"" + model + "\" declares a JSON chunk of " +
                                   std::to_string(length) + " bytes, more than its " +
                                   std::to_string(size) + " bytes hold (cut short or corrupt)");
    if (std::string_view(reinterpret_cast<char*>(chunk) + 4, 4) != "JSON") return;
  } else {
    in.clear();
    in.seekg(0);
    char first = ' ';
    while (in.get(first) && std::isspace(static_cast<unsigned char>(first))) {
    }
    if (!in || first != '{') return;
    in.seekg(-1, std::ios::cur);
  }
  int depth = 0;
  bool text = false, escaped = false;
  char buffer[1 << 16];
  while (length > 0 && in) {
    in.read(buffer, static_cast<std::streamsize>(std::min<std::uint64_t>(sizeof buffer, length)));
    const std::streamsize got = in.gcount();
    if (got <= 0) break;
    length -= static_cast<std::uint64_t>(got);
    for (std::streamsize n = 0; n < got; ++n) {
      const char c = buffer[n];
      if (text) {
        if (escaped)
          escaped = false;
        else if (c == '\\')
          escaped = true;
        else if (c == '"')
          text = false;
        continue;
      }
      if (c == '"') {
        text = true;
      } else if (c == '{' || c == '[') {
        if (++depth > max_gltf_depth)
          throw input_error(place, "the mesh of model \"" + model +
                                       "\" nests its JSON deeper than " +
                                       std::to_string(max_gltf_depth) + " levels");
      } else if (c == '}' || c == ']') {
        --depth;
      }
    }
  }
}

// Assimp 5.2's triangulation asserts (abort(), in Debian's build) that a mesh marked as holding
// polygons has a face of more than three corners; a face of no corner marks it so without one
// (a PLY face list of count 0, found by mesh_fuzzer). Validation lets such faces through, so they
// are refused here, before the step runs.
void check_polygons(const aiScene& scene, const std::string& place, const std::string& model) {
  for (unsigned m = 0; m < scene.mNumMeshes; ++m) {
    const aiMesh& part = *scene.mMeshes[m];
    bool polygon = false;
    for (unsigned f = 0; f < part.mNumFaces; ++f) {
      if (part.mFaces[f].mNumIndices == 0)
        throw input_error(place, "the mesh of model \"" + model + "\": face " + std::to_string(f) +
                                     " of its mesh " + std::to_string(m) + " names no vertex");
      polygon = polygon || part.mFaces[f].mNumIndices > 3;
    }
    if ((part.mPrimitiveTypes & aiPrimitiveType_POLYGON) && !polygon)
      throw input_error(place, "the mesh of model \"" + model + "\": its mesh " +
                                   std::to_string(m) +
                                   " is marked as holding polygons and holds none (corrupt)");
  }
}

}  // namespace

FacetMesh read_facet_mesh(const std::filesystem::path& file, const std::string& model) {
  const std::string place = file.string();
  require_input_file(place, "the mesh of model \"" + model + "\"");
  check_ply_counts(place, model);
  check_off_counts(place, model);
  check_gltf_depth(place, model);
  Assimp::Importer importer;
  auto owned = std::make_unique<CheckedIOSystem>();
  const CheckedIOSystem* files = owned.get();
  importer.SetIOHandler(owned.release());  // the importer deletes it
  // Read and validated first (faces naming vertices the mesh lacks, counts that disagree), then,
  // once glaswave has checked what Assimp's steps assume, node transforms applied, polygons cut
  // into triangles, shared vertices merged.
  const aiScene* scene = importer.ReadFile(place, aiProcess_ValidateDataStructure);
  auto check_scene = [&] {
    if (!files->refused().empty())
      throw input_error(place, "the mesh of model \"" + model + "\" names a file it cannot use (" +
                                   files->refused() + ")");
    if (!scene || (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) || !scene->mRootNode) {
      std::string why = importer.GetErrorString();
      std::replace(why.begin(), why.end(), '\n', ' ');
      throw input_error(place, "cannot read the mesh of model \"" + model +
                                   "\" (Assimp: " + (why.empty() ? "no scene" : why) + ")");
    }
  };
  check_scene();
  check_polygons(*scene, place, model);
  scene = importer.ApplyPostProcessing(aiProcess_Triangulate | aiProcess_PreTransformVertices |
                                       aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
  check_scene();
  FacetMesh mesh;
  std::map<std::string, std::uint16_t> material_numbers;
  for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
    const aiMesh& part = *scene->mMeshes[m];
    std::string material = "DefaultMaterial";
    if (part.mMaterialIndex < scene->mNumMaterials) {
      aiString name;
      if (scene->mMaterials[part.mMaterialIndex]->Get(AI_MATKEY_NAME, name) == AI_SUCCESS)
        material = name.C_Str();
    }
    add_mesh(part, material, mesh, material_numbers, place);
  }
  if (mesh.triangles.empty())
    throw input_error(place, "the mesh of model \"" + model + "\" holds no triangle of any area");
  return mesh;
}

bool is_disc_leaf_file(const std::filesystem::path& file) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return extension == ".def";
}

DiscLeaves read_disc_leaves(const std::filesystem::path& file, const std::string& model) {
  const std::string path = file.string();
  require_input_file(path, "the disc leaves of model \"" + model + "\"");
  std::ifstream in(file, std::ios::binary);
  if (!in) throw input_error(path, "cannot open the disc leaves of model \"" + model + "\"");
  DiscLeaves leaves;
  constexpr std::size_t max_line_bytes = 4096;
  char line[max_line_bytes];
  long number = 0;
  while (true) {
    in.getline(line, max_line_bytes);
    if (in.eof() && in.gcount() == 0) break;
    ++number;
    const std::string place = path + ":" + std::to_string(number);
    if (in.fail()) {
      if (!in.eof())
        throw input_error(place, "a line longer than " + std::to_string(max_line_bytes) +
                                     " bytes is no disc leaf (`radius x y z nx ny nz`)");
      in.clear(std::ios::eofbit);
    }
    std::string_view text(line);
    std::vector<std::string_view> words;
    for (std::size_t at = 0; at < text.size();) {
      const std::size_t start = text.find_first_not_of(" \t\r", at);
      if (start == std::string_view::npos) break;
      const std::size_t end = std::min(text.find_first_of(" \t\r", start), text.size());
      words.push_back(text.substr(start, end - start));
      at = end;
    }
    if (words.empty() || words.front().front() == '#') {
      if (in.eof()) break;
      continue;
    }
    if (words.size() != 7)
      throw input_error(place, "a disc leaf is 7 numbers, `radius x y z nx ny nz`, got " +
                                   std::to_string(words.size()) + " fields");
    double v[7];
    for (int i = 0; i < 7; ++i) {
      const std::optional<double> value = parse_number(words[i]);
      if (!value)
        throw input_error(place, "field " + std::to_string(i + 1) + ", " + field_excerpt(words[i]) +
                                     ", is not a finite number (a disc leaf is `radius x y z "
                                     "nx ny nz`)");
      v[i] = *value;
    }
    if (!(v[0] > 0.0 && v[0] <= max_model_reach_m))
      throw input_error(place, "the radius must be in (0, 1000] m, got " + std::to_string(v[0]));
    for (int i = 1; i < 4; ++i)
      if (std::abs(v[i]) > max_model_reach_m)
        throw input_error(place,
                          "the centre lies beyond 1 km of the model's origin (model units are "
                          "metres)");
    const double length = std::sqrt(v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
    if (!(length > 0.0) || !std::isfinite(length))
      throw input_error(place, "the normal (nx ny nz) has no length");
    if (leaves.size() >= max_facet_triangles)
      throw input_error(place,
                        "holds more than " + std::to_string(max_facet_triangles) + " disc leaves");
    leaves.discs_m.insert(leaves.discs_m.end(),
                          {static_cast<float>(v[1]), static_cast<float>(v[2]),
                           static_cast<float>(v[3]), static_cast<float>(v[0])});
    leaves.normals.insert(leaves.normals.end(),
                          {static_cast<float>(v[4] / length), static_cast<float>(v[5] / length),
                           static_cast<float>(v[6] / length)});
    if (in.eof()) break;
  }
  if (in.bad())
    throw input_error(path, "the disc leaves of model \"" + model + "\" could not be read");
  if (leaves.size() == 0)
    throw input_error(path, "the disc leaves of model \"" + model + "\" hold no disc");
  return leaves;
}

namespace {

const std::vector<std::string_view> geographic_header{"lon", "lat", "model", "rotation_deg",
                                                      "scale"};
const std::vector<std::string_view> metric_header{"x", "y", "model", "rotation_deg", "scale"};
// The optional last column: the model's origin above the ground (a floating crown).
constexpr std::string_view height_column = "z_m";
constexpr double max_height_m = 1000.0;

// Whether `fields` is `header`, or `header` and z_m.
bool header_is(const std::vector<std::string_view>& fields,
               const std::vector<std::string_view>& header) {
  if (fields.size() == header.size() + 1 && fields.back() == height_column)
    return std::equal(header.begin(), header.end(), fields.begin());
  return fields == header;
}

int model_number(std::string_view name, const std::vector<std::string>& models,
                 const std::string& place) {
  const auto found = std::find(models.begin(), models.end(), name);
  if (found != models.end()) return static_cast<int>(found - models.begin());
  std::string known;
  for (const std::string& m : models) known += (known.empty() ? "" : ", ") + m;
  throw input_error(place, "model " + field_excerpt(name) +
                               " is not in canopy.facets.models (there are: " + known + ")");
}

void check_tree(const FacetTree& tree, const std::string& place) {
  if (!(tree.scale > 0.0 && tree.scale <= max_scale))
    throw input_error(place, "scale must be in (0, 100]");
  if (!std::isfinite(tree.rotation_deg)) throw input_error(place, "rotation_deg must be finite");
  if (!(tree.lon_deg >= -180.0 && tree.lon_deg <= 360.0))
    throw input_error(place, "lon must be in [-180, 360]");
  if (!(tree.lat_deg >= -90.0 && tree.lat_deg <= 90.0))
    throw input_error(place, "lat must be in [-90, 90]");
  if (!(tree.z_m >= 0.0 && tree.z_m <= max_height_m))
    throw input_error(place, "z_m must be in [0, 1000] m");
}

std::vector<FacetTree> read_csv_trees(const std::filesystem::path& file,
                                      const std::vector<std::string>& models,
                                      const std::optional<PlaneSettings>& plane) {
  CsvReader csv(file, "the trees file");
  std::vector<std::string_view> fields;
  std::optional<GeographicLib::LocalCartesian> origin;
  std::size_t columns = geographic_header.size();
  const bool header = csv.next_row(fields);
  if (header) columns = fields.size();
  if (header && !header_is(fields, geographic_header)) {
    if (!header_is(fields, metric_header))
      throw input_error(csv.place(),
                        "expected the header lon,lat,model,rotation_deg,scale or "
                        "x,y,model,rotation_deg,scale (either with a last column z_m)");
    if (!plane)
      throw input_error(
          csv.place(), "x,y trees are metres from terrain.plane's origin; with a DEM give lon,lat");
    origin.emplace(plane->origin_lat_deg, plane->origin_lon_deg, 0.0);
  }
  std::vector<FacetTree> trees;
  while (csv.next_row(fields)) {
    const std::string place = csv.place();
    if (fields.size() != columns)
      throw input_error(place, "expected " + std::to_string(columns) + " values, got " +
                                   std::to_string(fields.size()));
    FacetTree tree;
    const double a = csv.number(fields[0], origin ? "x" : "lon");
    const double b = csv.number(fields[1], origin ? "y" : "lat");
    tree.model = model_number(fields[2], models, place);
    tree.rotation_deg = csv.number(fields[3], "rotation_deg");
    tree.scale = csv.number(fields[4], "scale");
    if (columns == 6) tree.z_m = csv.number(fields[5], height_column);
    if (origin) {
      if (std::abs(a) > max_offset_m || std::abs(b) > max_offset_m)
        throw input_error(place, "x and y must be within 1000000 m of the plane's origin");
      double h = 0.0;
      origin->Reverse(a, b, 0.0, tree.lat_deg, tree.lon_deg, h);
    } else {
      tree.lon_deg = a;
      tree.lat_deg = b;
    }
    check_tree(tree, place);
    trees.push_back(tree);
  }
  return trees;
}

// A number attribute: a number field, or a text field that is a number written whole; refused
// otherwise, as the CSV reader refuses it (OGR reads "abc" as 0).
double number_field(const OGRFeature& feature, int index, const char* name,
                    const std::string& place) {
  if (!feature.IsFieldSetAndNotNull(index))
    throw input_error(place, std::string(name) + " is empty");
  const OGRFieldType type = feature.GetFieldDefnRef(index)->GetType();
  if (type == OFTReal || type == OFTInteger || type == OFTInteger64)
    return feature.GetFieldAsDouble(index);
  const std::string text = feature.GetFieldAsString(index);
  double value = 0.0;
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  if (type != OFTString || text.empty() || error != std::errc() || stop != end)
    throw input_error(place, std::string(name) + " is " + field_excerpt(text) + ", not a number");
  return value;
}

// Why a layer lacks one of the trees' attributes: a Shapefile cuts field names to 10 characters
// (its dBase table's limit), so that it cannot hold rotation_deg at all.
std::string missing_attribute(const GDALDataset& dataset, const OGRFeatureDefn& definition,
                              int layer, const std::string& name) {
  std::string why = "layer " + std::to_string(layer) + " has no attribute " + name +
                    " (trees need model, rotation_deg and scale)";
  const GDALDriver* driver = const_cast<GDALDataset&>(dataset).GetDriver();
  if (driver && std::string(driver->GetDescription()) == "ESRI Shapefile" && name.size() > 10) {
    const std::string cut = name.substr(0, 10);
    why += ": a Shapefile cuts field names to 10 characters";
    if (definition.GetFieldIndex(cut.c_str()) >= 0) why += " (it holds " + cut + ")";
    why +=
        ", so it cannot hold " + name + "; write the trees as GeoPackage (.gpkg), GeoJSON or CSV";
  }
  return why;
}

std::vector<FacetTree> read_ogr_trees(const std::filesystem::path& file,
                                      const std::vector<std::string>& models) {
  prepare_gdal();
  const GdalErrorTrap trap;
  const std::string path = file.string();
  GdalDataset dataset(GDALDataset::FromHandle(
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  if (!dataset)
    throw input_error(path, "the trees file is neither a .csv nor a vector file OGR reads");
  std::vector<FacetTree> trees;
  for (int l = 0; l < dataset->GetLayerCount(); ++l) {
    OGRLayer* layer = dataset->GetLayer(l);
    std::unique_ptr<OGRCoordinateTransformation> to_wgs84;
    if (const OGRSpatialReference* crs = layer->GetSpatialRef()) {
      to_wgs84 = transformation_to_wgs84(*crs);
      if (!to_wgs84)
        throw input_error(path,
                          "layer " + std::to_string(l) + ": its CRS cannot be brought to WGS84");
    }
    const OGRFeatureDefn* definition = layer->GetLayerDefn();
    int fields[3];
    const char* names[3] = {"model", "rotation_deg", "scale"};
    for (int i = 0; i < 3; ++i) {
      fields[i] = definition->GetFieldIndex(names[i]);
      if (fields[i] < 0)
        throw input_error(path, missing_attribute(*dataset, *definition, l, names[i]));
    }
    const int height = definition->GetFieldIndex("z_m");  // optional
    layer->ResetReading();
    for (std::unique_ptr<OGRFeature> feature(layer->GetNextFeature()); feature;
         feature.reset(layer->GetNextFeature())) {
      const std::string place = path + ": feature " + std::to_string(feature->GetFID());
      OGRGeometry* geometry = feature->GetGeometryRef();
      if (!geometry || wkbFlatten(geometry->getGeometryType()) != wkbPoint)
        throw input_error(place, "a tree is a point");
      if (to_wgs84 && geometry->transform(to_wgs84.get()) != OGRERR_NONE)
        throw input_error(place, "its point cannot be brought to WGS84");
      const OGRPoint& point = *geometry->toPoint();
      FacetTree tree;
      tree.lon_deg = point.getX();
      tree.lat_deg = point.getY();
      tree.model = model_number(feature->GetFieldAsString(fields[0]), models, place);
      tree.rotation_deg = number_field(*feature, fields[1], "rotation_deg", place);
      tree.scale = number_field(*feature, fields[2], "scale", place);
      if (height >= 0 && feature->IsFieldSetAndNotNull(height))
        tree.z_m = number_field(*feature, height, "z_m", place);
      check_tree(tree, place);
      trees.push_back(tree);
    }
  }
  return trees;
}

}  // namespace

std::vector<FacetTree> read_facet_trees(const std::filesystem::path& file,
                                        const std::vector<std::string>& models,
                                        const std::optional<PlaneSettings>& plane) {
  std::string extension = file.extension().string();
  std::transform(extension.begin(), extension.end(), extension.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  std::vector<FacetTree> trees;
  if (extension == ".csv") {
    trees = read_csv_trees(file, models, plane);
  } else {
    require_input_file(file.string(), "the trees file");
    trees = read_ogr_trees(file, models);
  }
  if (trees.empty()) throw input_error(file.string(), "the trees file lists no trees");
  return trees;
}

}  // namespace glaswave
