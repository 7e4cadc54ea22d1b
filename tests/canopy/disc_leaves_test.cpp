// Disc leaf files (PRODUCT.md section 13: RAMI's `*.def`, one disc a line `radius x y z nx ny nz`)
// and the trees file's z_m column: read back to float precision, and every malformed line
// refused in one line naming the file and the line.
#include <gdal_priv.h>
#include <gtest/gtest.h>
#include <ogrsf_frmts.h>

#include <cmath>
#include <fstream>
#include <optional>
#include <string>

#include "canopy/facet_trees.hpp"
#include "core/error.hpp"
#include "tests/scratch_dir.hpp"

namespace glaswave {
namespace {

std::filesystem::path write(const std::filesystem::path& file, const std::string& text) {
  std::ofstream(file, std::ios::binary) << text;
  return file;
}

std::string refusal(const std::filesystem::path& file) {
  try {
    read_disc_leaves(file, "sphere");
  } catch (const Error& e) {
    EXPECT_EQ(e.kind(), ErrorKind::input);
    const std::string message = e.what();
    EXPECT_EQ(message.find('\n'), std::string::npos) << message;
    return message;
  }
  ADD_FAILURE() << "not refused";
  return "";
}

TEST(DiscLeaves, RamisLinesAreReadAndTheirNormalsMadeUnit) {
  test_support::ScratchDir dir;
  // Spaces or tabs, a comment, a blank line, CRLF ends, a normal of length 5, no final newline.
  const auto file = write(dir.path() / "HET01.def",
                          "# radius x y z nx ny nz\n0.1 1.5 -2 10.25 0 0 1\r\n\n"
                          "0.05\t0\t0\t-3\t3 0 4\n0.2 0 0 0 0 -1 0");
  EXPECT_TRUE(is_disc_leaf_file(file));
  EXPECT_TRUE(is_disc_leaf_file("A.DEF"));
  EXPECT_FALSE(is_disc_leaf_file("tree.obj"));
  const DiscLeaves leaves = read_disc_leaves(file, "sphere");
  ASSERT_EQ(leaves.size(), 3u);
  const std::vector<float> discs{1.5f,  -2.0f, 10.25f, 0.1f, 0.0f, 0.0f,
                                 -3.0f, 0.05f, 0.0f,   0.0f, 0.0f, 0.2f};
  const std::vector<float> normals{0.0f, 0.0f, 1.0f, 0.6f, 0.0f, 0.8f, 0.0f, -1.0f, 0.0f};
  EXPECT_EQ(leaves.discs_m, discs);
  for (std::size_t i = 0; i < normals.size(); ++i)
    EXPECT_NEAR(leaves.normals[i], normals[i], 1e-7) << i;
}

TEST(DiscLeaves, MalformedLinesAreRefusedNamingTheFileAndLine) {
  test_support::ScratchDir dir;
  const auto file = dir.path() / "bad.def";
  const std::string good = "0.1 0 0 1 0 0 1\n";
  struct Case {
    std::string text, expected;
  };
  for (const Case& c :
       {Case{good + "0.1 0 0 1 0 0\n", "bad.def:2: a disc leaf is 7 numbers"},
        Case{good + good + "0.1 0 0 1 0 0 1 7\n", "bad.def:3:"},
        Case{"0.1 0 0 one 0 0 1\n", "bad.def:1: field 4"},
        Case{"0.1 0 0 nan 0 0 1\n", "not a finite number"},
        Case{"0 0 0 1 0 0 1\n", "bad.def:1: the radius"},
        Case{"-0.1 0 0 1 0 0 1\n", "the radius must be in (0, 1000]"},
        Case{"0.1 0 0 2000 0 0 1\n", "beyond 1 km"},
        Case{"0.1 0 0 1 0 0 0\n", "bad.def:1: the normal"},
        Case{"0.1 0 0 1 1e308 1e308 0\n", "the normal"}, Case{"# nothing\n\n", "hold no disc"},
        Case{std::string(5000, '1') + "\n", "longer than 4096"}}) {
    write(file, c.text);
    const std::string message = refusal(file);
    EXPECT_NE(message.find(c.expected), std::string::npos) << message;
  }
  const std::string message = refusal(dir.path() / "absent.def");
  EXPECT_NE(message.find("absent.def"), std::string::npos) << message;
}

// The trees file's z_m column: the model's origin above the ground, 0 when the column is absent;
// out of [0, 1000] m refused at its row.
TEST(DiscLeaves, TheTreesFilesHeightColumnFloatsAModel) {
  test_support::ScratchDir dir;
  const PlaneSettings plane{45.0, 7.0, 0.0, 0.0, 0.0};
  write(dir.path() / "floating.csv",
        "x,y,model,rotation_deg,scale,z_m\n0,0,sphere,0,1,12.5\n10,0,sphere,0,1,0\n");
  const std::vector<FacetTree> trees =
      read_facet_trees(dir.path() / "floating.csv", {"sphere"}, plane);
  ASSERT_EQ(trees.size(), 2u);
  EXPECT_EQ(trees[0].z_m, 12.5);
  EXPECT_EQ(trees[1].z_m, 0.0);
  write(dir.path() / "standing.csv", "lon,lat,model,rotation_deg,scale\n7,45,sphere,0,1\n");
  EXPECT_EQ(read_facet_trees(dir.path() / "standing.csv", {"sphere"}, plane).at(0).z_m, 0.0);
  for (const auto& [text, expected] :
       {std::pair<std::string, std::string>{"x,y,model,rotation_deg,scale,z_m\n0,0,sphere,0,1,-1\n",
                                            "bad.csv:2: z_m must be in [0, 1000]"},
        {"x,y,model,rotation_deg,scale,z_m\n0,0,sphere,0,1\n", "bad.csv:2: expected 6 values"},
        {"x,y,model,rotation_deg,scale,height\n0,0,sphere,0,1,3\n", "bad.csv:1: expected the"}}) {
    write(dir.path() / "bad.csv", text);
    try {
      read_facet_trees(dir.path() / "bad.csv", {"sphere"}, plane);
      ADD_FAILURE() << text;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
  }
}

// Issue 42: a trees layer OGR reads took a non-numeric rotation_deg as 0 (the CSV reader refuses
// it); a Shapefile, whose field names are cut to 10 characters, cannot hold rotation_deg, and the
// error named the attribute missing without saying why.
TEST(FacetTreesLayer, NumbersAreReadWholeAndAShapefileSaysWhyItCannotHoldRotation) {
  test_support::ScratchDir dir;
  auto geojson = [&](const std::string& rotation) {
    return write(dir.path() / "trees.geojson",
                 R"({"type": "FeatureCollection", "features": [{"type": "Feature", )"
                 R"("geometry": {"type": "Point", "coordinates": [7, 45]}, "properties": )"
                 R"({"model": "sphere", "rotation_deg": )" +
                     rotation + R"(, "scale": 1}}]})");
  };
  auto message = [](const std::filesystem::path& file) -> std::string {
    try {
      read_facet_trees(file, {"sphere"}, std::nullopt);
    } catch (const Error& e) {
      EXPECT_EQ(e.kind(), ErrorKind::input);
      return e.what();
    }
    return "";
  };
  EXPECT_EQ(read_facet_trees(geojson("30"), {"sphere"}, std::nullopt).at(0).rotation_deg, 30.0);
  EXPECT_EQ(read_facet_trees(geojson("\"12.5\""), {"sphere"}, std::nullopt).at(0).rotation_deg,
            12.5);
  for (const char* text : {"\"abc\"", "\"12 deg\"", "\"\""}) {
    const std::string refused = message(geojson(text));
    EXPECT_NE(refused.find("trees.geojson: feature 0: rotation_deg is"), std::string::npos)
        << text << " | " << refused;
  }
  EXPECT_NE(message(geojson("null")).find("rotation_deg is empty"), std::string::npos);

  // A Shapefile written with a rotation_deg field: GDAL cuts it to rotation_d.
  const std::string shapefile = (dir.path() / "trees.shp").string();
  {
    GDALAllRegister();
    GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("ESRI Shapefile");
    ASSERT_NE(driver, nullptr);
    GDALDataset* data = driver->Create(shapefile.c_str(), 0, 0, 0, GDT_Unknown, nullptr);
    ASSERT_NE(data, nullptr);
    OGRLayer* layer = data->CreateLayer("trees", nullptr, wkbPoint, nullptr);
    for (const char* name : {"model", "rotation_deg", "scale"}) {
      OGRFieldDefn field(name, std::string(name) == "model" ? OFTString : OFTReal);
      layer->CreateField(&field);
    }
    GDALClose(data);
  }
  EXPECT_NE(message(shapefile).find("layer 0 has no attribute rotation_deg (trees need model, "
                                    "rotation_deg and scale): a Shapefile cuts field names to 10 "
                                    "characters (it holds rotation_d), so it cannot hold "
                                    "rotation_deg; write the trees as GeoPackage (.gpkg), "
                                    "GeoJSON or CSV"),
            std::string::npos)
      << message(shapefile);
}

}  // namespace
}  // namespace glaswave
