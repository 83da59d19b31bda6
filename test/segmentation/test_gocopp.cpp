// The GoCoPP optimiser's energy and its operators, one by one.
#include "segmentation_fixtures.h"
#include "shapes.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/segmentation/gocopp_segmenter.h>

#include <pcl/search/kdtree.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace paco {
namespace {

/// k-nearest-neighbour lists (self excluded) for the optimiser.
std::vector<std::vector<int>> knn(const pcl::PointCloud<pcl::PointNormal>::Ptr& cloud, int k = 20) {
  pcl::search::KdTree<pcl::PointNormal> tree;
  tree.setInputCloud(cloud);
  std::vector<std::vector<int>> lists(cloud->size());
  pcl::Indices found;
  std::vector<float> d;
  for (std::size_t i = 0; i < cloud->size(); ++i) {
    tree.nearestKSearch((*cloud)[i], k + 1, found, d);
    for (const auto j : found)
      if (static_cast<std::size_t>(j) != i) lists[i].push_back(static_cast<int>(j));
  }
  return lists;
}

/// A grid of points on the plane z = 0 over [0, w] x [0, h], normals +z.
pcl::PointCloud<pcl::PointNormal>::Ptr grid(int nx, int ny, double w, double h) {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointNormal>);
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      pcl::PointNormal p;
      p.x = static_cast<float>(w * i / (nx - 1));
      p.y = static_cast<float>(h * j / (ny - 1));
      p.z = 0.0f;
      p.normal_x = p.normal_y = 0.0f;
      p.normal_z = 1.0f;
      cloud->push_back(p);
    }
  return cloud;
}

GoCoPPParameters parameters(double epsilon = 0.004) {
  GoCoPPParameters p;
  p.epsilon = epsilon;
  return p;
}

TEST(GoCoPPEnergy, MatchesTheFormulaOnAKnownConfiguration) {
  auto cloud = grid(20, 10, 0.5, 0.25);  // 200 points, all on z = 0
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters());
  std::vector<int> labels(200, -1);
  for (int i = 0; i < 150; ++i) labels[static_cast<std::size_t>(i)] = 0;
  optimizer.setLabels(labels);
  const GoCoPPEnergy e = optimizer.energy();
  EXPECT_NEAR(e.fidelity, 0.0, 1e-6);          // every point on its plane
  EXPECT_DOUBLE_EQ(e.simplicity, 50.0 / 200);  // 1 primitive / (N / σ)
  EXPECT_DOUBLE_EQ(e.completeness, 0.25);      // 50 of 200 unassigned
  EXPECT_NEAR(e.total, (0.0 + 0.25 + 0.25) / 3.0, 1e-6);
}

TEST(GoCoPPOperators, TwoCoplanarHalvesMerge) {
  auto cloud = grid(30, 20, 0.6, 0.4);
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters());
  std::vector<int> labels(cloud->size());
  for (std::size_t i = 0; i < cloud->size(); ++i) labels[i] = (*cloud)[i].x < 0.3f ? 0 : 1;
  optimizer.setLabels(labels);
  ASSERT_EQ(optimizer.numPrimitives(), 2u);
  const double before = optimizer.energy().total;
  EXPECT_TRUE(optimizer.tryMerge(0, 1));
  EXPECT_EQ(optimizer.numPrimitives(), 1u);
  EXPECT_LT(optimizer.energy().total, before);
  for (const int l : optimizer.labels()) EXPECT_EQ(l, 0);
}

TEST(GoCoPPOperators, PerpendicularFacesDoNotMerge) {
  test::LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 1, 1}), 3000, 3);
  // Keep two adjacent faces: the bottom (z = 0) and the front (y = 0).
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointNormal>);
  std::vector<int> labels;
  for (std::size_t i = 0; i < box.cloud->size(); ++i) {
    const auto& p = (*box.cloud)[i];
    if (p.normal_z < -0.5f) {
      cloud->push_back(p);
      labels.push_back(0);
    } else if (p.normal_y < -0.5f) {
      cloud->push_back(p);
      labels.push_back(1);
    }
  }
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters(0.004 * std::sqrt(3.0)));
  optimizer.setLabels(labels);
  EXPECT_FALSE(optimizer.tryMerge(0, 1));
  EXPECT_EQ(optimizer.numPrimitives(), 2u);
}

/// Two planes meeting at a ridge: z = t·|x - 0.5| over [0, 1] x [0, 0.6], normals exact.
pcl::PointCloud<pcl::PointNormal>::Ptr ridge(double slope, std::vector<int>& side) {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointNormal>);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 800; ++i) {
    const double x = u(rng), y = 0.6 * u(rng);
    const double s = x < 0.5 ? -1.0 : 1.0;
    pcl::PointNormal p;
    p.x = static_cast<float>(x);
    p.y = static_cast<float>(y);
    p.z = static_cast<float>(slope * std::abs(x - 0.5));
    const Eigen::Vector3d n = Eigen::Vector3d(-s * slope, 0, 1).normalized();
    p.getNormalVector3fMap() = n.cast<float>();
    cloud->push_back(p);
    side.push_back(x < 0.5 ? 0 : 1);
  }
  return cloud;
}

TEST(GoCoPPOperators, AnOverMergedRegionSplits) {
  std::vector<int> side;
  auto cloud = ridge(std::tan(paco::degreesToRadians(15.0)), side);  // a 150° ridge
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters());
  optimizer.setLabels(std::vector<int>(cloud->size(), 0));
  const double before = optimizer.energy().total;
  ASSERT_TRUE(optimizer.trySplit(0));
  EXPECT_EQ(optimizer.numPrimitives(), 2u);
  EXPECT_LT(optimizer.energy().total, before);
  // The two parts are the two sides of the ridge.
  const auto labels = optimizer.labels();
  std::size_t agree = 0;
  for (std::size_t i = 0; i < side.size(); ++i) agree += (labels[i] == labels[0]) == (side[i] == side[0]) ? 1 : 0;
  EXPECT_GT(agree, side.size() * 98 / 100);
}

TEST(GoCoPPOperators, ANoisyFlatRegionDoesNotSplit) {
  auto cloud = grid(30, 30, 0.7, 0.7);
  std::mt19937 rng(9);
  std::normal_distribution<float> noise(0.0f, 0.001f);
  for (auto& p : *cloud) p.z = noise(rng);
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters());
  optimizer.setLabels(std::vector<int>(cloud->size(), 0));
  EXPECT_FALSE(optimizer.trySplit(0));
  EXPECT_EQ(optimizer.numPrimitives(), 1u);
}

TEST(GoCoPPOperators, OutliersAreExcluded) {
  auto cloud = grid(25, 20, 0.5, 0.4);
  const std::size_t inliers = cloud->size();
  // 25 points lifted 5 ε above the plane, labelled with it.
  for (int i = 0; i < 25; ++i) {
    pcl::PointNormal p = (*cloud)[static_cast<std::size_t>(i * 19)];
    p.z = 5 * 0.004f;
    cloud->push_back(p);
  }
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters());
  optimizer.setLabels(std::vector<int>(cloud->size(), 0));
  const double before = optimizer.energy().total;
  ASSERT_TRUE(optimizer.tryExclude(0));
  EXPECT_LT(optimizer.energy().total, before);
  const auto labels = optimizer.labels();
  for (std::size_t i = 0; i < cloud->size(); ++i) EXPECT_EQ(labels[i], i < inliers ? 0 : -1) << i;
  EXPECT_FALSE(optimizer.tryExclude(0)) << "nothing left to exclude";
}

TEST(GoCoPPOperators, UnassignedNeighboursAreInserted) {
  auto cloud = grid(30, 20, 0.6, 0.4);
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters());
  std::vector<int> labels(cloud->size(), -1);
  for (std::size_t i = 0; i < cloud->size(); ++i)
    if ((*cloud)[i].x < 0.4f) labels[i] = 0;
  optimizer.setLabels(labels);
  const double before = optimizer.energy().completeness;
  ASSERT_TRUE(optimizer.tryInsert(0));
  EXPECT_LT(optimizer.energy().completeness, before);
  // Repeated insertions reach the whole plane.
  while (optimizer.tryInsert(0)) {
  }
  EXPECT_DOUBLE_EQ(optimizer.energy().completeness, 0.0);
}

TEST(GoCoPPOperators, TransferReturnsBoundaryPointsToTheirPlane) {
  // Two perpendicular faces; the bottom-face points within ε of the front face are given to it.
  test::LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 1, 1}), 6000, 4);
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud(new pcl::PointCloud<pcl::PointNormal>);
  std::vector<int> labels, truth;
  const double eps = 0.004 * std::sqrt(3.0);
  std::size_t wrong = 0;
  for (const auto& p : *box.cloud) {
    if (p.normal_z < -0.5f) {
      cloud->push_back(p);
      truth.push_back(0);
      const bool near_front = p.y < eps * 0.9;
      labels.push_back(near_front ? 1 : 0);
      wrong += near_front ? 1 : 0;
    } else if (p.normal_y < -0.5f) {
      cloud->push_back(p);
      truth.push_back(1);
      labels.push_back(1);
    }
  }
  ASSERT_GT(wrong, 0u);
  const auto lists = knn(cloud);
  GoCoPPOptimizer optimizer(*cloud, lists, parameters(eps));
  optimizer.setLabels(labels);
  ASSERT_TRUE(optimizer.transfer());
  const auto result = optimizer.labels();
  for (std::size_t i = 0; i < truth.size(); ++i) EXPECT_EQ(result[i], truth[i]) << i;
}

TEST(GoCoPPOptimizer, RoundsRepairAFragmentedBox) {
  // Region growing then rounds on a box cut into many pieces: one primitive per face.
  test::LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 0.8, 0.6}), 3000, 8);
  const auto lists = knn(box.cloud);
  GoCoPPOptimizer optimizer(*box.cloud, lists, parameters(0.004 * std::sqrt(2.0)));
  std::vector<int> fragments(box.cloud->size());
  for (std::size_t i = 0; i < fragments.size(); ++i) {
    const auto& p = (*box.cloud)[i];
    // Face label times 4 quadrants: 24 fragments.
    fragments[i] = box.labels[i] * 4 + (p.x + p.y + p.z > 1.2f ? 2 : 0) + (p.x - p.y > 0.1f ? 1 : 0);
  }
  optimizer.setLabels(fragments);
  const double before = optimizer.energy().total;
  optimizer.optimize();
  EXPECT_EQ(optimizer.numPrimitives(), 6u);
  EXPECT_LT(optimizer.energy().total, before);
}

TEST(GoCoPPOptimizer, RegionGrowingFindsTheFacesOfABox) {
  test::LabelledSample box = test::sampleShape(test::makeBox({0, 0, 0}, {1, 0.8, 0.6}), 3000, 8);
  const auto lists = knn(box.cloud);
  GoCoPPOptimizer optimizer(*box.cloud, lists, parameters(0.004 * std::sqrt(2.0)));
  optimizer.growRegions();
  EXPECT_EQ(optimizer.numPrimitives(), 6u);
  EXPECT_LT(optimizer.energy().completeness, 0.05);
}

TEST(GoCoPPOptimizer, BadParametersAreRejected) {
  auto cloud = grid(5, 5, 1, 1);
  const auto lists = knn(cloud, 5);
  GoCoPPParameters p;
  p.lambda_simplicity = 2.0;
  p.lambda_completeness = 1.5;
  EXPECT_THROW(GoCoPPOptimizer(*cloud, lists, p), InvalidInputError);
  std::vector<std::vector<int>> short_lists(3);
  EXPECT_THROW(GoCoPPOptimizer(*cloud, short_lists, GoCoPPParameters{}), InvalidInputError);
}

}  // namespace
}  // namespace paco
