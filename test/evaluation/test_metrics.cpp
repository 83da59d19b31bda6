// CD, HD, NC, the failure box and NC_prim against hand-computed values.
#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/evaluation/metrics.h>

#include <shapes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

namespace ev = paco::evaluation;
using paco::test::makeBox;

TEST(Metrics, IdenticalMeshWithTheSameSeedScoresExactlyZero) {
  const paco::SurfaceMesh mesh = paco::test::makeLBracket();
  ev::MetricOptions options;
  options.reference_seed = options.prediction_seed;  // the same samples on both
  const ev::MeshMetrics m = ev::evaluateMesh(mesh, mesh, options);
  EXPECT_EQ(m.chamfer, 0.0);
  EXPECT_EQ(m.hausdorff, 0.0);
  EXPECT_EQ(m.normal_consistency, 1.0);
  EXPECT_EQ(m.num_faces, mesh.faces.size());
  EXPECT_EQ(m.num_vertices, mesh.vertices.size());
  EXPECT_TRUE(m.closed);
  EXPECT_NEAR(m.volume_ratio, 1.0, 1e-12);
}

TEST(Metrics, IdenticalMeshWithIndependentSamplesScoresTheSamplingFloor) {
  // With the default (independent) seeds a perfect mesh is not exactly 0: the floor is about the
  // mean nearest-neighbour spacing of 10,000 points, well under 2 (x 100, unit diagonal), and
  // samples within about that spacing of an edge find their neighbour on the other face (normal
  // at 90 degrees): 12 edges x 2 sides x ~0.01 wide over an area of 6 costs NC about 0.02-0.03.
  const paco::SurfaceMesh mesh = makeBox({0, 0, 0}, {1, 1, 1});
  const ev::MeshMetrics m = ev::evaluateMesh(mesh, mesh);
  EXPECT_GT(m.chamfer, 0.0);
  EXPECT_LT(m.chamfer, 2.0);
  EXPECT_LT(m.hausdorff, 4.0);
  EXPECT_GT(m.normal_consistency, 0.97);
  EXPECT_LT(m.normal_consistency, 1.0);
}

TEST(Metrics, UnitCubesShiftedAlongXMatchTheHandDerivation) {
  // A = [0,1]^3 (prediction), B = A + (d,0,0) (GT), 0 < d < 1. Distances from A's surface to B's:
  //  - face x=0 (area 1): every point is d from B's face x=d.                      mean d
  //  - face x=1 (inside B): min(d, distance to the square's border t) with
  //    P(t > s) = (1-2s)^2, so the mean is int_0^d (1-2s)^2 ds = d - 2d^2 + 4d^3/3.
  //  - the 4 side faces: 0 where x >= d (B's side face is coplanar), d - x where x < d:
  //    mean int_0^d (d-x) dx = d^2/2 each.
  // Mean over the area 6: (2d + 4d^3/3) / 6 = d/3 + 2d^3/9; B->A is the same by symmetry, so
  // CD = 2d/3 + 4d^3/9 and HD = d (face x=0, whose samples have exact partners d away because
  // both meshes are sampled with the same seed and B is A translated).
  // NC: faces x=0 and the side faces at x >= d match parallel faces (1); on face x=1 the points
  // within d of the border match a perpendicular side face (0): a fraction 1-(1-2d)^2; side-face
  // points at x < d match B's face x=d, perpendicular (0). NC = (6 - 8d + 4d^2) / 6.
  // Everything is measured in B's normalised frame (diagonal sqrt(3)) and CD, HD are x 100.
  // Sampling only adds: each sampled NN distance is >= the distance to the continuous surface, by
  // at most about the sample spacing (50,000 points on area 6: spacing ~0.011, mean NN gap in a
  // plane ~0.5 / sqrt(8333) = 0.0055 over ~2/3 of the area, both directions: < 0.01 on CD).
  const double d = 0.1;
  const paco::SurfaceMesh a = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh b = makeBox({d, 0, 0}, {1 + d, 1, 1});
  ev::MetricOptions options;
  options.num_samples = 50000;
  options.reference_seed = options.prediction_seed;
  const ev::MeshMetrics m = ev::evaluateMesh(a, b, options);
  const double to_report = 100.0 / std::sqrt(3.0);
  const double cd = 2.0 * d / 3.0 + 4.0 * d * d * d / 9.0;
  EXPECT_GE(m.chamfer, cd * to_report - 1e-4);
  EXPECT_LE(m.chamfer, (cd + 0.01) * to_report);
  EXPECT_GE(m.hausdorff, d * to_report - 1e-4);
  EXPECT_LE(m.hausdorff, (d + 0.01) * to_report);
  EXPECT_NEAR(m.normal_consistency, (6.0 - 8.0 * d + 4.0 * d * d) / 6.0, 0.015);
  EXPECT_TRUE(m.closed);
  EXPECT_NEAR(m.volume_ratio, 1.0, 1e-12);
  // Each half of CD is d/3 + 2d^3/9 (the two directions are symmetric here).
  for (double half : {m.chamfer_pred_to_gt, m.chamfer_gt_to_pred}) {
    EXPECT_GE(half, cd / 2.0 * to_report - 1e-4);
    EXPECT_LE(half, (cd / 2.0 + 0.005) * to_report);
  }
  EXPECT_NEAR(m.chamfer_pred_to_gt + m.chamfer_gt_to_pred, m.chamfer, 1e-9);
}

TEST(Metrics, TheHalvesOfChamferTellExtraSurfaceFromMissedSurface) {
  // The prediction is the GT cube [0,1]^3 plus a second unit cube at x in [2,3]. Every GT point
  // lies on the prediction (GT->pred: only the sampling gap, < 0.01). Half the prediction's area
  // is the far cube, whose points are x - 1 from the GT: 1 on its face x=2, 2 on x=3, 1.5 on
  // average on its 4 side faces, 1.5 over the cube; so pred->GT = 0.75 (the far cube's share of
  // 50,000 samples is 0.5 +- 0.007 at 3 sigma: +-0.011).
  paco::SurfaceMesh prediction = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh far_cube = makeBox({2, 0, 0}, {3, 1, 1});
  const auto offset = static_cast<std::uint32_t>(prediction.vertices.size());
  prediction.vertices.insert(prediction.vertices.end(), far_cube.vertices.begin(), far_cube.vertices.end());
  for (auto face : far_cube.faces) {
    for (auto& v : face) v += offset;
    prediction.faces.push_back(face);
  }
  ev::MetricOptions options;
  options.num_samples = 50000;
  const ev::MeshMetrics m = ev::evaluateMesh(prediction, makeBox({0, 0, 0}, {1, 1, 1}), options);
  const double to_report = 100.0 / std::sqrt(3.0);
  EXPECT_NEAR(m.chamfer_pred_to_gt, 0.75 * to_report, 0.015 * to_report);
  EXPECT_LT(m.chamfer_gt_to_pred, 0.01 * to_report);
  EXPECT_NEAR(m.chamfer_pred_to_gt + m.chamfer_gt_to_pred, m.chamfer, 1e-9);
  // The far cube's face x = 3 is 2 from the GT. Every GT point lies on the prediction: its largest
  // gap to the prediction's samples (about 25,000 on the GT's area 6, 0.015 apart) stays below 0.05.
  EXPECT_NEAR(m.hausdorff_pred_to_gt, 2.0 * to_report, 0.01 * to_report);
  EXPECT_LT(m.hausdorff_gt_to_pred, 0.05 * to_report);
  EXPECT_EQ(m.hausdorff, m.hausdorff_pred_to_gt);
}

TEST(Metrics, DistancesScaleWithTheReferenceDiagonalOnlyWhenNormalizing) {
  const paco::SurfaceMesh a = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh b = makeBox({0.1, 0, 0}, {1.1, 1, 1});
  ev::MetricOptions options;
  options.num_samples = 2000;
  const ev::MeshMetrics normalized = ev::evaluateMesh(a, b, options);
  options.normalize_by_reference = false;
  options.distance_scale = 1.0;
  const ev::MeshMetrics raw = ev::evaluateMesh(a, b, options);
  EXPECT_NEAR(normalized.chamfer, raw.chamfer * 100.0 / std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(normalized.hausdorff, raw.hausdorff * 100.0 / std::sqrt(3.0), 1e-6);
  EXPECT_NEAR(normalized.normal_consistency, raw.normal_consistency, 1e-9);
}

TEST(Metrics, VolumeRatioOfASmallerClosedSolid) {
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh half = makeBox({0, 0, 0}, {1, 1, 0.5});
  EXPECT_NEAR(ev::evaluateMesh(half, gt).volume_ratio, 0.5, 1e-12);
  paco::SurfaceMesh open = gt;
  open.faces.pop_back();
  const ev::MeshMetrics m = ev::evaluateMesh(open, gt);
  EXPECT_FALSE(m.closed);
  EXPECT_TRUE(std::isnan(m.volume_ratio));
}

namespace {

// A grid of points over the top face z = 1 of the unit cube, `step` apart (edges included).
std::vector<Eigen::Vector3d> topFaceGrid(double step) {
  std::vector<Eigen::Vector3d> points;
  const int n = static_cast<int>(std::round(1.0 / step));
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) points.emplace_back(i * step, j * step, 1.0);
  return points;
}

}  // namespace

TEST(Metrics, GtToPredSplitsIntoTheSeenAndTheHiddenSurface) {
  // GT: the unit cube, seen from above (a 0.005 grid on its top face). Prediction: its top half,
  // [0,1]^2 x [0.5,1]. The seen radius 0.03 of the normalised frame is r = 0.03 sqrt(3) = 0.052
  // in the cube's units, so the seen GT surface is the top face plus a band r high on each side
  // face: hidden area 5 - 4r of 6. On the hidden surface the GT->pred distance is 0.5 on the
  // bottom face (area 1), 0.5 - z on the side faces below z = 0.5 (area 2, integral 0.5) and 0 on
  // the side faces above (the prediction's sides): mean 1 / (5 - 4r), x 100 / sqrt(3). The seen
  // surface lies on the prediction: only the sampling gap, < 1 (x 100). The gap also adds a
  // little on the hidden surface (about 0.66 on the 37 % of it at distance 0: +0.25).
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh top_half = makeBox({0, 0, 0.5}, {1, 1, 1});
  ev::MetricOptions options;
  options.num_samples = 50000;
  const ev::MeshMetrics m = ev::evaluateMesh(top_half, gt, topFaceGrid(0.005), options);
  const double r = 0.03 * std::sqrt(3.0);
  EXPECT_NEAR(m.hidden_fraction, (5.0 - 4.0 * r) / 6.0, 0.01);
  EXPECT_NEAR(m.chamfer_gt_to_pred_hidden, 100.0 / std::sqrt(3.0) / (5.0 - 4.0 * r) + 0.25, 0.4);
  EXPECT_LT(m.chamfer_gt_to_pred_seen, 1.0);
  // The two parts make up GT->pred, weighted by their shares.
  EXPECT_NEAR((1.0 - m.hidden_fraction) * m.chamfer_gt_to_pred_seen + m.hidden_fraction * m.chamfer_gt_to_pred_hidden,
              m.chamfer_gt_to_pred, 1e-9);
  // Without seen points the split is not measured, and the rest is the same.
  const ev::MeshMetrics plain = ev::evaluateMesh(top_half, gt, options);
  EXPECT_TRUE(std::isnan(plain.hidden_fraction));
  EXPECT_TRUE(std::isnan(plain.chamfer_gt_to_pred_seen));
  EXPECT_TRUE(std::isnan(plain.chamfer_gt_to_pred_hidden));
  EXPECT_EQ(plain.chamfer, m.chamfer);
  EXPECT_EQ(plain.hausdorff, m.hausdorff);
}

TEST(Metrics, NormalConsistencyOfTheGtSplitsIntoTheSeenAndTheHiddenSurface) {
  // GT: the unit cube seen from above, as above (seen radius r = 0.03 sqrt(3) in its units).
  // Prediction: a wide slab [-1,2]^2 x [0.5,1]. Every GT sample's nearest predicted sample is on
  // the slab's top or bottom face (the slab's sides are 1 away), so the GT's top and bottom faces
  // agree (1) and its side faces are perpendicular (0). Seen: the top face (area 1) and a band r
  // high on each side face: 1 / (1 + 4r). Hidden: the bottom face and the rest of the sides:
  // 1 / (5 - 4r). Only edge samples differ, by the sampling gap.
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh slab = makeBox({-1, -1, 0.5}, {2, 2, 1});
  ev::MetricOptions options;
  options.num_samples = 50000;
  const ev::MeshMetrics m = ev::evaluateMesh(slab, gt, topFaceGrid(0.005), options);
  const double r = 0.03 * std::sqrt(3.0);
  EXPECT_NEAR(m.normal_consistency_gt_to_pred_seen, 1.0 / (1.0 + 4.0 * r), 0.02);
  EXPECT_NEAR(m.normal_consistency_gt_to_pred_hidden, 1.0 / (5.0 - 4.0 * r), 0.01);
  EXPECT_NEAR(m.normal_consistency_gt_to_pred, 2.0 / 6.0, 0.01);
  // The parts make up the GT->pred direction by their shares; NC is the mean of the directions.
  EXPECT_NEAR((1.0 - m.hidden_fraction) * m.normal_consistency_gt_to_pred_seen +
                  m.hidden_fraction * m.normal_consistency_gt_to_pred_hidden,
              m.normal_consistency_gt_to_pred, 1e-9);
  EXPECT_NEAR(0.5 * (m.normal_consistency_pred_to_gt + m.normal_consistency_gt_to_pred), m.normal_consistency, 1e-12);
  const ev::MeshMetrics plain = ev::evaluateMesh(slab, gt, options);
  EXPECT_TRUE(std::isnan(plain.normal_consistency_gt_to_pred_seen));
  EXPECT_TRUE(std::isnan(plain.normal_consistency_gt_to_pred_hidden));
  EXPECT_EQ(plain.normal_consistency_gt_to_pred, m.normal_consistency_gt_to_pred);
}

TEST(Metrics, NoSeenPointsHideEverythingAndAFullScanHidesNothing) {
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {1, 1, 1});
  const paco::SurfaceMesh top_half = makeBox({0, 0, 0.5}, {1, 1, 1});
  const ev::MeshMetrics unseen = ev::evaluateMesh(top_half, gt, std::vector<Eigen::Vector3d>());
  EXPECT_EQ(unseen.hidden_fraction, 1.0);
  EXPECT_TRUE(std::isnan(unseen.chamfer_gt_to_pred_seen));
  EXPECT_NEAR(unseen.chamfer_gt_to_pred_hidden, unseen.chamfer_gt_to_pred, 1e-9);
  // The GT's own dense sample as the scan: every GT point is seen.
  const paco::SurfaceSample scan = paco::sampleSurface(gt, 20000, 7);
  const ev::MeshMetrics seen = ev::evaluateMesh(top_half, gt, scan.points);
  EXPECT_EQ(seen.hidden_fraction, 0.0);
  EXPECT_TRUE(std::isnan(seen.chamfer_gt_to_pred_hidden));
  EXPECT_NEAR(seen.chamfer_gt_to_pred_seen, seen.chamfer_gt_to_pred, 1e-9);
  // A failure box is split the same way: the cube's box is the cube, so it scores as the cube.
  const ev::MeshMetrics failed = ev::evaluateFailure(gt, topFaceGrid(0.005));
  const ev::MeshMetrics cube = ev::evaluateMesh(gt, gt, topFaceGrid(0.005));
  EXPECT_EQ(failed.hidden_fraction, cube.hidden_fraction);
  EXPECT_NEAR(failed.chamfer_gt_to_pred_hidden, cube.chamfer_gt_to_pred_hidden, 0.2);  // the sampling floor
  EXPECT_NEAR(failed.hidden_fraction, (5.0 - 4.0 * 0.03 * std::sqrt(3.0)) / 6.0, 0.02);
}

TEST(Metrics, BadSeenPointsOrRadiusAreErrors) {
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {1, 1, 1});
  std::vector<Eigen::Vector3d> seen = topFaceGrid(0.1);
  seen[3].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(ev::evaluateMesh(gt, gt, seen), paco::InvalidInputError);
  ev::MetricOptions options;
  options.seen_radius = 0.0;
  EXPECT_THROW(ev::evaluateMesh(gt, gt, topFaceGrid(0.1), options), paco::InvalidInputError);
}

TEST(Metrics, EmptyOrInvalidMeshesAreErrors) {
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {1, 1, 1});
  paco::SurfaceMesh empty;
  EXPECT_THROW(ev::evaluateMesh(empty, gt), paco::InvalidInputError);
  EXPECT_THROW(ev::evaluateMesh(gt, empty), paco::InvalidInputError);
  paco::SurfaceMesh bad = gt;
  bad.faces[0][0] = 99;
  EXPECT_THROW(ev::evaluateMesh(bad, gt), paco::InvalidInputError);
}

TEST(FailureBox, IsTheReferenceBoundingBox) {
  // An L-bracket's bounding box is [0,1] x [0,1] x [0,0.6].
  const paco::SurfaceMesh gt = paco::test::makeLBracket(1.0, 0.4, 0.6);
  const paco::SurfaceMesh box = ev::failureBox(gt);
  Eigen::Vector3d lo, hi;
  paco::boundingBox(box, lo, hi);
  EXPECT_TRUE(lo.isApprox(Eigen::Vector3d(0, 0, 0), 1e-12) || lo.norm() < 1e-12);
  EXPECT_TRUE(hi.isApprox(Eigen::Vector3d(1, 1, 0.6), 1e-12));
  EXPECT_TRUE(paco::analyseTopology(box).isClosedManifold());
  EXPECT_NEAR(paco::signedVolume(box), 0.6, 1e-12);

  // The cube variant has diagonal 1 in the normalised frame: edge |gt diagonal| / sqrt(3).
  const paco::SurfaceMesh cube = ev::failureBox(gt, ev::FailureBox::UnitDiagonalCube);
  paco::boundingBox(cube, lo, hi);
  const double edge = std::sqrt(1.0 + 1.0 + 0.36) / std::sqrt(3.0);
  EXPECT_NEAR((hi - lo).x(), edge, 1e-12);
  EXPECT_NEAR((hi - lo).z(), edge, 1e-12);
  EXPECT_NEAR((0.5 * (hi + lo) - Eigen::Vector3d(0.5, 0.5, 0.3)).norm(), 0.0, 1e-12);
}

TEST(FailureBox, AFailedCaseScoresExactlyTheBox) {
  const paco::SurfaceMesh gt = paco::test::makeBossOnSlab();
  const ev::MeshMetrics failed = ev::evaluateFailure(gt);
  const ev::MeshMetrics box = ev::evaluateMesh(ev::failureBox(gt), gt);
  EXPECT_EQ(failed.chamfer, box.chamfer);
  EXPECT_EQ(failed.hausdorff, box.hausdorff);
  EXPECT_EQ(failed.normal_consistency, box.normal_consistency);
  EXPECT_EQ(failed.num_faces, 0u);
  EXPECT_EQ(failed.num_vertices, 0u);
  EXPECT_FALSE(failed.closed);
  // Hand value for HD: the 2 x 2 x 1 slab with the 1 x 1 x 1 boss centred on top has the box
  // [0,2]^2 x [0,2]. The box points farthest from the part are its top corners, e.g. (0,0,2), whose
  // nearest part point is the boss's top corner (0.5,0.5,2): sqrt(0.5) away. Every part point is
  // at most 0.5 from the box. The GT diagonal is sqrt(12), so HD = 100 sqrt(0.5) / sqrt(12) = 20.4.
  EXPECT_NEAR(failed.hausdorff, 100.0 * std::sqrt(0.5) / std::sqrt(12.0), 1.0);
}

TEST(FailureBox, ABoxShapedPartScoresAtTheSamplingFloor) {
  const paco::SurfaceMesh gt = makeBox({0, 0, 0}, {2, 1, 0.5});
  const ev::MeshMetrics failed = ev::evaluateFailure(gt);
  EXPECT_LT(failed.chamfer, 2.0);
  EXPECT_GT(failed.normal_consistency, 0.97);  // the sampling floor, see above
}

TEST(PrimitiveAgreement, KnownPermutationOfPlanesScoresOne) {
  std::vector<paco::Plane> gt;
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, 0, 1),
                                   Eigen::Vector3d(1, 1, 0).normalized(), Eigen::Vector3d(1, 0, 1).normalized()})
    gt.emplace_back(n, -0.3);
  const std::vector<int> permutation = {2, 4, 0, 1, 3};
  std::vector<paco::Plane> predicted;
  for (int j : permutation) predicted.push_back(gt[static_cast<std::size_t>(j)].flipped());  // orientation ignored
  const ev::PrimitiveAgreement a = ev::comparePrimitives(predicted, gt);
  EXPECT_NEAR(a.nc_prim, 1.0, 1e-12);
  EXPECT_EQ(a.reference_of_predicted, permutation);
  EXPECT_EQ(a.unmatched_predicted, 0u);
  EXPECT_EQ(a.unmatched_reference, 0u);
}

TEST(PrimitiveAgreement, UnmatchedPlanesAreCounted) {
  std::vector<paco::Plane> gt = {paco::Plane({1, 0, 0}, 0), paco::Plane({0, 1, 0}, 0), paco::Plane({0, 0, 1}, 0),
                                 paco::Plane({0, 0, 1}, -1)};
  // Two of four GT planes predicted exactly, one tilted by 60 degrees (|cos| = 0.5): (1+1+0.5)/4.
  std::vector<paco::Plane> predicted = {paco::Plane({1, 0, 0}, 0.2), paco::Plane({0, 1, 0}, 0),
                                        paco::Plane({0, std::sin(paco::kPi / 3), std::cos(paco::kPi / 3)}, 0)};
  ev::PrimitiveAgreement a = ev::comparePrimitives(predicted, gt);
  EXPECT_NEAR(a.nc_prim, 2.5 / 4.0, 1e-12);
  EXPECT_EQ(a.unmatched_reference, 1u);
  EXPECT_EQ(a.unmatched_predicted, 0u);
  // Extra predicted planes do not lower NC_prim but are reported.
  predicted.push_back(paco::Plane({0, 0, 1}, -1));
  predicted.push_back(paco::Plane({1, 1, 1}, 0));
  a = ev::comparePrimitives(predicted, gt);
  // Now x, y and z(-1) match exactly; the other z plane takes the better of the tilted plane
  // (|cos| 0.5) and (1,1,1) (|cos| 1/sqrt(3)); the tilted one is left over.
  EXPECT_NEAR(a.nc_prim, (3.0 + 1.0 / std::sqrt(3.0)) / 4.0, 1e-12);
  EXPECT_EQ(a.unmatched_predicted, 1u);
  EXPECT_EQ(a.unmatched_reference, 0u);
  EXPECT_EQ(ev::comparePrimitives({}, gt).nc_prim, 0.0);
  EXPECT_TRUE(std::isnan(ev::comparePrimitives(predicted, {}).nc_prim));
}
