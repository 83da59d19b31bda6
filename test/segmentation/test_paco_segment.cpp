// The paco_segment tool: good input gives exit 0 and a labelled PCD; bad input gives a non-zero
// exit, a message, and no output file.
#include "segmentation_fixtures.h"
#include "shapes.h"
#include "test_support.h"

#include <paco/io/cloud_io.h>
#include <paco/io/vertex_groups_io.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <set>
#include <string>

namespace paco {
namespace {

using paco::test::quoted;

void writeBoxCloud(const std::string& path, bool with_normals) {
  const auto box = test::sampleShape(test::makeBox({0, 0, 0}, {2.0, 1.5, 1.0}), 3000, 21);
  io::LabelledCloud cloud;
  cloud.points = *box.cloud;
  cloud.has_normals = with_normals;
  if (!with_normals)
    for (auto& p : cloud.points) p.normal_x = p.normal_y = p.normal_z = 0.0f;
  io::saveCloud(path, cloud);
}

TEST(PacoSegment, WritesALabelledPcdAndVertexGroups) {
  test::TempDir dir;
  const std::string input = dir.file("box.ply"), output = dir.file("labelled.pcd"), vg = dir.file("planes.vg");
  writeBoxCloud(input, true);
  std::string log;
  const int rc = test::runCommand(quoted(test::toolPath("paco_segment")) + " " + quoted(input) + " -o " +
                                      quoted(output) + " --vg " + quoted(vg),
                                  &log);
  ASSERT_EQ(rc, 0) << log;
  EXPECT_NE(log.find("6 planes"), std::string::npos) << log;
  EXPECT_NE(log.find("coverage"), std::string::npos) << log;
  const io::LabelledCloud labelled = io::loadCloud(output);
  ASSERT_EQ(labelled.points.size(), 3000u);
  ASSERT_TRUE(labelled.hasLabels());
  std::set<int> labels(labelled.labels.begin(), labelled.labels.end());
  labels.erase(-1);
  EXPECT_EQ(labels, (std::set<int>{0, 1, 2, 3, 4, 5}));
  const io::VertexGroups groups = io::loadVertexGroups(vg);
  EXPECT_EQ(groups.segmentation.size(), 6u);
  EXPECT_FALSE(std::filesystem::exists(dir.file("labelled.partial.pcd")));
}

// A room scanned from inside, normals facing into it: as the other tools, paco_segment turns them
// outwards, so that the planes it writes face out of the room's volume (the floor down, the ceiling
// up) and paco_assemble builds the room from them; --keep-inward-normals keeps them as given.
TEST(PacoSegment, TurnsTheNormalsOfARoomScannedFromInsideOutwards) {
  test::TempDir dir;
  io::LabelledCloud room;
  room.has_normals = true;
  room.points = *test::scanLShapedRoomFromInside(6000, 5);
  io::saveCloud(dir.file("room.pcd"), room);
  const std::string tool = quoted(test::toolPath("paco_segment")) + " " + quoted(dir.file("room.pcd")) + " -o " +
                           quoted(dir.file("labelled.pcd")) + " --vg " + quoted(dir.file("planes.vg"));
  for (const bool keep : {false, true}) {
    SCOPED_TRACE(keep ? "kept" : "turned");
    std::string log;
    ASSERT_EQ(test::runCommand(tool + (keep ? " --keep-inward-normals" : ""), &log), 0) << log;
    EXPECT_NE(log.find(keep ? "kept so (--keep-inward-normals)" : "turned outwards"), std::string::npos) << log;
    const io::VertexGroups groups = io::loadVertexGroups(dir.file("planes.vg"));
    std::size_t floors = 0;
    for (const Plane& plane : groups.segmentation.planes) {
      if (std::abs(plane.normal.z()) < 0.99 || std::abs(plane.offset) > 1e-3) continue;  // the floor, z = 0
      ++floors;
      EXPECT_NEAR(plane.normal.z(), keep ? 1.0 : -1.0, 1e-3);
    }
    EXPECT_EQ(floors, 1u);
    const io::LabelledCloud labelled = io::loadCloud(dir.file("labelled.pcd"));
    ASSERT_EQ(labelled.points.size(), room.points.size());
    for (std::size_t i = 0; i < room.points.size(); ++i)
      ASSERT_EQ(labelled.points[i].getNormalVector3fMap(),
                (keep ? 1.0f : -1.0f) * room.points[i].getNormalVector3fMap())
          << i;
  }
}

// A cloud above --max-points: a thinned copy is segmented, and every point gets the label of its
// nearest kept point on that plane, and its estimated normal. The six faces come out as six
// planes, each point on its own face's plane.
TEST(PacoSegment, ACloudAboveMaxPointsIsLabelledFromAThinnedCopy) {
  test::TempDir dir;
  const auto box = test::sampleShape(test::makeBox({0, 0, 0}, {2.0, 1.5, 1.0}), 6000, 23);
  io::LabelledCloud cloud;
  cloud.points = *box.cloud;
  cloud.has_normals = false;
  io::saveCloud(dir.file("box.xyz"), cloud);
  std::string log;
  ASSERT_EQ(test::runCommand(quoted(test::toolPath("paco_segment")) + " " + quoted(dir.file("box.xyz")) + " -o " +
                                 quoted(dir.file("labelled.pcd")) + " --vg " + quoted(dir.file("planes.vg")) +
                                 " --max-points 1500",
                             &log),
            0)
      << log;
  EXPECT_NE(log.find("thin: segmenting"), std::string::npos) << log;
  EXPECT_NE(log.find("of 6000 points"), std::string::npos) << log;
  EXPECT_NE(log.find("gocopp: 6 planes"), std::string::npos) << log;
  const io::LabelledCloud labelled = io::loadCloud(dir.file("labelled.pcd"));
  ASSERT_EQ(labelled.points.size(), 6000u);
  ASSERT_TRUE(labelled.hasLabels());
  const io::VertexGroups groups = io::loadVertexGroups(dir.file("planes.vg"));
  ASSERT_EQ(groups.segmentation.size(), 6u);
  // Every labelled point lies on its label's plane, and that is its own face's plane but near an
  // edge, where a point lies on both faces' planes (within 0.011, the inlier distance, of the
  // edge: about 1.5 % of the points).
  std::size_t labelled_points = 0, on_its_face = 0;
  for (std::size_t i = 0; i < labelled.points.size(); ++i) {
    const int label = labelled.labels[i];
    if (label < 0) continue;
    ++labelled_points;
    const Plane& plane = groups.segmentation.planes[static_cast<std::size_t>(label)];
    EXPECT_LT(std::abs(plane.signedDistance(labelled.points[i].getVector3fMap().cast<double>())), 0.02) << i;
    on_its_face += std::abs(plane.normal.dot(box.plane_normals[static_cast<std::size_t>(box.labels[i])])) > 0.99;
  }
  EXPECT_GT(labelled_points, 5880u);  // 98 %
  EXPECT_GT(on_its_face, 5820u);      // 97 %
  std::size_t unit_normals = 0;
  for (const auto& p : labelled.points) unit_normals += std::abs(p.getNormalVector3fMap().norm() - 1.0f) < 1e-3f;
  EXPECT_EQ(unit_normals, 6000u);
  // Without thinning (0) every point is segmented, as before.
  ASSERT_EQ(test::runCommand(quoted(test::toolPath("paco_segment")) + " " + quoted(dir.file("box.xyz")) + " -o " +
                                 quoted(dir.file("all.pcd")) + " --max-points 0",
                             &log),
            0)
      << log;
  EXPECT_EQ(log.find("thin:"), std::string::npos) << log;
  EXPECT_EQ(test::runCommand(quoted(test::toolPath("paco_segment")) + " " + quoted(dir.file("box.xyz")) + " -o " +
                                 quoted(dir.file("few.pcd")) + " --max-points 100",
                             &log),
            2);
  EXPECT_NE(log.find("--max-points must be 0 (every point) or at least 256, got 100"), std::string::npos) << log;
}

TEST(PacoSegment, EstimatesMissingNormalsWithAnyBackend) {
  test::TempDir dir;
  const std::string input = dir.file("box.xyz"), output = dir.file("labelled.pcd");
  writeBoxCloud(input, false);
  std::string log;
  const int rc = test::runCommand(quoted(test::toolPath("paco_segment")) + " " + quoted(input) + " -o " +
                                      quoted(output) + " --backend region-growing",
                                  &log);
  ASSERT_EQ(rc, 0) << log;
  EXPECT_NE(log.find("region-growing: 6 planes"), std::string::npos) << log;
  const io::LabelledCloud labelled = io::loadCloud(output);
  EXPECT_TRUE(labelled.has_normals);
}

// A box with Gaussian noise of 1 % of its diagonal, far above the default inlier distance (0.4 %
// of it): planes of 100 points or more then hold few of the points, unless --noise-adaptation
// widens the distance to the noise.
TEST(PacoSegment, NoiseAdaptationWidensTheInlierDistanceOnANoisyScan) {
  test::TempDir dir;
  const std::string input = dir.file("noisy.pcd");
  auto box = test::sampleShape(test::makeBox({0, 0, 0}, {2.0, 1.5, 1.0}), 3000, 21);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.01f * std::sqrt(4.0f + 2.25f + 1.0f));
  io::LabelledCloud cloud;
  cloud.points = *box.cloud;
  cloud.has_normals = true;
  for (auto& p : cloud.points)
    for (int a = 0; a < 3; ++a) p.getVector3fMap()[a] += noise(rng);
  io::saveCloud(input, cloud);
  const std::string tool = quoted(test::toolPath("paco_segment")) + " " + quoted(input) + " --min-points 100 -o ";
  auto labelledShare = [](const std::string& path) {
    const auto labels = io::loadCloud(path).labels;
    return static_cast<double>(std::count_if(labels.begin(), labels.end(), [](int l) { return l >= 0; })) /
           static_cast<double>(labels.size());
  };

  std::string log;
  ASSERT_EQ(test::runCommand(tool + quoted(dir.file("fixed.pcd")), &log), 0) << log;
  EXPECT_EQ(log.find("inlier distance raised"), std::string::npos) << log;
  EXPECT_LT(labelledShare(dir.file("fixed.pcd")), 0.5) << log;

  ASSERT_EQ(test::runCommand(tool + quoted(dir.file("adapted.pcd")) + " --noise-adaptation 2.8", &log), 0) << log;
  EXPECT_NE(log.find("gocopp: 6 planes"), std::string::npos) << log;
  EXPECT_NE(log.find("inlier distance raised to"), std::string::npos) << log;
  EXPECT_GT(labelledShare(dir.file("adapted.pcd")), 0.9) << log;

  EXPECT_EQ(test::runCommand(tool + quoted(dir.file("bad.pcd")) + " --noise-adaptation -1", &log), 2) << log;
  EXPECT_NE(log.find("--noise-adaptation"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.pcd")));
}

TEST(PacoSegment, HelpExitsZero) {
  std::string log;
  EXPECT_EQ(test::runCommand(quoted(test::toolPath("paco_segment")) + " --help", &log), 0);
  EXPECT_NE(log.find("--backend"), std::string::npos) << log;
  EXPECT_NE(log.find("--lambda-simplicity"), std::string::npos) << log;
}

TEST(PacoSegment, BadInputFailsWithAMessageAndNoOutput) {
  test::TempDir dir;
  const std::string output = dir.file("labelled.pcd");
  const std::string tool = quoted(test::toolPath("paco_segment"));
  std::string log;

  // Missing file.
  EXPECT_NE(test::runCommand(tool + " " + quoted(dir.file("missing.ply")) + " -o " + quoted(output), &log), 0);
  EXPECT_NE(log.find("error"), std::string::npos) << log;

  // Garbage file.
  test::writeBytes(dir.file("garbage.pcd"), "this is not a point cloud\n");
  EXPECT_NE(test::runCommand(tool + " " + quoted(dir.file("garbage.pcd")) + " -o " + quoted(output), &log), 0);
  EXPECT_NE(log.find("error"), std::string::npos) << log;

  // Two points: fewer than a plane needs.
  test::writeBytes(dir.file("two.xyz"), "0 0 0\n1 0 0\n");
  EXPECT_NE(test::runCommand(tool + " " + quoted(dir.file("two.xyz")) + " -o " + quoted(output), &log), 0);
  EXPECT_NE(log.find("at least 3"), std::string::npos) << log;

  // Unknown backend and bad parameter: usage errors.
  writeBoxCloud(dir.file("box.ply"), true);
  EXPECT_EQ(test::runCommand(tool + " " + quoted(dir.file("box.ply")) + " -o " + quoted(output) + " --backend hough", &log), 2);
  EXPECT_NE(log.find("unknown planar segmenter"), std::string::npos) << log;
  EXPECT_EQ(test::runCommand(tool + " " + quoted(dir.file("box.ply")) + " -o " + quoted(output) + " --epsilon -1", &log), 2);
  EXPECT_EQ(test::runCommand(tool + " " + quoted(dir.file("box.ply")), &log), 2);

  EXPECT_FALSE(std::filesystem::exists(output));
  EXPECT_FALSE(std::filesystem::exists(dir.file("labelled.partial.pcd")));
}

}  // namespace
}  // namespace paco
