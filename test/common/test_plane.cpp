#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/plane.h>

#include <gtest/gtest.h>

#include <cmath>

using paco::Plane;

TEST(Plane, ConstructorNormalisesNormalAndOffset) {
  Plane p(Eigen::Vector3d(0, 0, 2), -4);  // 2z - 4 = 0  ->  z = 2
  EXPECT_NEAR(p.normal.norm(), 1.0, 1e-15);
  EXPECT_NEAR(p.offset, -2.0, 1e-15);
  EXPECT_NEAR(p.signedDistance(Eigen::Vector3d(5, 5, 3)), 1.0, 1e-15);
  EXPECT_TRUE(p.project(Eigen::Vector3d(1, 2, 7)).isApprox(Eigen::Vector3d(1, 2, 2)));
  EXPECT_TRUE(p.foot().isApprox(Eigen::Vector3d(0, 0, 2)));
}

TEST(Plane, ZeroOrNonFiniteNormalIsRejected) {
  EXPECT_THROW(Plane(Eigen::Vector3d::Zero(), 1), paco::InvalidInputError);
  EXPECT_THROW(Plane(Eigen::Vector3d(NAN, 0, 1), 1), paco::InvalidInputError);
}

TEST(Plane, FitRecoversTiltedPlaneAndRespectsHint) {
  const Eigen::Vector3d n = Eigen::Vector3d(1, 2, 3).normalized();
  const Plane truth = Plane::fromPointAndNormal(Eigen::Vector3d(0.5, -1, 2), n);
  Eigen::Vector3d u = n.unitOrthogonal(), v = n.cross(u);
  std::vector<Eigen::Vector3d> pts;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) pts.push_back(truth.foot() + 0.1 * i * u + 0.07 * j * v);
  const Plane fit = Plane::fit(pts, -n);
  EXPECT_NEAR(fit.normal.dot(-n), 1.0, 1e-12);
  EXPECT_NEAR(fit.offset, -truth.offset, 1e-12);
}

TEST(Plane, FitOfCollinearPointsThrows) {
  std::vector<Eigen::Vector3d> pts = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
  EXPECT_THROW(Plane::fit(pts), paco::InvalidInputError);
  EXPECT_THROW(Plane::fit({{0, 0, 0}, {1, 0, 0}}), paco::InvalidInputError);
}

TEST(Plane, ModelCoefficientsRoundTrip) {
  const Plane p(Eigen::Vector3d(0, 0.6, 0.8), -1.5);
  const pcl::ModelCoefficients c = paco::toModelCoefficients(p);
  ASSERT_EQ(c.values.size(), 4u);
  EXPECT_FLOAT_EQ(c.values[1], 0.6f);
  EXPECT_FLOAT_EQ(c.values[3], -1.5f);
  const Plane q = paco::fromModelCoefficients(c);
  EXPECT_NEAR((q.normal - p.normal).norm(), 0, 1e-7);
  EXPECT_NEAR(q.offset, p.offset, 1e-7);
  pcl::ModelCoefficients bad;
  bad.values = {1, 2, 3};
  EXPECT_THROW(paco::fromModelCoefficients(bad), paco::InvalidInputError);
}

TEST(Plane, UnorientedAngleIgnoresFlip) {
  const Plane a(Eigen::Vector3d(0, 0, 1), 0);
  EXPECT_NEAR(a.unorientedAngleTo(a.flipped()), 0.0, 1e-12);
  const Plane b(Eigen::Vector3d(1, 0, 1), 0);
  EXPECT_NEAR(a.unorientedAngleTo(b), paco::kPi / 4, 1e-12);
}
