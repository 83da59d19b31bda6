// The share of the primitives' points far from a surface (src/point_coverage.h), with which the
// assembler compares PolyFit's optimum and its warm start.
#include "point_coverage.h"

#include "shapes.h"

#include <gtest/gtest.h>

namespace {

using paco::detail::shareOfPointsFartherThan;

paco::PlanarPrimitive pointsAt(const std::vector<Eigen::Vector3d>& positions) {
  paco::PlanarPrimitive primitive;
  for (const Eigen::Vector3d& x : positions) {
    pcl::PointNormal p;
    p.x = static_cast<float>(x.x());
    p.y = static_cast<float>(x.y());
    p.z = static_cast<float>(x.z());
    primitive.points.push_back(p);
  }
  return primitive;
}

// Unit cube; points on a face, 0.25 inside, 0.5 outside and at the centre (0.5 from every face),
// over two primitives: the counts beyond each distance are known by hand.
TEST(PointCoverage, CountsThePointsFartherThanTheDistanceOverAllPrimitives) {
  const paco::SurfaceMesh cube = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  const std::vector<paco::PlanarPrimitive> primitives = {
      pointsAt({{0.5, 0.5, 1.0}, {0.25, 0.5, 0.5}}),         // on the top; 0.25 from x = 0
      pointsAt({{0.5, 0.5, 1.5}, {0.5, 0.5, 0.5}})};         // 0.5 above the top; the centre
  EXPECT_DOUBLE_EQ(shareOfPointsFartherThan(cube, primitives, 0.1), 0.75);
  EXPECT_DOUBLE_EQ(shareOfPointsFartherThan(cube, primitives, 0.3), 0.5);
  EXPECT_DOUBLE_EQ(shareOfPointsFartherThan(cube, primitives, 0.6), 0.0);
}

TEST(PointCoverage, NoPointsIsNothingFarAndNoSurfaceIsEverythingFar) {
  const paco::SurfaceMesh cube = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  EXPECT_EQ(shareOfPointsFartherThan(cube, {}, 0.1), 0.0);
  EXPECT_EQ(shareOfPointsFartherThan(paco::SurfaceMesh{}, {pointsAt({{0, 0, 0}})}, 0.1), 1.0);
}

}  // namespace
