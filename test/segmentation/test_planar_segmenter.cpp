// PlanarSegmenter and its four backends on generated shapes with known planes, and bad input.
#include "segmentation_fixtures.h"
#include "shapes.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/segmentation/segmentation.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>
#include <string>

namespace paco {
namespace {

using test::LabelledSample;

LabelledSample cleanBox() {
  return test::sampleShape(test::makeBox({0, 0, 0}, {1.0, 0.8, 0.6}), 3000, 7);
}

LabelledSample partialLBracket() {
  SurfaceMesh mesh = test::makeLBracket();
  test::transformMesh(mesh, test::obliqueRotation(), {0.3, -0.2, 0.1});
  const LabelledSample full = test::sampleShape(mesh, 4000, 11);
  // Drop the 30 % of points nearest a viewpoint off one corner.
  return test::partialView(full, (test::obliqueRotation() * Eigen::Vector3d(1.6, -0.6, 1.2)).cast<float>(), 0.3);
}

// The box of cleanBox() with Gaussian noise of `fraction` of its diagonal on every coordinate;
// the points keep their faces' true normals, as the MFCAD scans with noise do.
LabelledSample noisyBox(double fraction) {
  LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1.0, 0.8, 0.6}), 3000, 12);
  const double diagonal = std::sqrt(1.0 + 0.64 + 0.36);
  std::mt19937 rng(5);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(fraction * diagonal));
  for (auto& p : *box.cloud)
    for (int a = 0; a < 3; ++a) p.getVector3fMap()[a] += noise(rng);
  return box;
}

class EveryBackend : public ::testing::TestWithParam<std::string> {};

TEST_P(EveryBackend, CleanBoxGivesSixPlanesWithinOneDegree) {
  const LabelledSample box = cleanBox();
  auto seg = makePlanarSegmenter<pcl::PointNormal>(GetParam());
  EXPECT_EQ(seg->name(), GetParam());
  seg->setInputCloud(box.cloud);
  PlanarSegmentation result;
  seg->segment(result);
  ASSERT_EQ(result.size(), 6u);
  ASSERT_NO_THROW(result.validate(box.cloud->size()));
  std::set<int> matched;
  for (const auto& plane : result.planes) {
    int best = -1;
    double best_cos = 0.0;
    for (std::size_t f = 0; f < box.plane_normals.size(); ++f) {
      const double c = plane.normal.dot(box.plane_normals[f]);  // oriented: outward like the samples
      if (c > best_cos) {
        best_cos = c;
        best = static_cast<int>(f);
      }
    }
    EXPECT_GT(best_cos, std::cos(paco::degreesToRadians(1.0))) << "plane normal " << plane.normal.transpose();
    matched.insert(best);
  }
  EXPECT_EQ(matched.size(), 6u) << "each face gets its own plane";
  EXPECT_GT(result.coverage(), 0.9);
}

TEST_P(EveryBackend, PartialLBracketFindsAllVisiblePlanes) {
  const LabelledSample bracket = partialLBracket();
  auto seg = makePlanarSegmenter<pcl::PointNormal>(GetParam());
  seg->setInputCloud(bracket.cloud);
  PlanarSegmentation result;
  seg->segment(result);
  const test::PlaneRecovery r = test::scoreRecovery(bracket, result);
  EXPECT_GE(r.visible, 6);  // the partial view still shows most faces
  EXPECT_EQ(r.found, r.visible);
  EXPECT_LT(r.worst_angle_deg, 1.0);
}

TEST_P(EveryBackend, BoxWithoutNormalsEstimatesThem) {
  const LabelledSample box = cleanBox();
  auto seg = makePlanarSegmenter<pcl::PointXYZ>(GetParam());
  seg->setInputCloud(test::withoutNormals(*box.cloud));
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_TRUE(seg->prepared().normals_estimated);
  const test::PlaneRecovery r = test::scoreRecovery(box, result);
  EXPECT_EQ(r.found, 6);
  EXPECT_LT(r.worst_angle_deg, 1.0);
}

TEST_P(EveryBackend, PlanesWithEstimatedNormalsFaceOutwardsAlsoInAConcaveCorner) {
  // The L-bracket's two inner faces lie on the far side of the box centre from the way they
  // face, so turning each estimated normal away from the centre gets them wrong; they must face
  // outwards like the rest, found through the edges they share with their neighbours.
  const LabelledSample bracket = partialLBracket();
  auto seg = makePlanarSegmenter<pcl::PointXYZ>(GetParam());
  seg->setInputCloud(test::withoutNormals(*bracket.cloud));
  PlanarSegmentation result;
  seg->segment(result);
  ASSERT_TRUE(seg->prepared().normals_estimated);
  const test::PlaneRecovery r = test::scoreRecovery(bracket, result);
  EXPECT_GE(r.found, 6);
  EXPECT_EQ(r.facing_inwards, 0);
}

TEST_P(EveryBackend, TheInnerFacesOfAThinChannelWithoutNormalsFaceIntoIt) {
  // A sheet-metal U channel 0.05 thick, turned off the axes: its rims are too thin to segment,
  // so no shared edge ties the three inner faces to the outer ones, and all three face the box
  // centre. Turned away from the centre they would face into the metal; rays through the walls
  // say otherwise. The RANSAC backends' segments also carry a false edge across a wall, which
  // ties the inner faces to the hull with the wrong parity until the rays split the group there.
  if (GetParam() == "region-growing")
    GTEST_SKIP() << "PCL region growing finds no plane on walls this thin (every neighbourhood holds both sides)";
  SurfaceMesh channel = test::makeUChannel(1.0, 0.6, 0.05, 1.0);
  test::transformMesh(channel, test::obliqueRotation(), {0.3, -0.2, 0.1});
  const LabelledSample sample = test::sampleShape(channel, 8000, 21);
  auto seg = makePlanarSegmenter<pcl::PointXYZ>(GetParam());
  seg->setInputCloud(test::withoutNormals(*sample.cloud));
  PlanarSegmentation result;
  seg->segment(result);
  ASSERT_TRUE(seg->prepared().normals_estimated);
  const test::PlaneRecovery r = test::scoreRecovery(sample, result, 300);
  EXPECT_EQ(r.visible, 6);  // the outer and inner faces of the web and of the two legs
  EXPECT_EQ(r.found, r.visible);
  EXPECT_EQ(r.facing_inwards, 0);
}

TEST_P(EveryBackend, NoisyBoxWithoutNormalsTakesNormalsFromMoreNeighbours) {
  // Noise of 1 % of the diagonal on every coordinate, about 40 % of the point spacing: from
  // 20 neighbours the estimated normals tilt so much that few points fit their face's plane.
  const LabelledSample box = noisyBox(0.01);
  const double diagonal = std::sqrt(1.0 + 0.64 + 0.36);
  auto seg = makePlanarSegmenter<pcl::PointXYZ>(GetParam());
  seg->setInputCloud(test::withoutNormals(*box.cloud));
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_EQ(seg->prepared().normal_neighbours_used, 40);
  // With the inlier band far below the noise, a segment holds only part of its face, so faces
  // are matched by plane: each needs a segment within 5 degrees, facing outwards, and within
  // 3 % of the diagonal (three times the noise).
  for (std::size_t f = 0; f < box.plane_normals.size(); ++f) {
    const Eigen::Vector3d& outward = box.plane_normals[f];
    double face_offset = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 0; i < box.labels.size(); ++i)
      if (box.labels[i] == static_cast<int>(f)) {
        face_offset -= outward.dot((*box.cloud)[i].getVector3fMap().cast<double>());
        ++count;
      }
    face_offset /= static_cast<double>(count);
    bool matched = false;
    for (const auto& plane : result.planes)
      matched |= plane.normal.dot(outward) > std::cos(paco::degreesToRadians(5.0)) &&
                 std::abs(plane.offset - face_offset) < 0.03 * diagonal;
    EXPECT_TRUE(matched) << "face " << f << " normal " << outward.transpose() << " offset " << face_offset;
  }

  // The same box without noise keeps the segmenter's 20.
  auto clean = makePlanarSegmenter<pcl::PointXYZ>(GetParam());
  clean->setInputCloud(test::withoutNormals(*cleanBox().cloud));
  clean->segment(result);
  EXPECT_EQ(clean->prepared().normal_neighbours_used, 20);
}

TEST_P(EveryBackend, RepeatedPointsShareTheirOriginalsLabel) {
  // Every point of the box ten times, the copies spread through the cloud (as when a scan
  // is merged with itself): the copies would fill each k-nearest neighbourhood; the result must be
  // the box's six planes, with each copy labelled like its original.
  const LabelledSample box = cleanBox();
  const std::size_t n = box.cloud->size();
  pcl::PointCloud<pcl::PointNormal>::Ptr repeated(new pcl::PointCloud<pcl::PointNormal>);
  for (int copy = 0; copy < 10; ++copy) *repeated += *box.cloud;
  auto seg = makePlanarSegmenter<pcl::PointNormal>(GetParam());
  seg->setInputCloud(repeated);
  PlanarSegmentation result;
  seg->segment(result);
  ASSERT_NO_THROW(result.validate(repeated->size()));
  EXPECT_EQ(result.size(), 6u);
  EXPECT_GT(result.coverage(), 0.9);
  std::size_t differing = 0;
  for (std::size_t i = n; i < repeated->size(); ++i) differing += result.labels[i] != result.labels[i % n];
  EXPECT_EQ(differing, 0u);
}

INSTANTIATE_TEST_SUITE_P(Backends, EveryBackend, ::testing::ValuesIn(availablePlanarSegmenters()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name = info.param;
                           for (auto& c : name)
                             if (c == '-') c = '_';
                           return name;
                         });

TEST(PlanarSegmenter, DefaultBackendIsGoCoPP) {
  EXPECT_EQ(makePlanarSegmenter<pcl::PointXYZ>()->name(), "gocopp");
  EXPECT_EQ(availablePlanarSegmenters().front(), "gocopp");
}

TEST(PlanarSegmenter, ScanMinimumIsAShareOfThePointsAndAtLeastThree) {
  EXPECT_EQ(scanMinPointsPerPlane(2048), 20);    // 20.48, rounded
  EXPECT_EQ(scanMinPointsPerPlane(20000), 200);
  EXPECT_EQ(scanMinPointsPerPlane(100), 3);      // 1 point: a plane still needs 3
  EXPECT_EQ(scanMinPointsPerPlane(0), 3);
  // A requested count (--min-points) wins; 0 asks for the share.
  EXPECT_EQ(scanMinPointsPerPlane(2048, 50), 50);
  EXPECT_EQ(scanMinPointsPerPlane(2048, 0), 20);
}

// How many of the four walls of makePlateWithDiamondHole(hole, ...) the tools' segmentation
// (setScanDefaults with `min_points`) finds in `cloud`; `segmenter` keeps the run for inspection.
int diamondHoleWallsFound(const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud, double hole, int min_points,
                          PlanarSegmenter<pcl::PointNormal>& segmenter) {
  const double centre_distance = hole / std::sqrt(2.0);  // from the hole's axis to each wall
  segmenter.setInputCloud(cloud);
  setScanDefaults(segmenter, cloud->size(), min_points, 0);
  PlanarSegmentation result;
  segmenter.segment(result);
  int found = 0;
  for (const Eigen::Vector2d& into_hole :
       {Eigen::Vector2d(1, 1), Eigen::Vector2d(-1, 1), Eigen::Vector2d(-1, -1), Eigen::Vector2d(1, -1)}) {
    // The wall faces into the hole: its normal points at the centre (0.5, 0.5, z).
    const Eigen::Vector3d normal = Eigen::Vector3d(into_hole.x(), into_hole.y(), 0).normalized();
    const Eigen::Vector3d centre(0.5, 0.5, 0.15);
    for (const Plane& plane : result.planes)
      if (plane.normal.dot(normal) > std::cos(degreesToRadians(2.0)) &&
          std::abs(plane.signedDistance(centre) - centre_distance) < 0.005) {
        ++found;
        break;
      }
  }
  return found;
}

// Each wall of the diamond hole holds about 1.3 % of the points, like the walls of the small
// holes and pockets of MFCAD parts at 2,048 points. The tools' 1 % keeps them; 1.5 %, the rule
// before the thirty-fourth session, left them out, and PolyFit closed the hole over.
TEST(PlanarSegmenter, TheToolsDefaultKeepsTheWallsOfASmallHole) {
  const auto scan = paco::test::scanByFace(paco::test::makePlateWithDiamondHole(0.1, 0.3), 20000, 5);
  auto segmenter = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  EXPECT_EQ(diamondHoleWallsFound(scan.cloud, 0.1, 0, *segmenter), 4);
  EXPECT_EQ(diamondHoleWallsFound(scan.cloud, 0.1, 300, *segmenter), 0) << "1.5 % of 20,000 points";
}

// The walls of a smaller hole hold about 0.5 % of the points each (about 100 of 20,000): on an
// exact scan the tools keep planes of 0.25 % (kExactScanMinPlaneFraction) and carve it; with
// noise of 0.05 % of the diagonal, too little for noise adaptation, the 1 % rule holds and
// leaves them out.
TEST(PlanarSegmenter, OnAnExactScanTheToolsKeepTheWallsOfATinyHole) {
  const double hole = 0.04;
  const auto scan = paco::test::scanByFace(paco::test::makePlateWithDiamondHole(hole, 0.3), 20000, 5);
  const std::size_t n = scan.cloud->size();
  auto segmenter = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  EXPECT_EQ(diamondHoleWallsFound(scan.cloud, hole, 0, *segmenter), 4);
  EXPECT_EQ(segmenter->getMinPointsPerPlane(), scanMinPointsPerPlane(n));
  EXPECT_EQ(segmenter->getUsedMinPointsPerPlane(), exactScanMinPointsPerPlane(n, 0));
  EXPECT_LT(segmenter->getUsedMinPointsPerPlane(), segmenter->getMinPointsPerPlane());

  pcl::PointCloud<pcl::PointNormal>::Ptr noisy(new pcl::PointCloud<pcl::PointNormal>(*scan.cloud));
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0.0f, static_cast<float>(0.0005 * std::sqrt(2.09)));  // the plate's diagonal
  for (auto& p : *noisy)
    for (int a = 0; a < 3; ++a) p.getVector3fMap()[a] += noise(rng);
  EXPECT_EQ(diamondHoleWallsFound(noisy, hole, 0, *segmenter), 0);
  EXPECT_EQ(segmenter->getUsedMinPointsPerPlane(), scanMinPointsPerPlane(n));
  EXPECT_DOUBLE_EQ(segmenter->getUsedDistanceThreshold(), segmenter->getDistanceThreshold()) << "not noisy";

  // A requested count holds on every scan.
  EXPECT_EQ(diamondHoleWallsFound(scan.cloud, hole, 150, *segmenter), 0);
  EXPECT_EQ(segmenter->getUsedMinPointsPerPlane(), 150);
  // The library's own default leaves the minimum alone.
  auto plain = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  EXPECT_EQ(plain->getExactScanMinPointsPerPlane(), 0);
  plain->setInputCloud(scan.cloud);
  PlanarSegmentation result;
  plain->segment(result);
  EXPECT_EQ(plain->getUsedMinPointsPerPlane(), plain->getMinPointsPerPlane());
  EXPECT_THROW(plain->setExactScanMinPointsPerPlane(2), InvalidInputError);
  EXPECT_THROW(plain->setExactScanMinPointsPerPlane(-1), InvalidInputError);
}

TEST(PlanarSegmenter, ExactScanMinimumIsAQuarterPercentUnlessACountIsAsked) {
  EXPECT_EQ(exactScanMinPointsPerPlane(2048, 0), 5);  // 5.12, rounded
  EXPECT_EQ(exactScanMinPointsPerPlane(20000, 0), 50);
  EXPECT_EQ(exactScanMinPointsPerPlane(400, 0), 3);   // 1 point: a plane still needs 3
  EXPECT_EQ(exactScanMinPointsPerPlane(2048, 40), 40);
}

TEST(PlanarSegmenter, ScanParallelMinimumIsAShareUnlessACountOrOffIsAsked) {
  EXPECT_EQ(scanMinPointsPerParallelPlane(2048, 0), 3);  // 3.07, rounded
  EXPECT_EQ(scanMinPointsPerParallelPlane(20000, 0), 30);
  EXPECT_EQ(scanMinPointsPerParallelPlane(100, 0), 3);
  EXPECT_EQ(scanMinPointsPerParallelPlane(2048, 15), 15);
  EXPECT_EQ(scanMinPointsPerParallelPlane(2048, -1), 0);  // off
  EXPECT_EQ(scanMinPointsPerParallelPlane(2048, -2), 0);  // any other negative: off
}

// Labels two known large planes and nothing else, so that the parallel-plane pass is all that
// can find the rest.
class KnownLargePlanes : public PlanarSegmenter<pcl::PointNormal> {
 public:
  KnownLargePlanes(int first_plane_end, int second_plane_end) : first_end_(first_plane_end), second_end_(second_plane_end) {}
  std::string name() const override { return "known-large-planes"; }

 protected:
  void performSegmentation(std::vector<int>& labels) override {
    for (std::size_t i = 0; i < labels.size(); ++i) {
      const int source = prepared().source_indices[i];
      labels[i] = source < first_end_ ? 0 : (source < second_end_ ? 1 : -1);
    }
  }

 private:
  int first_end_, second_end_;
};

TEST(PlanarSegmenter, SmallPlanesParallelToALargeOneGetASecondChance) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  auto add = [&](float x, float y, float z, float nx, float ny, float nz) {
    pcl::PointNormal p;
    p.x = x, p.y = y, p.z = z, p.normal_x = nx, p.normal_y = ny, p.normal_z = nz;
    cloud->push_back(p);
  };
  for (int i = 0; i < 30; ++i)  // floor z = 0: 900 points
    for (int j = 0; j < 30; ++j) add(i / 29.0f, j / 29.0f, 0.0f, 0, 0, 1);
  for (int i = 0; i < 30; ++i)  // wall x = 0: 540 points
    for (int j = 0; j < 18; ++j) add(0.0f, i / 29.0f, 0.6f * j / 17.0f, -1, 0, 0);
  const int first_small = static_cast<int>(cloud->size());
  for (int i = 0; i < 4; ++i)  // a pocket floor at z = 0.4, parallel to the floor: 12 points
    for (int j = 0; j < 3; ++j) add(0.5f + 0.03f * i, 0.5f + 0.05f * j, 0.4f, 0, 0, 1);
  const int strip = static_cast<int>(cloud->size());
  for (int i = 0; i < 12; ++i) add(0.8f, 0.1f + 0.07f * i, 0.25f, 0, 0, 1);  // a line: no unique plane
  // Single points facing up, 0.03 apart in height (2 epsilon is 0.012 here) and away from the
  // other heights: no window holds more than one.
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.05f, 0.95f);
  for (float z : {0.06f, 0.09f, 0.12f, 0.15f, 0.18f, 0.31f, 0.34f, 0.47f, 0.50f, 0.53f, 0.56f, 0.59f})
    add(unit(rng), unit(rng), z, 0, 0, 1);

  KnownLargePlanes seg(900, 1440);
  seg.setInputCloud(cloud);
  PlanarSegmentation result;
  seg.segment(result);
  EXPECT_EQ(result.size(), 2u) << "off by default";

  seg.setMinPointsPerParallelPlane(10);
  seg.segment(result);
  ASSERT_EQ(result.size(), 3u);
  const Plane& pocket = result.planes[2];  // sorted by size: the 12-point pocket floor is last
  EXPECT_GT(pocket.normal.dot(Eigen::Vector3d::UnitZ()), 0.9999);
  EXPECT_NEAR(pocket.offset, -0.4, 1e-5);
  std::vector<int> expected;
  for (int i = first_small; i < strip; ++i) expected.push_back(i);
  EXPECT_EQ(std::vector<int>(result.segments[2].indices.begin(), result.segments[2].indices.end()), expected);
  for (int i = strip; i < static_cast<int>(cloud->size()); ++i) EXPECT_EQ(result.labels[i], -1) << "point " << i;

  seg.setMinPointsPerParallelPlane(13);  // one more point than the pocket floor has
  seg.segment(result);
  EXPECT_EQ(result.size(), 2u);
  seg.setMinPointsPerParallelPlane(900);  // not below the plane minimum: changes nothing
  seg.segment(result);
  EXPECT_EQ(result.size(), 2u);

  EXPECT_THROW(seg.setMinPointsPerParallelPlane(2), InvalidInputError);
  EXPECT_THROW(seg.setMinPointsPerParallelPlane(-1), InvalidInputError);
}

// A noisy floor and wall (Gaussian noise of 0.01, all their points labelled) with a 12-point patch
// of free points parallel to the floor: on a noisy scan the patch is the floor's noise tail when it
// lies within 4 RMS of the floor and over its points, and a plane of its own otherwise.
PlanarSegmentation segmentFaceWithPatch(float patch_x, float patch_z, bool noise_adaptation = true) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  auto add = [&](float x, float y, float z, float nx, float ny, float nz) {
    pcl::PointNormal p;
    p.x = x, p.y = y, p.z = z, p.normal_x = nx, p.normal_y = ny, p.normal_z = nz;
    cloud->push_back(p);
  };
  for (int i = 0; i < 30; ++i)  // floor z = 0: 900 points
    for (int j = 0; j < 30; ++j) add(i / 29.0f, j / 29.0f, noise(rng), 0, 0, 1);
  for (int i = 0; i < 30; ++i)  // wall x = 0: 540 points
    for (int j = 0; j < 18; ++j) add(noise(rng), i / 29.0f, 0.6f * j / 17.0f, -1, 0, 0);
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 3; ++j) add(patch_x + 0.03f * i, 0.5f + 0.05f * j, patch_z, 0, 0, 1);
  KnownLargePlanes seg(900, 1440);
  seg.setMinPointsPerParallelPlane(10);
  if (noise_adaptation) seg.setNoiseAdaptation(kScanNoiseMultiple);
  seg.setInputCloud(cloud);
  PlanarSegmentation result;
  seg.segment(result);
  EXPECT_EQ(seg.getUsedDistanceThreshold() > seg.getDistanceThreshold(), noise_adaptation);
  return result;
}

TEST(PlanarSegmenter, OnANoisyScanTheScatterOfAFaceIsNotANewPlane) {
  // 0.03 above the face and over its points: a piece of its scatter (noise of 1 % of the diagonal
  // made such planes on either side of every face, and the cell complex thin slabs between them).
  const PlanarSegmentation tail = segmentFaceWithPatch(0.5f, 0.03f);
  EXPECT_EQ(tail.size(), 2u);
  for (std::size_t i = 1440; i < tail.labels.size(); ++i) EXPECT_EQ(tail.labels[i], -1) << "point " << i;

  // As near, but beside the face: a step's floor of its own.
  const PlanarSegmentation beside = segmentFaceWithPatch(1.3f, 0.03f);
  ASSERT_EQ(beside.size(), 3u);
  EXPECT_NEAR(beside.planes[2].offset, -0.03, 1e-5);

  // Over the face but 6 RMS above it: a pocket's floor or a step, beyond the scatter.
  const PlanarSegmentation above = segmentFaceWithPatch(0.5f, 0.06f);
  ASSERT_EQ(above.size(), 3u);
  EXPECT_NEAR(above.planes[2].offset, -0.06, 1e-5);

  // Without noise adaptation the scan is not known to be noisy, and the patch is a plane.
  const PlanarSegmentation unknown = segmentFaceWithPatch(0.5f, 0.03f, false);
  ASSERT_EQ(unknown.size(), 3u);
  EXPECT_NEAR(unknown.planes[2].offset, -0.03, 1e-5);
}

TEST(PlanarSegmenter, UnknownBackendNameIsAClearError) {
  try {
    makePlanarSegmenter<pcl::PointXYZ>("hough");
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("gocopp"), std::string::npos) << e.what();
  }
}

TEST(PlanarSegmenter, DistancesAreRelativeToTheDiagonal) {
  // The same box in metres and in micrometres-scale units gives the same segmentation.
  const LabelledSample box = cleanBox();
  pcl::PointCloud<pcl::PointNormal>::Ptr tiny(new pcl::PointCloud<pcl::PointNormal>(*box.cloud));
  for (auto& p : *tiny) p.getVector3fMap() *= 1e-3f;
  GoCoPPSegmenter<pcl::PointNormal> a, b;
  a.setInputCloud(box.cloud);
  b.setInputCloud(tiny);
  PlanarSegmentation ra, rb;
  a.segment(ra);
  b.segment(rb);
  ASSERT_EQ(ra.size(), 6u);
  ASSERT_EQ(rb.size(), 6u);
  for (std::size_t s = 0; s < 6; ++s) {
    EXPECT_GT(ra.planes[s].normal.dot(rb.planes[s].normal), 0.9999);
    EXPECT_NEAR(ra.planes[s].offset * 1e-3, rb.planes[s].offset, 1e-5);
  }
}

TEST(PlanarSegmenter, PlanesAreInTheUserFrameAndOrientedLikeTheNormals) {
  const LabelledSample box = cleanBox();
  GoCoPPSegmenter<pcl::PointNormal> seg;
  seg.setInputCloud(box.cloud);
  PlanarSegmentation result;
  seg.segment(result);
  ASSERT_EQ(result.size(), 6u);
  for (std::size_t s = 0; s < result.size(); ++s) {
    // Every inlier is within ε (0.004 x diagonal) of its plane, in user units.
    const double diagonal = std::sqrt(1.0 + 0.64 + 0.36);
    for (const int i : result.segments[s].indices) {
      const Eigen::Vector3d x = (*box.cloud)[static_cast<std::size_t>(i)].getVector3fMap().cast<double>();
      EXPECT_LT(std::abs(result.planes[s].signedDistance(x)), 0.004 * diagonal + 1e-6);
      EXPECT_GT(result.planes[s].normal.dot((*box.cloud)[static_cast<std::size_t>(i)].getNormalVector3fMap().cast<double>()), 0.99);
    }
  }
  // Sorted by decreasing size.
  for (std::size_t s = 1; s < result.size(); ++s)
    EXPECT_GE(result.segments[s - 1].indices.size(), result.segments[s].indices.size());
}

TEST(PlanarSegmenter, IndicesRestrictTheInput) {
  const LabelledSample box = cleanBox();
  pcl::IndicesPtr top(new pcl::Indices);
  for (std::size_t i = 0; i < box.cloud->size(); ++i)
    if ((*box.cloud)[i].z > 0.59f) top->push_back(static_cast<int>(i));
  ASSERT_GT(top->size(), 300u);
  GoCoPPSegmenter<pcl::PointNormal> seg;
  seg.setInputCloud(box.cloud);
  seg.setIndices(top);
  PlanarSegmentation result;
  seg.segment(result);
  ASSERT_EQ(result.labels.size(), box.cloud->size());
  ASSERT_EQ(result.size(), 1u);
  EXPECT_GT(result.planes[0].normal.z(), 0.9999);
  EXPECT_NEAR(result.planes[0].offset, -0.6, 1e-4);
  std::size_t labelled = 0;
  for (std::size_t i = 0; i < box.cloud->size(); ++i)
    if (result.labels[i] >= 0) {
      ++labelled;
      EXPECT_GT((*box.cloud)[i].z, 0.59f);
    }
  EXPECT_GT(labelled, top->size() * 9 / 10);
}

TEST(PlanarSegmenter, NonFinitePointsAreDroppedAndLabelledNone) {
  LabelledSample box = cleanBox();
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  (*box.cloud)[5].x = nan;
  (*box.cloud)[17].y = inf;
  (*box.cloud)[2999].z = -inf;
  GoCoPPSegmenter<pcl::PointNormal> seg;
  seg.setInputCloud(box.cloud);
  PlanarSegmentation result;
  seg.segment(result);
  EXPECT_EQ(result.size(), 6u);
  ASSERT_EQ(result.labels.size(), box.cloud->size());
  EXPECT_EQ(result.labels[5], -1);
  EXPECT_EQ(result.labels[17], -1);
  EXPECT_EQ(result.labels[2999], -1);
  EXPECT_EQ(seg.prepared().size(), box.cloud->size() - 3);
}

TEST(PlanarSegmenter, NonFiniteNormalsAreEstimated) {
  LabelledSample box = cleanBox();
  for (std::size_t i = 0; i < box.cloud->size(); i += 3) (*box.cloud)[i].normal_x = std::numeric_limits<float>::quiet_NaN();
  GoCoPPSegmenter<pcl::PointNormal> seg;
  seg.setInputCloud(box.cloud);
  PlanarSegmentation result;
  seg.segment(result);
  EXPECT_TRUE(seg.prepared().normals_estimated);
  EXPECT_EQ(test::scoreRecovery(box, result).found, 6);
}

TEST(PlanarSegmenter, SeparateNormalsAreUsed) {
  const LabelledSample box = cleanBox();
  pcl::PointCloud<pcl::Normal>::Ptr normals(new pcl::PointCloud<pcl::Normal>);
  for (const auto& p : *box.cloud) normals->push_back(pcl::Normal(p.normal_x, p.normal_y, p.normal_z));
  GoCoPPSegmenter<pcl::PointXYZ> seg;
  seg.setInputCloud(test::withoutNormals(*box.cloud));
  seg.setInputNormals(normals);
  PlanarSegmentation result;
  seg.segment(result);
  EXPECT_FALSE(seg.prepared().normals_estimated);
  EXPECT_EQ(result.size(), 6u);

  normals->resize(10);
  EXPECT_THROW(seg.segment(result), InvalidInputError);
}

TEST(PlanarSegmenter, NoInputIsAClearError) {
  GoCoPPSegmenter<pcl::PointXYZ> seg;
  PlanarSegmentation result;
  EXPECT_THROW(seg.segment(result), InvalidInputError);
  seg.setInputCloud(pcl::PointCloud<pcl::PointXYZ>::Ptr(new pcl::PointCloud<pcl::PointXYZ>));
  EXPECT_THROW(seg.segment(result), InvalidInputError);
}

TEST(PlanarSegmenter, FewerPointsThanAPlaneNeedsIsAClearError) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr two(new pcl::PointCloud<pcl::PointXYZ>);
  two->push_back({0, 0, 0});
  two->push_back({1, 0, 0});
  GoCoPPSegmenter<pcl::PointXYZ> seg;
  seg.setInputCloud(two);
  PlanarSegmentation result;
  try {
    seg.segment(result);
    FAIL() << "expected InvalidInputError";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3"), std::string::npos) << e.what();
  }
  // Three finite points among NaNs are not enough either once the NaNs go.
  two->push_back({std::numeric_limits<float>::quiet_NaN(), 0, 0});
  EXPECT_THROW(seg.segment(result), InvalidInputError);
}

TEST(PlanarSegmenter, CoincidentPointsAreAClearError) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr same(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 100; ++i) same->push_back({1, 2, 3});
  GoCoPPSegmenter<pcl::PointXYZ> seg;
  seg.setInputCloud(same);
  PlanarSegmentation result;
  EXPECT_THROW(seg.segment(result), InvalidInputError);
}

TEST(PlanarSegmenter, CollinearPointsGiveNoPlane) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr line(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 200; ++i) line->push_back({0.01f * i, 0.02f * i, -0.005f * i});
  for (const auto& name : availablePlanarSegmenters()) {
    auto seg = makePlanarSegmenter<pcl::PointXYZ>(name);
    seg->setInputCloud(line);
    PlanarSegmentation result;
    ASSERT_NO_THROW(seg->segment(result)) << name;
    EXPECT_TRUE(result.empty()) << name;
    ASSERT_EQ(result.labels.size(), line->size());
    for (const int l : result.labels) EXPECT_EQ(l, -1);
  }
}

TEST(PlanarSegmenter, FewerPointsThanSigmaGiveNoPlane) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr small(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 5; ++j) small->push_back({0.1f * i, 0.1f * j, 0.0f});
  for (const auto& name : availablePlanarSegmenters()) {
    auto seg = makePlanarSegmenter<pcl::PointXYZ>(name);
    seg->setInputCloud(small);
    PlanarSegmentation result;
    ASSERT_NO_THROW(seg->segment(result)) << name;
    EXPECT_TRUE(result.empty()) << name;
    EXPECT_EQ(result.labels.size(), 30u);
  }
}

TEST(PlanarSegmenter, IndexOutOfRangeIsAClearError) {
  const LabelledSample box = cleanBox();
  GoCoPPSegmenter<pcl::PointNormal> seg;
  seg.setInputCloud(box.cloud);
  seg.setIndices(pcl::IndicesPtr(new pcl::Indices{0, 1, 2, 99999}));
  PlanarSegmentation result;
  EXPECT_THROW(seg.segment(result), InvalidInputError);
}

TEST(PlanarSegmenter, BadParametersAreRejectedAtTheSetter) {
  GoCoPPSegmenter<pcl::PointXYZ> seg;
  EXPECT_THROW(seg.setDistanceThreshold(0.0), InvalidInputError);
  EXPECT_THROW(seg.setDistanceThreshold(std::numeric_limits<double>::quiet_NaN()), InvalidInputError);
  EXPECT_THROW(seg.setNormalThreshold(1.5), InvalidInputError);
  EXPECT_THROW(seg.setMinPointsPerPlane(2), InvalidInputError);
  EXPECT_THROW(seg.setNumberOfNeighbours(1), InvalidInputError);
  EXPECT_THROW(seg.setLambdaSimplicity(-1.0), InvalidInputError);
  EXPECT_THROW(seg.setMaxRounds(-1), InvalidInputError);
  RansacSegmenter<pcl::PointXYZ> ransac;
  EXPECT_THROW(ransac.setMaxIterations(0), InvalidInputError);
  EfficientRansacSegmenter<pcl::PointXYZ> efficient;
  EXPECT_THROW(efficient.setProbability(1.0), InvalidInputError);
  RegionGrowingSegmenter<pcl::PointXYZ> growing;
  EXPECT_THROW(growing.setCurvatureThreshold(0.5), InvalidInputError);
}

// A user backend: one plane through everything, by subclassing.
class EverythingIsOnePlane : public PlanarSegmenter<pcl::PointXYZ> {
 public:
  std::string name() const override { return "one-plane"; }

 protected:
  void performSegmentation(std::vector<int>& labels) override { std::fill(labels.begin(), labels.end(), 0); }
};

TEST(PlanarSegmenter, UsersCanAddABackendBySubclassing) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr plane(new pcl::PointCloud<pcl::PointXYZ>);
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) plane->push_back({0.1f * i, 0.1f * j, 2.0f + 0.05f * i});
  PlanarSegmenter<pcl::PointXYZ>::Ptr seg = std::make_shared<EverythingIsOnePlane>();
  seg->setInputCloud(plane);
  PlanarSegmentation result;
  seg->segment(result);
  ASSERT_EQ(result.size(), 1u);
  // z = 2 + 0.5 x  <=>  -0.5 x + z - 2 = 0, normalised.
  const Eigen::Vector3d expected = Eigen::Vector3d(-0.5, 0, 1).normalized();
  EXPECT_GT(std::abs(result.planes[0].normal.dot(expected)), 1 - 1e-9);
  EXPECT_NEAR(std::abs(result.planes[0].offset), 2.0 / std::sqrt(1.25), 1e-5);
  EXPECT_DOUBLE_EQ(result.coverage(), 1.0);
}

TEST(NoiseLevel, ReadsTheScatterOffTheSurface) {
  auto clean = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  clean->setInputCloud(cleanBox().cloud);
  PlanarSegmentation result;
  clean->segment(result);
  EXPECT_LT(clean->prepared().noiseLevel(kNoiseNeighbours, kNoiseQuantile), 1e-4);

  // Noise of 1 % of the diagonal, about 0.01 in the working frame: the scatter off a plane
  // fitted to the noisy neighbours themselves is a little less than that.
  auto noisy = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  noisy->setInputCloud(noisyBox(0.01).cloud);
  noisy->segment(result);
  const double level = noisy->prepared().noiseLevel(kNoiseNeighbours, kNoiseQuantile);
  EXPECT_GT(level, 0.005);
  EXPECT_LT(level, 0.011);
  EXPECT_THROW(noisy->prepared().noiseLevel(2, 0.25), InvalidInputError);
  EXPECT_THROW(noisy->prepared().noiseLevel(20, 1.5), InvalidInputError);
}

// A wall little more than a point spacing thin, noise-free: every neighbourhood holds both of its
// sides, two layers with nothing between them. That is not noise, and the level stays near 0 (it
// read half the thickness before, 0.009).
TEST(NoiseLevel, TheTwoSidesOfAThinWallAreNotNoise) {
  pcl::PointCloud<pcl::PointNormal>::Ptr wall(new pcl::PointCloud<pcl::PointNormal>);
  const float spacing = 0.02f, thickness = 0.025f;
  for (const float z : {0.0f, thickness})
    for (int i = 0; i < 50; ++i)
      for (int j = 0; j < 50; ++j) {
        pcl::PointNormal p;
        p.x = spacing * i;
        p.y = spacing * j;
        p.z = z;
        p.normal_x = p.normal_y = 0.0f;
        p.normal_z = z > 0.0f ? 1.0f : -1.0f;
        wall->push_back(p);
      }
  auto seg = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  seg->setInputCloud(wall);
  PlanarSegmentation result;
  seg->segment(result);
  // The working frame has a unit diagonal (about 1.39 here): the sides are 0.018 apart in it.
  EXPECT_LT(seg->prepared().noiseLevel(kNoiseNeighbours, kNoiseQuantile), 1e-3);
}

// A gear of 24 teeth, noise-free, whose flanks are about a point spacing wide: nearly every
// point's 20 neighbours reach over an edge onto another flank. Only the neighbours whose normals
// agree with the point's count, so the level is 0 and noise adaptation leaves ε alone. Counting
// every neighbour, the edges read as noise, as they did on MFCAD parts with many small faces
// (7 of the first 100 validation inputs at 25 % missing had ε widened, up to 0.012).
TEST(NoiseLevel, TheEdgesOfManySmallFacesAreNotNoise) {
  std::vector<Eigen::Vector2d> profile;
  const int teeth = 24;
  for (int i = 0; i < 2 * teeth; ++i) {
    const double angle = kPi * i / teeth, radius = i % 2 == 0 ? 0.5 : 0.42;
    profile.emplace_back(radius * std::cos(angle), radius * std::sin(angle));
  }
  const LabelledSample gear = test::sampleShape(test::makePrism(profile, 0.6), 2048, 3);
  auto seg = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  setScanDefaults(*seg, gear.cloud->size(), 0, 0);
  seg->setInputCloud(gear.cloud);
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_LT(seg->prepared().noiseLevel(kNoiseNeighbours, kNoiseQuantile), 1e-6);
  EXPECT_DOUBLE_EQ(seg->getUsedDistanceThreshold(), seg->getDistanceThreshold());
  EXPECT_EQ(seg->getUsedMinPointsPerPlane(), exactScanMinPointsPerPlane(gear.cloud->size(), 0)) << "an exact scan";
}

// A blob of random points is no surface: whatever its estimated normals, it is not an exact
// scan, and the tools keep the 1 % minimum.
TEST(NoiseLevel, ARandomBlobIsNotAnExactScan) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr blob(new pcl::PointCloud<pcl::PointXYZ>);
  std::mt19937 rng(4);
  std::uniform_real_distribution<float> coordinate(0.0f, 1.0f);
  for (int i = 0; i < 2048; ++i) blob->push_back(pcl::PointXYZ(coordinate(rng), coordinate(rng), coordinate(rng)));
  auto seg = makePlanarSegmenter<pcl::PointXYZ>("gocopp");
  setScanDefaults(*seg, blob->size(), 0, 0);
  seg->setInputCloud(blob);
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_GT(seg->prepared().noiseLevel(kNoiseNeighbours, kNoiseQuantile), kExactScanNoiseLevel);
  EXPECT_EQ(seg->getUsedMinPointsPerPlane(), seg->getMinPointsPerPlane());
}

TEST(NoiseAdaptation, ANoisyBoxGetsOnePlanePerFace) {
  const LabelledSample box = noisyBox(0.01);
  // The tools' plane minimums alone: the inlier band (0.4 % of the diagonal) is far below the
  // noise, and the faces break into many planes.
  auto narrow = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  setScanMinimums(*narrow, box.cloud->size(), 0, 0);
  narrow->setInputCloud(box.cloud);
  PlanarSegmentation fragments;
  narrow->segment(fragments);
  EXPECT_GT(fragments.size(), 12u);
  EXPECT_DOUBLE_EQ(narrow->getUsedDistanceThreshold(), 0.004);

  auto seg = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  setScanDefaults(*seg, box.cloud->size(), 0, 0);
  EXPECT_DOUBLE_EQ(seg->getNoiseAdaptation(), kScanNoiseMultiple);
  seg->setInputCloud(box.cloud);
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_GT(seg->getUsedDistanceThreshold(), 0.01);
  EXPECT_LE(seg->getUsedDistanceThreshold(), kMaxNoiseAdaptedDistance);
  ASSERT_EQ(result.size(), box.plane_normals.size());
  EXPECT_GT(result.coverage(), 0.9);
  for (std::size_t f = 0; f < box.plane_normals.size(); ++f) {
    bool matched = false;
    for (const auto& plane : result.planes) matched |= plane.normal.dot(box.plane_normals[f]) > std::cos(paco::degreesToRadians(2.0));
    EXPECT_TRUE(matched) << "face " << f << " normal " << box.plane_normals[f].transpose();
  }
}

// On a noisy scan the tools ask for larger parallel planes (kNoisyScanMinParallelPlaneFraction):
// the noise scattered off each face would otherwise make planes of a few points.
TEST(NoiseAdaptation, RaisesTheParallelPlaneMinimumOnANoisyScanOnly) {
  const LabelledSample noisy = noisyBox(0.01);
  const std::size_t n = noisy.cloud->size();
  auto seg = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  setScanDefaults(*seg, n, 0, 0);
  EXPECT_EQ(seg->getNoisyScanMinPointsPerParallelPlane(), noisyScanMinPointsPerParallelPlane(n, 0));
  seg->setInputCloud(noisy.cloud);
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_EQ(seg->getMinPointsPerPlane(), scanMinPointsPerPlane(n));
  EXPECT_EQ(seg->getUsedMinPointsPerParallelPlane(), noisyScanMinPointsPerParallelPlane(n, 0));
  EXPECT_GT(seg->getUsedMinPointsPerParallelPlane(), scanMinPointsPerParallelPlane(n, 0));
  EXPECT_EQ(result.size(), 6u);
  for (const auto& segment : result.segments)
    EXPECT_GE(segment.indices.size(), static_cast<std::size_t>(seg->getUsedMinPointsPerParallelPlane()));

  // The clean-scan minimums on the same noisy scan: the scatter cut off each face by the inlier
  // distance is not a plane either (recoverParallelPlanes leaves a face's noise tails free).
  auto clean_rule = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  setScanDefaults(*clean_rule, n, 0, 0);
  clean_rule->setNoisyScanMinPointsPerParallelPlane(0);
  clean_rule->setInputCloud(noisy.cloud);
  PlanarSegmentation pieces;
  clean_rule->segment(pieces);
  EXPECT_EQ(clean_rule->getUsedMinPointsPerParallelPlane(), scanMinPointsPerParallelPlane(n, 0));
  EXPECT_EQ(pieces.size(), 6u);

  // A clean scan keeps the clean-scan minimums; a requested count holds on every scan.
  const LabelledSample clean = cleanBox();
  seg->setInputCloud(clean.cloud);
  setScanDefaults(*seg, clean.cloud->size(), 0, 0);
  seg->segment(result);
  EXPECT_EQ(seg->getMinPointsPerPlane(), scanMinPointsPerPlane(clean.cloud->size()));
  EXPECT_EQ(seg->getUsedMinPointsPerParallelPlane(), scanMinPointsPerParallelPlane(clean.cloud->size(), 0));
  setScanDefaults(*seg, n, 40, 12);
  seg->setInputCloud(noisy.cloud);
  seg->segment(result);
  EXPECT_EQ(seg->getMinPointsPerPlane(), 40);
  EXPECT_EQ(seg->getUsedMinPointsPerParallelPlane(), 12);
  EXPECT_THROW(seg->setNoisyScanMinPointsPerParallelPlane(2), InvalidInputError);
  EXPECT_THROW(seg->setNoisyScanMinPointsPerParallelPlane(-1), InvalidInputError);
}

TEST(PlanarSegmenter, NoisyScanParallelMinimumIsTheEarlierShareUnlessACountOrOffIsAsked) {
  EXPECT_EQ(noisyScanMinPointsPerParallelPlane(2048, 0), 10);  // 10.24, rounded
  EXPECT_EQ(noisyScanMinPointsPerParallelPlane(100, 0), 3);
  EXPECT_EQ(noisyScanMinPointsPerParallelPlane(2048, 15), 15);
  EXPECT_EQ(noisyScanMinPointsPerParallelPlane(2048, -1), 0);  // off
}

TEST(NoiseAdaptation, LeavesACleanScanAndTheDefaultAlone) {
  auto seg = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  EXPECT_DOUBLE_EQ(seg->getNoiseAdaptation(), 0.0);
  const LabelledSample box = cleanBox();
  setScanDefaults(*seg, box.cloud->size(), 0, 0);
  seg->setInputCloud(box.cloud);
  PlanarSegmentation result;
  seg->segment(result);
  EXPECT_DOUBLE_EQ(seg->getUsedDistanceThreshold(), seg->getDistanceThreshold());
  EXPECT_EQ(result.size(), 6u);

  // Off by default: a noisy scan keeps the distance threshold it was given.
  auto plain = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  plain->setDistanceThreshold(0.006);
  plain->setInputCloud(noisyBox(0.01).cloud);
  plain->segment(result);
  EXPECT_DOUBLE_EQ(plain->getUsedDistanceThreshold(), 0.006);
  // Adaptation only widens: an ε wider than the adapted one, even beyond its cap, stays.
  plain->setNoiseAdaptation(kScanNoiseMultiple);
  plain->setDistanceThreshold(0.08);
  plain->segment(result);
  EXPECT_DOUBLE_EQ(plain->getUsedDistanceThreshold(), 0.08);
  EXPECT_THROW(plain->setNoiseAdaptation(-1.0), InvalidInputError);
  EXPECT_THROW(plain->setNoiseAdaptation(std::numeric_limits<double>::quiet_NaN()), InvalidInputError);
}

}  // namespace
}  // namespace paco
