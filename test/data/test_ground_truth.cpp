#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/data/ground_truth.h>

#include "shapes.h"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace {

using paco::data::extractGroundTruth;
using paco::data::GroundTruth;

Eigen::Matrix3d someRotation() {
  return (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()) *
          Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

/// Every expected normal has exactly one recovered plane within `tolerance` (radians).
void expectNormals(const GroundTruth& gt, std::vector<Eigen::Vector3d> expected, double tolerance = 1e-9) {
  ASSERT_EQ(gt.faces.size(), expected.size());
  for (const auto& face : gt.faces) {
    auto it = std::find_if(expected.begin(), expected.end(), [&](const Eigen::Vector3d& n) {
      return (face.plane.normal - n.normalized()).norm() < tolerance;
    });
    ASSERT_NE(it, expected.end()) << "unexpected normal " << face.plane.normal.transpose();
    expected.erase(it);
  }
}

TEST(GroundTruth, BoxHasSixAxisPlanesWithAreas) {
  const GroundTruth gt = extractGroundTruth(paco::test::makeBox({0, 0, 0}, {3, 2, 1}));
  expectNormals(gt, {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}});
  // Sorted by area: the two 3 x 2 faces first, then 3 x 1, then 2 x 1.
  EXPECT_NEAR(gt.faces[0].area, 6.0, 1e-12);
  EXPECT_NEAR(gt.faces[2].area, 3.0, 1e-12);
  EXPECT_NEAR(gt.faces[5].area, 2.0, 1e-12);
  EXPECT_NEAR(gt.faces[0].plane.normal.z() * gt.faces[0].plane.normal.z(), 1.0, 1e-12);
  for (const auto& face : gt.faces) {  // offsets: the box spans [0,3] x [0,2] x [0,1]
    const Eigen::Vector3d n = face.plane.normal;
    const double expected = n.sum() > 0 ? -(n.x() * 3 + n.y() * 2 + n.z() * 1) : 0.0;
    EXPECT_NEAR(face.plane.offset, expected, 1e-12);
  }
}

TEST(GroundTruth, ChamferAndBossPlanesRecoveredExactlyUnderRotation) {
  const Eigen::Matrix3d r = someRotation();
  paco::SurfaceMesh chamfered = paco::test::makeChamferedCube(0.3);
  paco::test::transformMesh(chamfered, r, Eigen::Vector3d(5, -2, 1));
  std::vector<Eigen::Vector3d> expected{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}, {1, 0, 1}};
  for (auto& n : expected) n = r * n.normalized();
  expectNormals(extractGroundTruth(chamfered), expected);

  paco::SurfaceMesh boss = paco::test::makeBossOnSlab();
  paco::test::transformMesh(boss, r, Eigen::Vector3d::Zero());
  const GroundTruth gt = extractGroundTruth(boss);
  EXPECT_EQ(gt.faces.size(), 11u);  // slab 6 + boss 5 (the slab top ring is one plane)
  double total = 0;
  for (const auto& face : gt.faces) total += face.area;
  EXPECT_NEAR(total, paco::surfaceArea(boss), 1e-9);
}

TEST(GroundTruth, DisjointCoplanarRegionsAreOnePlane) {
  // U-section prism: both arm tops lie on y = 2 (disjoint, same orientation): 9 planes, not 10.
  const paco::SurfaceMesh u = paco::test::makePrism({{0, 0}, {3, 0}, {3, 2}, {2, 2}, {2, 1}, {1, 1}, {1, 2}, {0, 2}}, 1.0);
  const GroundTruth gt = extractGroundTruth(u);
  EXPECT_EQ(gt.faces.size(), 9u);
}

TEST(GroundTruth, InsideOutMeshIsFlippedToOutwardNormals) {
  paco::SurfaceMesh box = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  paco::flipFaces(box);
  const GroundTruth gt = extractGroundTruth(box);
  for (const auto& face : gt.faces) {  // outward: the centre is on the negative side
    EXPECT_LT(face.plane.signedDistance(Eigen::Vector3d(0.5, 0.5, 0.5)), 0.0);
  }
}

TEST(GroundTruth, TessellatedCylinderIsRejected) {
  std::vector<Eigen::Vector2d> circle;
  for (int k = 0; k < 48; ++k) circle.emplace_back(std::cos(2 * paco::kPi * k / 48), std::sin(2 * paco::kPi * k / 48));
  try {
    extractGroundTruth(paco::test::makePrism(circle, 2.0));
    FAIL() << "a tessellated cylinder was accepted";
  } catch (const paco::InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("not plane-only"), std::string::npos) << e.what();
  }
  // A hexagonal prism is plane-only (60 degree turns).
  std::vector<Eigen::Vector2d> hexagon;
  for (int k = 0; k < 6; ++k) hexagon.emplace_back(std::cos(paco::kPi * k / 3), std::sin(paco::kPi * k / 3));
  EXPECT_EQ(extractGroundTruth(paco::test::makePrism(hexagon, 1.0)).faces.size(), 8u);
}

TEST(GroundTruth, OpenMeshIsRejected) {
  paco::SurfaceMesh box = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  box.faces.pop_back();
  try {
    extractGroundTruth(box);
    FAIL() << "an open box was accepted";
  } catch (const paco::InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("not closed"), std::string::npos) << e.what();
  }
  paco::data::GroundTruthOptions lenient;
  lenient.require_closed = false;
  EXPECT_EQ(extractGroundTruth(box, lenient).faces.size(), 5u);
  EXPECT_THROW(extractGroundTruth(paco::SurfaceMesh{}), paco::InvalidInputError);
}

TEST(GroundTruth, SampledPointsLieOnTheirPlanes) {
  paco::SurfaceMesh boss = paco::test::makeBossOnSlab();
  paco::test::transformMesh(boss, someRotation(), Eigen::Vector3d(0.3, 0.2, -4));
  const GroundTruth gt = extractGroundTruth(boss);
  const paco::data::GtPoints points = paco::data::sampleGroundTruth(gt, 8192, 11);
  ASSERT_EQ(points.points.size(), 8192u);
  std::vector<int> hits(gt.faces.size(), 0);
  for (std::size_t i = 0; i < points.points.size(); ++i) {
    const auto& face = gt.faces.at(points.labels[i]);
    EXPECT_LT(std::abs(face.plane.signedDistance(points.points[i])), 1e-6 * gt.diagonal);
    EXPECT_LT((points.normals[i] - face.plane.normal).norm(), 1e-12);
    ++hits[points.labels[i]];
  }
  // Uniform by area: the largest face (slab bottom, area 4 of 4+8+3+1+4 = 20) gets ~20 %.
  double total = 0;
  for (const auto& f : gt.faces) total += f.area;
  EXPECT_NEAR(hits[0] / 8192.0, gt.faces[0].area / total, 0.02);
}

}  // namespace
