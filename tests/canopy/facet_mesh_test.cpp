// Facet trees' meshes that Assimp would read unchecked (issue 42): faces naming vertices the mesh
// lacks, a header declaring more faces than its file holds, and files the model names (an OBJ's
// mtllib, a glTF's buffer) that are FIFOs. Each is refused in one line naming the file, at once:
// never a crash, never a wait, never gigabytes reserved.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <utility>

#include "canopy/facet_trees.hpp"
#include "core/error.hpp"
#include "tests/cpu_time.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

std::filesystem::path write(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
  return file;
}

std::string refusal(const std::filesystem::path& file) {
  try {
    read_facet_mesh(file, "oak");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    return message;
  }
  return "";
}

std::string ply(const std::string& face_count, const std::string& faces) {
  return "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
         "property float z\nelement face " +
         face_count +
         "\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n" + faces;
}

TEST(FacetMesh, AReadablePlyIsRead) {
  test_support::ScratchDir dir;
  const FacetMesh mesh =
      read_facet_mesh(write(dir.path() / "ok.ply", ply("1", "3 0 1 2\n")), "oak");
  EXPECT_EQ(mesh.triangles.size(), 3u);
  EXPECT_EQ(mesh.vertices_m.size(), 9u);
}

TEST(FacetMesh, FacesNamingVerticesTheMeshLacksAreRefused) {
  test_support::ScratchDir dir;
  for (const char* face : {"3 0 1 100000000\n", "3 0 1 -5\n", "3 0 1 3\n"}) {
    const auto file = write(dir.path() / "bad.ply", ply("1", face));
    const std::string message = refusal(file);
    EXPECT_NE(message.find("bad.ply"), std::string::npos) << face << message;
  }
}

// Assimp 5.2 aborts in its triangulation on a face of no corner (mesh_fuzzer's binary PLY, ASCII
// here): before the fix this test ended the test program.
TEST(FacetMesh, AFaceOfNoCornerIsRefusedBeforeAssimpTriangulates) {
  test_support::ScratchDir dir;
  const std::pair<const char*, const char*> cases[] = {{"1", "0\n"}, {"2", "3 0 1 2\n0\n"}};
  for (const auto& [count, faces] : cases) {
    const auto file = write(dir.path() / "empty-face.ply", ply(count, faces));
    const std::string message = refusal(file);
    EXPECT_NE(message.find("empty-face.ply: the mesh of model \"oak\": face "), std::string::npos)
        << message;
    EXPECT_NE(message.find("names no vertex"), std::string::npos) << message;
  }
}

// Assimp takes any file beginning with the bytes "ply" for a PLY; one whose first line was more
// ("plyply", mesh_fuzzer) escaped glaswave's header checks and Assimp read its header for ever; so
// did a header whose end_header followed a carriage return.
TEST(FacetMesh, APlyWhoseFirstLineIsMoreThanPlyIsRefused) {
  test_support::ScratchDir dir;
  const double cpu_before_s = test_support::cpu_used_s();
  const std::string message = refusal(write(dir.path() / "plyply.ply", "ply" + ply("1", "0\n")));
  EXPECT_NE(message.find("plyply.ply: the mesh of model \"oak\": its PLY header's first line is "
                         "not the word ply alone"),
            std::string::npos)
      << message;
  EXPECT_LT(test_support::cpu_used_s() - cpu_before_s, 5.0);
  // A keyword after a carriage return or a space: Assimp read past the file's end for ever.
  for (const char* before : {"\r", " "}) {
    std::string text = ply("1", "3 0 1 2\n");
    text.insert(text.find("end_header"), before);
    EXPECT_NE(refusal(write(dir.path() / "cr.ply", text)).find("begins with a space or holds a "),
              std::string::npos);
  }
  // The word in capitals, or with a carriage return, is PLY's first line still.
  std::string upper = ply("1", "3 0 1 2\n");
  upper.replace(0, 4, "PLY\r\n");
  EXPECT_EQ(read_facet_mesh(write(dir.path() / "upper.ply", upper), "oak").triangles.size(), 3u);
}

TEST(FacetMesh, AHeaderDeclaringMoreThanItsFileHoldsIsRefusedAtOnce) {
  test_support::ScratchDir dir;
  const double cpu_before_s = test_support::cpu_used_s();
  const auto file = write(dir.path() / "big.ply", ply("1000000000", "3 0 1 2\n"));
  ASSERT_LT(std::filesystem::file_size(file), 200u);
  const std::string message = refusal(file);
  EXPECT_NE(message.find("declares 1000000000 face elements"), std::string::npos) << message;
  EXPECT_NE(message.find("big.ply"), std::string::npos) << message;
  EXPECT_NE(refusal(write(dir.path() / "sign.ply", ply("-1", ""))).find("not a whole number"),
            std::string::npos);
  EXPECT_LT(test_support::cpu_used_s() - cpu_before_s, 5.0);
  // Binary: 4 bytes a float; 3 vertices of 12 bytes are 36, here 35.
  const std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  EXPECT_NE(refusal(write(dir.path() / "short.ply", header + std::string(35, '\0')))
                .find("more than its 35 bytes"),
            std::string::npos);
}

// An OFF header's counts, as PLY's (mesh_fuzzer: 6.7e99 vertices in 300 bytes, for which Assimp
// asked 34 GB): 3 vertices and a face need at least 3 x 6 + 4 bytes ("0 0 0\n", "1 0\n").
TEST(FacetMesh, AnOffHeaderDeclaringMoreThanItsFileHoldsIsRefused) {
  test_support::ScratchDir dir;
  const std::string plate = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  EXPECT_EQ(read_facet_mesh(write(dir.path() / "plate.off", plate), "oak").triangles.size(), 3u);
  const std::string message =
      refusal(write(dir.path() / "big.off", "OFF\n" + std::string(100, '6') + " 1 0\n0 0 0\n"));
  EXPECT_NE(message.find("big.off"), std::string::npos) << message;
  EXPECT_NE(message.find("declares 66666666666666666666... (100 digits) in its OFF header, more "
                         "than its 115 bytes hold"),
            std::string::npos)
      << message;
  // mesh_fuzzer's second: the count a line further on, after one on the keyword's line.
  EXPECT_NE(refusal(write(dir.path() / "later.off", "OFF 2\n\n" + std::string(100, '6') + " 1\n"))
                .find("(100 digits)"),
            std::string::npos);
  // Its counts without the keyword, which Assimp reads in a .off file, and a keyword run on into
  // the first count ("OFF02").
  EXPECT_NE(refusal(write(dir.path() / "bare.off", std::string(100, '6') + " 1 0\n0 0 0\n"))
                .find("(100 digits)"),
            std::string::npos);
  EXPECT_NE(refusal(write(dir.path() / "run_on.off", "OFF02\n\n" + std::string(100, '6') + "\n"))
                .find("(100 digits)"),
            std::string::npos);
  EXPECT_NE(refusal(write(dir.path() / "hash.off", "OFF 3#\n\n" + std::string(30, '6') + " 2\n"))
                .find("(30 digits) in its OFF header"),
            std::string::npos);
  // A comment line's numbers are not the header's.
  EXPECT_EQ(read_facet_mesh(
                write(dir.path() / "comment.off", "OFF\n# 2026 12 02\n" + plate.substr(4)), "oak")
                .triangles.size(),
            3u);
  // 5 vertices and a face need 34 bytes: 28 are refused.
  EXPECT_NE(refusal(write(dir.path() / "short.off", "OFF 5 1 0\n0 0 0\n1 0 0\n0 1 0\n"))
                .find("declares 5 vertices and 1 faces"),
            std::string::npos);
}

TEST(FacetMesh, FilesTheModelNamesFollowTheRegularFileRule) {
  test_support::ScratchDir dir;
  const auto fifo = dir.path() / "fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  // An OBJ's materials from a FIFO: Assimp's own check opened it and waited for ever.
  std::string message =
      refusal(write(dir.path() / "plate.obj", "mtllib fifo\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"));
  EXPECT_NE(message.find("plate.obj"), std::string::npos) << message;
  EXPECT_NE(message.find("FIFO"), std::string::npos) << message;
  // A glTF's buffer.
  message =
      refusal(write(dir.path() / "plate.gltf",
                    R"({"asset": {"version": "2.0"}, "buffers": [{"uri": "fifo", "byteLength": 36}],
          "bufferViews": [{"buffer": 0, "byteLength": 36}],
          "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                         "min": [0, 0, 0], "max": [1, 1, 0]}],
          "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
          "nodes": [{"mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0})"));
  EXPECT_NE(message.find("plate.gltf"), std::string::npos) << message;
  EXPECT_NE(message.find("FIFO"), std::string::npos) << message;
  // The same model with its buffer a regular file is read.
  std::string buffer(36, '\0');
  const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  buffer.assign(reinterpret_cast<const char*>(xyz), sizeof xyz);
  write(dir.path() / "plate.bin", buffer);
  std::string gltf;
  {
    std::ifstream in(dir.path() / "plate.gltf");
    gltf.assign(std::istreambuf_iterator<char>(in), {});
  }
  gltf.replace(gltf.find("\"fifo\""), 6, "\"plate.bin\"");
  EXPECT_EQ(read_facet_mesh(write(dir.path() / "plate.gltf", gltf), "oak").triangles.size(), 3u);
}

// A glTF of 200 000 nested arrays overflowed the stack of Assimp's recursive JSON parser; one of
// 256 levels, a string holding brackets and escaped quotes, is read on to the parser's own
// verdict.
// A GLB whose JSON chunk declares more bytes than the file holds: Assimp reserved them first
// (1.7 GB for a file of 105 bytes, mesh_fuzzer). glTF 1's binary header has its scene's length in
// the same four bytes.
TEST(FacetMesh, AGlbDeclaringAChunkBeyondItsFileIsRefusedAtOnce) {
  test_support::ScratchDir dir;
  const std::string json = R"({"asset": {"version": "2.0"}})";
  auto glb = [&](std::uint32_t version, std::uint32_t declared) {
    std::string bytes = "glTF";
    for (std::uint32_t word : {version, std::uint32_t(20 + json.size()), declared})
      for (int b = 0; b < 4; ++b) bytes += static_cast<char>(word >> (8 * b) & 0xff);
    return bytes + (version == 2 ? "JSON" : std::string(4, '\0')) + json;
  };
  for (std::uint32_t version : {1u, 2u}) {
    const std::string message = refusal(write(dir.path() / "big.glb", glb(version, 0x6a000198u)));
    EXPECT_NE(message.find("big.glb: the mesh of model \"oak\" declares a JSON chunk of "
                           "1778385304 bytes, more than its 49 bytes hold"),
              std::string::npos)
        << version << ": " << message;
  }
  // The length the file holds is Assimp's to read (no triangle here: refused, but not for size).
  const std::string message = refusal(write(dir.path() / "fits.glb", glb(2, json.size())));
  EXPECT_EQ(message.find("declares a JSON chunk"), std::string::npos) << message;
}

TEST(FacetMesh, GltfNestedDeeperThanItsLimitIsRefusedBeforeItIsParsed) {
  test_support::ScratchDir dir;
  const std::string deep = std::string(200000, '[') + std::string(200000, ']');
  std::string message = refusal(
      write(dir.path() / "deep.gltf", R"({"asset": {"version": "2.0"}, "extras": )" + deep + "}"));
  EXPECT_NE(message.find("deep.gltf: the mesh of model \"oak\" nests its JSON deeper than 256"),
            std::string::npos)
      << message;
  const std::string levels = std::string(255, '[') + std::string(255, ']');
  message = refusal(write(dir.path() / "fine.gltf", R"({"asset": {"version": "2.0"}, "extras": )" +
                                                        levels + R"(, "x": "[[\"[[[" })"));
  EXPECT_EQ(message.find("nests its JSON"), std::string::npos) << message;
}

}  // namespace
}  // namespace glaswave
