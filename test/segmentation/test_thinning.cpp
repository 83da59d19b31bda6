// thinToPointBudget: a dense scan is cut to a working size of even density, with input points
// kept as they are, and segmentation still finds its faces.
#include "segmentation_fixtures.h"
#include "shapes.h"

#include <paco/common/error.h>
#include <paco/segmentation/segmentation.h>
#include <paco/segmentation/thinning.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <map>
#include <random>
#include <tuple>

namespace paco {
namespace {

using test::LabelledSample;
using Key = std::tuple<float, float, float>;

Key keyOf(const pcl::PointNormal& p) { return {p.x, p.y, p.z}; }

double faceArea(const SurfaceMesh& mesh, std::size_t face) {
  Eigen::Vector3d twice_area = Eigen::Vector3d::Zero();  // Newell: any planar polygon
  const auto& loop = mesh.faces[face];
  for (std::size_t i = 0; i < loop.size(); ++i)
    twice_area += mesh.vertices[loop[i]].cross(mesh.vertices[loop[(i + 1) % loop.size()]]);
  return 0.5 * twice_area.norm();
}

/// A dense L-bracket with scanner noise (0.2 % of its diagonal along the normal).
LabelledSample denseNoisyBracket(std::size_t points) {
  SurfaceMesh mesh = test::makeLBracket();
  test::transformMesh(mesh, test::obliqueRotation(), {0.3, -0.2, 0.1});
  LabelledSample s = test::sampleShape(mesh, points, 5);
  std::mt19937 rng(3);
  std::normal_distribution<float> noise(0.0f, 0.002f * 1.3f);
  for (auto& p : *s.cloud) p.getVector3fMap() += noise(rng) * p.getNormalVector3fMap();
  return s;
}

/// The thinned points with their GT labels, found by exact position in the input.
LabelledSample labelThinned(const LabelledSample& dense, const pcl::PointCloud<pcl::PointNormal>& thinned) {
  std::map<Key, int> label_at;
  for (std::size_t i = 0; i < dense.cloud->size(); ++i) label_at[keyOf((*dense.cloud)[i])] = dense.labels[i];
  LabelledSample out;
  out.plane_normals = dense.plane_normals;
  for (const auto& p : thinned) {
    const auto it = label_at.find(keyOf(p));
    if (it == label_at.end()) ADD_FAILURE() << "a thinned point is not an input point";
    out.cloud->push_back(p);
    out.labels.push_back(it == label_at.end() ? -1 : it->second);
  }
  return out;
}

TEST(Thinning, KeepsInputPointsEvenlyWithinTheBudget) {
  // A box whose faces differ in area: after thinning, each face keeps a share of the points
  // close to its share of the area, though the input is 4 times denser on one face.
  SurfaceMesh box = test::makeBox({0, 0, 0}, {1.0, 0.8, 0.6});
  LabelledSample dense = test::sampleShape(box, 40000, 9);
  const LabelledSample extra = test::sampleShape(box, 120000, 10);
  for (std::size_t i = 0; i < extra.cloud->size(); ++i)
    if (extra.labels[i] == dense.labels.front()) {
      dense.cloud->push_back((*extra.cloud)[i]);
      dense.labels.push_back(extra.labels[i]);
    }
  pcl::PointCloud<pcl::PointNormal> thinned;
  const ThinningReport report = thinToPointBudget(*dense.cloud, 4000, thinned);
  EXPECT_TRUE(report.thinned());
  EXPECT_EQ(report.input_points, dense.cloud->size());
  EXPECT_EQ(report.output_points, thinned.size());
  EXPECT_LE(thinned.size(), 4000u);
  EXPECT_GE(thinned.size(), 3400u);  // 85 % of the budget
  EXPECT_GT(report.voxel_size, 0.0);

  const LabelledSample labelled = labelThinned(dense, thinned);
  std::map<int, double> area_share, point_share;
  double total_area = 0.0;
  for (std::size_t f = 0; f < box.faces.size(); ++f) total_area += faceArea(box, f);
  for (std::size_t f = 0; f < box.faces.size(); ++f) area_share[static_cast<int>(f)] = faceArea(box, f) / total_area;
  for (const int l : labelled.labels) point_share[l] += 1.0 / static_cast<double>(labelled.labels.size());
  for (const auto& [face, share] : area_share)
    EXPECT_NEAR(point_share[face], share, 0.25 * share) << "face " << face;
  // Normals come from the input as they are.
  for (const auto& p : thinned) EXPECT_NEAR(p.getNormalVector3fMap().norm(), 1.0f, 1e-5f);
}

TEST(Thinning, AThinnedNoisyScanStillSegmentsIntoItsFaces) {
  const LabelledSample dense = denseNoisyBracket(80000);
  pcl::PointCloud<pcl::PointNormal>::Ptr thinned(new pcl::PointCloud<pcl::PointNormal>);
  thinToPointBudget(*dense.cloud, 8192, *thinned);
  const LabelledSample labelled = labelThinned(dense, *thinned);

  auto seg = makePlanarSegmenter<pcl::PointNormal>("gocopp");
  seg->setInputCloud(thinned);
  PlanarSegmentation result;
  seg->segment(result);
  const test::PlaneRecovery r = test::scoreRecovery(labelled, result);
  EXPECT_EQ(r.visible, 8);  // every face of the L-bracket
  EXPECT_EQ(r.found, r.visible);
  EXPECT_LT(r.worst_angle_deg, 1.0);
  EXPECT_LE(result.size(), 10u) << "a few fragments at most, not one per neighbourhood";
}

// Labels from a thinned copy: a point takes a nearby kept point's plane only when it lies on it;
// labels that do not fit the thinned copy are refused.
TEST(Thinning, LabelsFromAThinnedCopyNeedThePointOnThePlane) {
  pcl::PointCloud<pcl::PointNormal> thinned, cloud;
  PlanarSegmentation segmentation;
  segmentation.planes = {Plane::fromPointAndNormal({0, 0, 0}, {0, 0, 1})};
  for (int i = 0; i < 4; ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(i), p.y = 0.0f, p.z = 0.0f;
    thinned.push_back(p);
    segmentation.labels.push_back(i < 3 ? 0 : -1);  // the last kept point is on no plane
  }
  for (const float z : {0.0f, 0.05f, 0.5f}) {
    pcl::PointNormal p;
    p.x = 0.4f, p.y = 0.0f, p.z = z;
    cloud.push_back(p);
  }
  pcl::PointNormal beside_the_unlabelled;  // nearest to the unlabelled point, but on the plane
  beside_the_unlabelled.x = 2.9f, beside_the_unlabelled.y = beside_the_unlabelled.z = 0.0f;
  cloud.push_back(beside_the_unlabelled);
  std::vector<int> nearest;
  EXPECT_EQ(labelsFromThinned(cloud, thinned, segmentation, 0.1, &nearest), (std::vector<int>{0, 0, -1, 0}));
  EXPECT_EQ(nearest, (std::vector<int>{0, 0, 0, 3}));
  segmentation.labels.pop_back();
  EXPECT_THROW(labelsFromThinned(cloud, thinned, segmentation, 0.1), InvalidInputError);
  segmentation.labels.push_back(1);  // names no plane
  EXPECT_THROW(labelsFromThinned(cloud, thinned, segmentation, 0.1), InvalidInputError);
}

// Over several chunks of the parallel search, any thread count labels every point alike, and the
// progress callback sees every chunk end, the last at the point count.
TEST(Thinning, LabellingOnSeveralThreadsMatchesOneThread) {
  pcl::PointCloud<pcl::PointNormal> thinned, cloud;
  PlanarSegmentation segmentation;
  segmentation.planes = {Plane::fromPointAndNormal({0, 0, 0}, {0, 0, 1}),
                         Plane::fromPointAndNormal({0, 0, 0}, {1, 0, 0})};
  for (int i = 0; i < 50; ++i)
    for (int j = 0; j < 50; ++j) {
      pcl::PointNormal floor, wall;
      floor.x = 0.02f * static_cast<float>(i), floor.y = 0.02f * static_cast<float>(j), floor.z = 0.0f;
      wall.x = 0.0f, wall.y = floor.x, wall.z = 0.02f + floor.y;
      thinned.push_back(floor);
      segmentation.labels.push_back(0);
      thinned.push_back(wall);
      segmentation.labels.push_back(1);
    }
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.0f, 1.0f);
  for (int i = 0; i < 150000; ++i) {  // three chunks; a few points on neither plane
    pcl::PointNormal p;
    p.x = unit(rng), p.y = unit(rng), p.z = unit(rng);
    if (i % 3 == 0) p.z = 0.0f;
    else if (i % 3 == 1) p.x = 0.0f;
    cloud.push_back(p);
  }
  std::vector<std::size_t> calls;
  const std::vector<int> one = labelsFromThinned(cloud, thinned, segmentation, 0.005, nullptr, {}, 1);
  const std::vector<int> two = labelsFromThinned(
      cloud, thinned, segmentation, 0.005, nullptr, [&](std::size_t done) { calls.push_back(done); }, 2);
  EXPECT_EQ(one, two);
  EXPECT_EQ(calls, (std::vector<std::size_t>{65536, 131072, 150000}));
  std::map<int, std::size_t> counts;
  for (const int label : one) ++counts[label];
  EXPECT_GE(counts[0] + counts[1], 100000u);  // every point of the floor and the wall
  EXPECT_GT(counts[1], 45000u);
  EXPECT_GT(counts[-1], 45000u);  // most of the points off both planes
}

TEST(Thinning, ACloudWithinTheBudgetIsCopiedAsItIs) {
  const LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 1, 1}), 1000, 1);
  box.cloud->push_back(pcl::PointNormal());  // a non-finite point stays: nothing is thinned
  box.cloud->back().x = std::numeric_limits<float>::quiet_NaN();
  pcl::PointCloud<pcl::PointNormal> out;
  const ThinningReport report = thinToPointBudget(*box.cloud, 1001, out);
  EXPECT_FALSE(report.thinned());
  EXPECT_EQ(report.voxel_size, 0.0);
  ASSERT_EQ(out.size(), box.cloud->size());
  for (std::size_t i = 0; i + 1 < out.size(); ++i) EXPECT_EQ(keyOf(out[i]), keyOf((*box.cloud)[i]));
}

TEST(Thinning, NonFinitePointsAreLeftOutWhenThinning) {
  LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 1, 1}), 3000, 2);
  for (std::size_t i = 0; i < box.cloud->size(); i += 10) (*box.cloud)[i].z = std::numeric_limits<float>::infinity();
  pcl::PointCloud<pcl::PointNormal> out;
  const ThinningReport report = thinToPointBudget(*box.cloud, 1000, out);
  EXPECT_TRUE(report.thinned());
  EXPECT_LE(out.size(), 1000u);
  EXPECT_GE(out.size(), 850u);
  for (const auto& p : out) EXPECT_TRUE(std::isfinite(p.z));
}

TEST(RepeatedPoints, EachRepeatNamesTheFirstPointAtItsPosition) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (const auto& xyz : {Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0), Eigen::Vector3f(0, 0, 0),
                          Eigen::Vector3f(1, 0, 1e-6f), Eigen::Vector3f(0, 0, 0), Eigen::Vector3f(1, 0, 0)})
    cloud.push_back(pcl::PointXYZ(xyz.x(), xyz.y(), xyz.z()));
  cloud.push_back(pcl::PointXYZ(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  cloud.push_back(pcl::PointXYZ(std::numeric_limits<float>::quiet_NaN(), 0, 0));
  EXPECT_EQ(findRepeatedPoints(cloud), (std::vector<int>{-1, -1, 0, -1, 0, 1, -1, -1}));
  pcl::PointCloud<pcl::PointXYZ> distinct;
  EXPECT_EQ(removeRepeatedPoints(cloud, distinct), 3u);
  ASSERT_EQ(distinct.size(), 5u);
  EXPECT_EQ(distinct[2].z, 1e-6f);  // close is not the same: only exact repeats go
  EXPECT_THROW(removeRepeatedPoints(cloud, cloud), InvalidInputError);
}

// A unit box scanned with 2,000 points, and points added around it.
pcl::PointCloud<pcl::PointNormal> boxWith(const std::vector<Eigen::Vector3f>& extra) {
  pcl::PointCloud<pcl::PointNormal> cloud = *test::sampleShape(test::makeBox({0, 0, 0}, {1, 1, 1}), 2000, 4).cloud;
  for (const auto& xyz : extra) {
    pcl::PointNormal p;
    p.getVector3fMap() = xyz;
    p.getNormalVector3fMap() = Eigen::Vector3f::UnitZ();
    cloud.push_back(p);
  }
  return cloud;
}

TEST(StrayPoints, APointFarFromTheScanIsStray) {
  // The box's diagonal is 1.73: a point 38 units away, and a group of 3 points 5 units away.
  const pcl::PointCloud<pcl::PointNormal> cloud =
      boxWith({{38, 38, 38}, {6, 0.5, 0.5}, {6.02, 0.5, 0.5}, {6, 0.52, 0.5}});
  EXPECT_EQ(findStrayPoints(cloud), (std::vector<int>{2000, 2001, 2002, 2003}));
  pcl::PointCloud<pcl::PointNormal> working;
  const ScanPreparationReport report = prepareScanPoints(cloud, 0, working);
  EXPECT_EQ(report.strays_removed, 4u);
  EXPECT_EQ(working.size(), 2000u);
  EXPECT_TRUE(report.changed());
  EXPECT_EQ(prepareScanPoints(cloud, 0, working, /*remove_strays=*/false).strays_removed, 0u);
  EXPECT_EQ(working.size(), 2004u);
}

TEST(StrayPoints, PointsNearerThanTheScanIsWideOrManyOfThemAreKept) {
  // 1.5 units from the box (less than its 1.73 diagonal): kept, like ground returns below a roof.
  EXPECT_TRUE(findStrayPoints(boxWith({{2.5, 0.5, 0.5}})).empty());
  // 20 points (1 % of the scan) 5 units away: a second piece of the object, not stray.
  std::vector<Eigen::Vector3f> piece;
  for (int i = 0; i < 20; ++i) piece.emplace_back(6.0f + 0.01f * static_cast<float>(i), 0.5f, 0.5f);
  EXPECT_TRUE(findStrayPoints(boxWith(piece)).empty());
  // No stray in the box alone; non-finite points are never stray.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_TRUE(findStrayPoints(boxWith({{nan, 0, 0}})).empty());
  EXPECT_EQ(findStrayPoints(boxWith({{nan, 0, 0}, {40, 0, 0}})), (std::vector<int>{2001}));
}

TEST(StrayPoints, ASparseCloudOrMoreFarPointsThanStraysHaveIsKept) {
  // Ten points spread through a box, each farther from the others than a link: no group holds
  // most of them, so none is stray (all but one were, and the segmenter then said "the input has 1").
  pcl::PointCloud<pcl::PointXYZ> sparse;
  for (int i = 0; i < 10; ++i)
    sparse.push_back(pcl::PointXYZ(float(i % 2), float((i / 2) % 2) + 0.1f * float(i), float(i / 4)));
  EXPECT_TRUE(findStrayPoints(sparse).empty());
  // A 2,000-point box and 11 single points far from it and from each other: one more than 0.5 %
  // of the points, so none is stray; with 10 of them, all are.
  // (On a sphere of radius 40 about the box, more than 30 apart: each is a group of its own.)
  std::vector<Eigen::Vector3f> far;
  for (int i = 0; i < 11; ++i) {
    const float z = 1.0f - 2.0f * (float(i) + 0.5f) / 11.0f, r = std::sqrt(1.0f - z * z), a = 2.4f * float(i);
    far.push_back(Eigen::Vector3f(0.5f, 0.5f, 0.5f) + 40.0f * Eigen::Vector3f(r * std::cos(a), r * std::sin(a), z));
  }
  EXPECT_TRUE(findStrayPoints(boxWith(far)).empty());
  far.pop_back();
  EXPECT_EQ(findStrayPoints(boxWith(far)).size(), 10u);
}

TEST(Thinning, BadInputIsAClearError) {
  const LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 1, 1}), 1000, 3);
  pcl::PointCloud<pcl::PointNormal> out;
  EXPECT_THROW(thinToPointBudget(*box.cloud, kMinPointBudget - 1, out), InvalidInputError);
  EXPECT_THROW(thinToPointBudget(*box.cloud, 500, *box.cloud), InvalidInputError);
  pcl::PointCloud<pcl::PointNormal> all_nan(600, 1, pcl::PointNormal());
  for (auto& p : all_nan) p.x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(thinToPointBudget(all_nan, 500, out), InvalidInputError);
  // Coincident points thin to one.
  pcl::PointCloud<pcl::PointNormal> same(600, 1, pcl::PointNormal());
  EXPECT_EQ(thinToPointBudget(same, 500, out).output_points, 1u);
  EXPECT_EQ(out.size(), 1u);
}

}  // namespace
}  // namespace paco
