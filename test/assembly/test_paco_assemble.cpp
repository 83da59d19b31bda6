// Runs the built paco_assemble tool: a good input gives a closed mesh, bad inputs exit non-zero
// and leave no file behind.
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>
#include <paco/io/vertex_groups_io.h>

#include "shape_primitives.h"
#include "shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

namespace {

using paco::test::TempDir;

using paco::test::quoted;
std::string tool() { return paco::test::toolPath("paco_assemble"); }
bool toolBuilt() { return std::filesystem::exists(tool()); }

TEST(PacoAssemble, AssemblesVertexGroupsWithBothBackends) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_assemble is not built";
  TempDir dir;
  const paco::SurfaceMesh truth = paco::test::makeLBracket();
  paco::io::saveVertexGroups(dir.file("bracket.bvg"), paco::io::toVertexGroups(paco::test::primitivesOf(truth)));
  for (const std::string options : {"--backend polyfit", "--backend polyfit --no-warm-start", "--backend cell-complex"}) {
    SCOPED_TRACE(options);
    const bool polyfit = options.find("polyfit") != std::string::npos;
    const bool warm_start = polyfit && options.find("--no-warm-start") == std::string::npos;
    // The cell complex's mesh goes to STL, which the tool writes as well.
    const std::string mesh_path = dir.file(std::string("bracket_") + (polyfit ? "polyfit.obj" : "cell_complex.stl"));
    std::string out;
    const int rc = paco::test::runCommand(tool() + " " + quoted(dir.file("bracket.bvg")) + " -o " + quoted(mesh_path) +
                                              " " + options, &out);
    ASSERT_EQ(rc, 0) << out;
    EXPECT_NE(out.find("closed"), std::string::npos) << out;
    EXPECT_NE(out.find("8 planes used"), std::string::npos) << out;
    // One line on the backend's work, and for PolyFit whether CBC started from the cell complex.
    EXPECT_EQ(out.find("polyfit: ") != std::string::npos, polyfit) << out;
    EXPECT_EQ(out.find("cell-complex: ") != std::string::npos, !polyfit) << out;
    EXPECT_EQ(out.find("started from the cell complex's surface") != std::string::npos, warm_start) << out;
    const paco::SurfaceMesh mesh = paco::io::loadMesh(mesh_path);
    EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
    EXPECT_NEAR(paco::signedVolume(mesh), paco::signedVolume(truth), 0.01 * paco::signedVolume(truth));
  }
}

TEST(PacoAssemble, AssemblesALabelledCloud) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_assemble is not built";
  TempDir dir;
  const auto primitives = paco::test::primitivesOf(paco::test::makeChamferedCube());
  paco::io::LabelledCloud cloud;
  paco::flattenPrimitives(primitives, cloud.points, cloud.labels);
  for (auto& label : cloud.labels) label += 100;  // labels need not start at 0
  cloud.has_normals = true;
  paco::io::saveCloud(dir.file("cube.ply"), cloud);
  std::string out;
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("cube.ply")) + " -o " + quoted(dir.file("cube.off")) +
                                       " --backend cell-complex", &out), 0) << out;
  EXPECT_NE(out.find("7 planes used"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(dir.file("cube.off")));
}

// The L-shaped room's planes facing into the room (as a scanner inside it gives them): the tool
// turns them, says so, and builds the room's volume; --keep-inward-normals keeps them as given.
TEST(PacoAssemble, TurnsPrimitivesOfARoomThatFaceInwards) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_assemble is not built";
  TempDir dir;
  paco::io::saveVertexGroups(dir.file("room.bvg"), paco::io::toVertexGroups(
                                                     paco::test::primitivesFacingInwards(paco::test::makeLShapedRoom())));
  for (const bool keep : {false, true}) {
    SCOPED_TRACE(keep ? "kept" : "turned");
    const std::string mesh_path = dir.file(keep ? "kept.obj" : "turned.obj");
    std::string out;
    ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("room.bvg")) + " -o " + quoted(mesh_path) +
                                         " --backend cell-complex" + (keep ? " --keep-inward-normals" : ""),
                                     &out),
              0)
        << out;
    EXPECT_EQ(out.find("turned outwards") != std::string::npos, !keep) << out;
    const paco::SurfaceMesh mesh = paco::io::loadMesh(mesh_path);
    const double volume_error = std::abs(paco::signedVolume(mesh) - paco::test::kLShapedRoomVolume);
    if (keep)
      EXPECT_GT(volume_error, 0.01 * paco::test::kLShapedRoomVolume);
    else
      EXPECT_LT(volume_error, 0.001 * paco::test::kLShapedRoomVolume);
  }
}

TEST(PacoAssemble, FailsCleanlyWithoutPartialOutput) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_assemble is not built";
  TempDir dir;
  auto primitives = paco::test::primitivesOf(paco::test::makeBox({0, 0, 0}, {1, 1, 1}));
  primitives.resize(3);
  paco::io::saveVertexGroups(dir.file("three.vg"), paco::io::toVertexGroups(primitives));
  std::string out;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("three.vg")) + " -o " + quoted(dir.file("m.obj")), &out), 1);
  EXPECT_NE(out.find("too-few-planes"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.obj")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.partial.obj")));

  paco::io::LabelledCloud unlabelled;
  unlabelled.points.resize(10);
  paco::io::saveCloud(dir.file("plain.pcd"), unlabelled);
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("plain.pcd")) + " -o " + quoted(dir.file("m.obj")), &out), 1);
  EXPECT_NE(out.find("no per-point plane labels"), std::string::npos) << out;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("missing.vg")) + " -o " + quoted(dir.file("m.obj")), &out), 1);
  EXPECT_FALSE(std::filesystem::exists(dir.file("m.obj")));
}

TEST(PacoAssemble, UsageErrorsAndHelp) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_assemble is not built";
  std::string out;
  EXPECT_EQ(paco::test::runCommand(tool() + " --help", &out), 0);
  EXPECT_NE(out.find("--backend"), std::string::npos) << out;
  EXPECT_NE(out.find("--time-limit"), std::string::npos) << out;
  EXPECT_EQ(paco::test::runCommand(tool() + " in.vg", &out), 2);
  EXPECT_EQ(paco::test::runCommand(tool() + " in.vg -o out.obj --backend ksr", &out), 2);
  EXPECT_NE(out.find("unknown assembly backend"), std::string::npos) << out;
  EXPECT_EQ(paco::test::runCommand(tool() + " in.vg -o out.3mf", &out), 2);
  EXPECT_NE(out.find("-o must name a .obj, .off, .ply or .stl file"), std::string::npos) << out;
}

}  // namespace
