#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/data/partial.h>

#include "shapes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

namespace {

using namespace paco::data;

/// The boss-on-slab part, normalised (centre 0, unit diagonal).
GroundTruth normalisedBoss() {
  paco::SurfaceMesh mesh = paco::test::makeBossOnSlab();
  paco::Normalization::fromBoundingBox(mesh.vertices).apply(mesh);
  return extractGroundTruth(mesh);
}

TEST(Partial, ViewpointsAreEightDistinctUnitDirections) {
  std::set<std::tuple<double, double, double>> seen;
  for (int v = 0; v < 8; ++v) {
    const Eigen::Vector3d d = viewpointDirection(v, 8);
    EXPECT_NEAR(d.norm(), 1.0, 1e-12);
    seen.insert({d.x(), d.y(), d.z()});
  }
  EXPECT_EQ(seen.size(), 8u);
  EXPECT_NEAR(viewpointDirection(13, 20).norm(), 1.0, 1e-12);
  EXPECT_THROW(viewpointDirection(8, 8), paco::InvalidInputError);
}

TEST(Partial, NearestRemovalReachesTheAskedMissingRatio) {
  const GroundTruth gt = normalisedBoss();
  const PartialScanner scanner(gt, PartialOptions{}, 3);
  // An independent uniform sample measures the removed area: the points nearer to the viewpoint
  // than the nearest kept point.
  const GtPoints probe = sampleGroundTruth(gt, 8192, 99);
  for (double ratio : {0.25, 0.5, 0.75}) {
    for (int view : {0, 5}) {
      const Eigen::Vector3d dir = viewpointDirection(view, 8);
      const PartialScan scan = scanner.scan(dir, ratio, 7);
      ASSERT_EQ(scan.points.size(), 2048u);
      EXPECT_NEAR(scan.missing_ratio, ratio, 1e-3);
      for (const auto& p : scan.points) EXPECT_GE((p - dir).norm(), scan.cut_distance - 1e-12);
      std::size_t removed = 0;
      for (const auto& p : probe.points) removed += (p - dir).norm() < scan.cut_distance;
      EXPECT_NEAR(static_cast<double>(removed) / probe.points.size(), ratio, 0.02) << "ratio " << ratio << " view " << view;
      for (std::size_t i = 0; i < scan.points.size(); ++i) {  // labels and normals are the GT face's
        const PlanarFace& face = gt.faces.at(scan.labels[i]);
        EXPECT_LT(std::abs(face.plane.signedDistance(scan.points[i])), 1e-9);
        EXPECT_LT((scan.normals[i] - face.plane.normal).norm(), 1e-12);
      }
    }
  }
}

TEST(Partial, NoiseHasTheAskedSigma) {
  const GroundTruth gt = normalisedBoss();
  PartialOptions options;
  options.noise_percent = 1.5;
  const PartialScanner scanner(gt, options, 3);
  const PartialScan scan = scanner.scan(viewpointDirection(2, 8), 0.5, 1);
  double sum2 = 0;  // the offset along the face normal is one Gaussian coordinate (rotation invariant)
  for (std::size_t i = 0; i < scan.points.size(); ++i) {
    const double d = gt.faces[scan.labels[i]].plane.signedDistance(scan.points[i]);
    sum2 += d * d;
  }
  EXPECT_NEAR(std::sqrt(sum2 / scan.points.size()), 0.015, 0.0015);
}

TEST(Partial, SameSeedSamePointsOtherSeedOthers) {
  const GroundTruth gt = normalisedBoss();
  const PartialScanner a(gt, PartialOptions{}, 5), b(gt, PartialOptions{}, 5);
  const PartialScan s1 = a.scan(viewpointDirection(1, 8), 0.5, 9), s2 = b.scan(viewpointDirection(1, 8), 0.5, 9);
  EXPECT_EQ(s1.points, s2.points);
  EXPECT_NE(s1.points, a.scan(viewpointDirection(1, 8), 0.5, 10).points);
}

TEST(Partial, VisibilityModeKeepsOnlyWhatTheScannerSees) {
  const GroundTruth gt = normalisedBoss();
  PartialOptions options;
  options.mode = RemovalMode::Visibility;
  const PartialScanner scanner(gt, options, 3);
  const Eigen::Vector3d dir = viewpointDirection(0, 8);  // (1,1,1): sees +x, +y, +z faces
  const PartialScan scan = scanner.scan(dir, 0.75, 2);
  EXPECT_NEAR(scan.missing_ratio, 0.75, 1e-3);
  for (std::size_t i = 0; i < scan.points.size(); ++i)
    EXPECT_GT(scan.normals[i].dot(dir - scan.points[i]), 0.0) << "a back-facing point was kept";
  // 25 % missing needs more than one station (a scanner sees about half of a convex part).
  const PartialScan simple = scanner.scan(dir, 0.25, 2);
  EXPECT_NEAR(simple.missing_ratio, 0.25, 0.01);
  // Ray casting: the boss hides part of the slab top from a low viewpoint.
  const Eigen::Vector3d eye(1.0, 0.0, 0.05);
  const std::vector<Eigen::Vector3d> points{{-0.2, 0.0, 0.0}, {0.22, 0.0, 0.0}};  // slab top behind / before the boss
  const std::vector<Eigen::Vector3d> normals{{0, 0, 1}, {0, 0, 1}};
  const std::vector<bool> visible = visibleFrom(gt.mesh, points, normals, eye);
  EXPECT_FALSE(visible[0]);
  EXPECT_TRUE(visible[1]);
}

TEST(Partial, ASingleScannerKeepsEverythingItSeesAndNothingElse) {
  const GroundTruth gt = normalisedBoss();
  PartialOptions options;
  options.mode = RemovalMode::Visibility;
  options.single_scanner = true;
  const PartialScanner scanner(gt, options, 3);
  for (const int view : {0, 5}) {
    const Eigen::Vector3d dir = viewpointDirection(view, 8);
    // Asked to keep more than one scanner sees, it keeps all it sees: the same at 0 % and 25 %.
    const PartialScan all = scanner.scan(dir, 0.0, 2);
    const PartialScan simple = scanner.scan(dir, 0.25, 2);
    EXPECT_EQ(all.missing_ratio, simple.missing_ratio) << "view " << view;
    EXPECT_GT(simple.missing_ratio, 0.35) << "view " << view << ": a scanner sees about half of a convex part";
    for (std::size_t i = 0; i < simple.points.size(); ++i)
      ASSERT_GT(simple.normals[i].dot(dir - simple.points[i]), 0.0) << "view " << view << ": a back-facing point";
    // Asked to keep less, it keeps the points nearest to the scanner (a shorter range).
    EXPECT_NEAR(scanner.scan(dir, 0.75, 2).missing_ratio, 0.75, 1e-3) << "view " << view;
  }
  // With the stations, the other cube corners fill in up to the level.
  PartialOptions stations = options;
  stations.single_scanner = false;
  EXPECT_NEAR(PartialScanner(gt, stations, 3).scan(viewpointDirection(0, 8), 0.25, 2).missing_ratio, 0.25, 0.01);
}

}  // namespace
