#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/common/surface_mesh.h>

#include <gtest/gtest.h>

TEST(Normalization, MovesBoxToOriginWithUnitDiagonalAndBack) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back({100, 200, 300});
  cloud.push_back({103, 204, 300});  // diagonal 5
  cloud.push_back({NAN, 0, 0});      // ignored for the box
  const auto n = paco::Normalization::fromBoundingBox(cloud);
  EXPECT_NEAR(n.scale, 0.2, 1e-12);
  EXPECT_TRUE(n.center.isApprox(Eigen::Vector3d(101.5, 202, 300)));
  auto copy = cloud;
  n.apply(copy);
  EXPECT_NEAR(copy[0].x, -0.3, 1e-6);
  EXPECT_NEAR(copy[1].y, 0.4, 1e-6);
  n.applyInverse(copy);
  EXPECT_NEAR(copy[1].x, 103, 1e-4);
  EXPECT_NEAR(copy[1].z, 300, 1e-4);
}

TEST(Normalization, PlaneStaysThroughTheSamePoints) {
  paco::Normalization n;
  n.center = Eigen::Vector3d(1, 2, 3);
  n.scale = 0.25;
  const paco::Plane p = paco::Plane::fromPointAndNormal(Eigen::Vector3d(4, 5, 6), Eigen::Vector3d(1, 1, 0));
  const paco::Plane q = n.apply(p);
  EXPECT_NEAR(q.signedDistance(n.apply(Eigen::Vector3d(4, 5, 6))), 0, 1e-12);
  EXPECT_NEAR(q.signedDistance(n.apply(Eigen::Vector3d(3, 6, -10))), 0, 1e-12);
  const paco::Plane back = n.applyInverse(q);
  EXPECT_NEAR(back.offset, p.offset, 1e-12);
}

TEST(Normalization, CompositionAndInverse) {
  paco::Normalization a{Eigen::Vector3d(1, 0, 0), 2.0}, b{Eigen::Vector3d(0, 3, 0), 0.5};
  const Eigen::Vector3d x(7, -2, 5);
  EXPECT_TRUE(a.then(b).apply(x).isApprox(b.apply(a.apply(x))));
  EXPECT_TRUE(a.inverse().apply(a.apply(x)).isApprox(x));
}

TEST(Normalization, DegenerateCloudIsRejected) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  EXPECT_THROW(paco::Normalization::fromBoundingBox(cloud), paco::InvalidInputError);
  cloud.push_back({1, 1, 1});
  cloud.push_back({1, 1, 1});
  EXPECT_THROW(paco::Normalization::fromBoundingBox(cloud), paco::InvalidInputError);
}
