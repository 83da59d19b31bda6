#include <paco/common/error.h>
#include <paco/common/primitive.h>
#include <paco/common/scan_shares.h>

#include <gtest/gtest.h>

namespace {
paco::PlanarSegmentation twoPlaneSegmentation() {
  paco::PlanarSegmentation seg;
  seg.planes = {paco::Plane(Eigen::Vector3d(0, 0, 1), 0), paco::Plane(Eigen::Vector3d(1, 0, 0), -1)};
  seg.labels = {0, 0, 1, -1, 1};
  seg.rebuildSegmentsFromLabels();
  return seg;
}
}  // namespace

TEST(PlanarSegmentation, SegmentsAndLabelsAgree) {
  auto seg = twoPlaneSegmentation();
  ASSERT_EQ(seg.segments.size(), 2u);
  EXPECT_EQ(seg.segments[0].indices, (std::vector<int>{0, 1}));
  EXPECT_EQ(seg.segments[1].indices, (std::vector<int>{2, 4}));
  EXPECT_DOUBLE_EQ(seg.coverage(), 0.8);
  EXPECT_EQ(seg.pointsPerSegment(), (std::vector<std::size_t>{2, 2}));
  auto stray = seg;
  stray.labels.push_back(7);  // a label without a plane is not counted
  EXPECT_EQ(stray.pointsPerSegment(), (std::vector<std::size_t>{2, 2}));
  EXPECT_NO_THROW(seg.validate(5));
  EXPECT_THROW(seg.validate(6), paco::InvalidInputError);
  auto copy = seg;
  copy.rebuildLabelsFromSegments(5);
  EXPECT_EQ(copy.labels, seg.labels);
}

TEST(PlanarSegmentation, LabelWithoutPlaneIsRejected) {
  paco::PlanarSegmentation seg;
  seg.planes = {paco::Plane()};
  seg.labels = {0, 3};
  EXPECT_THROW(seg.rebuildSegmentsFromLabels(), paco::InvalidInputError);
}

// Stored labels 4 (z = 0, normals down), 2 (x = 1), 7 (two points: no plane) and -1: two
// segments in label order, each plane oriented like its points' normals.
TEST(PlanarSegmentation, FromLabelsFitsAPlaneToEachLabelWithThreePoints) {
  pcl::PointCloud<pcl::PointNormal> cloud;
  auto add = [&](float x, float y, float z, float nx, float ny, float nz) {
    pcl::PointNormal p;
    p.x = x, p.y = y, p.z = z, p.normal_x = nx, p.normal_y = ny, p.normal_z = nz;
    cloud.push_back(p);
  };
  add(0, 0, 0, 0, 0, -1), add(1, 0, 0, 0, 0, -1), add(0, 1, 0, 0, 0, -1);
  add(1, 0, 0, 1, 0, 0), add(1, 1, 0, 1, 0, 0), add(1, 0, 1, 1, 0, 0);
  add(5, 5, 5, 0, 0, 1), add(6, 5, 5, 0, 0, 1), add(9, 9, 9, 0, 0, 1);
  const std::vector<int> labels = {4, 4, 4, 2, 2, 2, 7, 7, -1};
  const auto seg = paco::PlanarSegmentation::fromLabels(cloud, labels);
  ASSERT_EQ(seg.size(), 2u);
  EXPECT_EQ(seg.labels, (std::vector<int>{1, 1, 1, 0, 0, 0, -1, -1, -1}));
  EXPECT_NEAR(seg.planes[0].normal.x(), 1.0, 1e-9);
  EXPECT_NEAR(seg.planes[0].offset, -1.0, 1e-9);
  EXPECT_NEAR(seg.planes[1].normal.z(), -1.0, 1e-9);
  EXPECT_EQ(seg.segments[1].indices, (std::vector<int>{0, 1, 2}));
  EXPECT_THROW(paco::PlanarSegmentation::fromLabels(cloud, {0, 0}), paco::InvalidInputError);
}

TEST(PlanarPrimitive, MakePrimitivesCopiesPointsAndUsesPlaneNormalWhenMissing) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < 5; ++i) cloud.push_back(pcl::PointXYZ(i, 0, 0));
  auto prims = paco::makePrimitives(cloud, twoPlaneSegmentation());
  ASSERT_EQ(prims.size(), 2u);
  ASSERT_EQ(prims[1].points.size(), 2u);
  EXPECT_FLOAT_EQ(prims[1].points[1].x, 4.0f);
  EXPECT_FLOAT_EQ(prims[1].points[0].normal_x, 1.0f);
  EXPECT_FLOAT_EQ(prims[0].confidence, 1.0f);

  pcl::PointCloud<pcl::PointNormal> flat;
  std::vector<int> labels;
  paco::flattenPrimitives(prims, flat, labels);
  EXPECT_EQ(flat.size(), 4u);
  EXPECT_EQ(labels, (std::vector<int>{0, 0, 1, 1}));
}

TEST(ScanShares, PercentTextPrintsTheShareAsTheToolsDo) {
  EXPECT_EQ(paco::percentText(0.01), "1 %");
  EXPECT_EQ(paco::percentText(0.005), "0.5 %");
  EXPECT_EQ(paco::percentText(0.015), "1.5 %");
}
