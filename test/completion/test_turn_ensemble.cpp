#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/completion/turn_ensemble.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>

namespace paco {
namespace {

using paco::kPi;

// A k x k grid of points on the plane, centred at the plane's point nearest to `centre`, with
// the plane's normal; the grid spans `size`.
PlanarPrimitive grid(const Plane& plane, const Eigen::Vector3d& centre, double size, int k, float confidence) {
  PlanarPrimitive primitive;
  primitive.plane = plane;
  primitive.confidence = confidence;
  const Eigen::Vector3d u = plane.normal.unitOrthogonal(), v = plane.normal.cross(u);
  const Eigen::Vector3d origin = plane.project(centre);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      pcl::PointNormal p;
      p.getVector3fMap() =
          (origin + size * ((i + 0.5) / k - 0.5) * u + size * ((j + 0.5) / k - 0.5) * v).cast<float>();
      p.getNormalVector3fMap() = plane.normal.cast<float>();
      primitive.points.push_back(p);
    }
  return primitive;
}

Plane tilted(double degrees, double height) {  // z = height, normal +z turned about y
  const double a = paco::degreesToRadians(degrees);
  return Plane::fromPointAndNormal({0.5, 0.5, height}, {std::sin(a), 0.0, std::cos(a)});
}

TEST(EnsembleTurns, AreTheAxisRotationsIdentityAndHalfTurnsFirst) {
  const auto turns = ensembleTurns(kMaxEnsembleTurns);
  ASSERT_EQ(turns.size(), 24u);
  EXPECT_TRUE(turns[0].isIdentity(0.0));
  for (std::size_t t = 0; t < turns.size(); ++t) {
    const Eigen::Matrix3d& r = turns[t];
    EXPECT_TRUE((r * r.transpose()).isIdentity(1e-12)) << t;
    EXPECT_NEAR(r.determinant(), 1.0, 1e-12) << t;
    // Every axis goes to an axis: one entry of +-1 per row.
    EXPECT_DOUBLE_EQ(r.cwiseAbs().sum(), 3.0) << t;
    // Half turns about an axis keep every axis's extent: diagonal matrices.
    if (t >= 1 && t <= 3) {
      EXPECT_TRUE(r.cwiseAbs().isIdentity(0.0)) << t;
      EXPECT_NEAR(Eigen::AngleAxisd(r).angle(), kPi, 1e-12) << t;
    }
    for (std::size_t s = 0; s < t; ++s) EXPECT_FALSE(r.isApprox(turns[s])) << t << " repeats " << s;
  }
  // A shorter list is the start of the full one.
  const auto four = ensembleTurns(4);
  ASSERT_EQ(four.size(), 4u);
  for (std::size_t t = 0; t < 4; ++t) EXPECT_TRUE(four[t].isApprox(turns[t]));
  EXPECT_THROW(ensembleTurns(0), InvalidInputError);
  EXPECT_THROW(ensembleTurns(kMaxEnsembleTurns + 1), InvalidInputError);
}

TEST(MergeTurnPredictions, AFaceMostTurnsPredictIsKeptWithTheMeanConfidenceAndPlane) {
  // Turn 1: the top z = 1 (confidence 0.9) and a guess x = 1 (0.8). Turn 2: the top 2 degrees
  // tilted and 0.005 higher (0.7), and a guess y = 1 (0.9).
  const Plane top = tilted(0.0, 1.0), top2 = tilted(2.0, 1.005);
  std::vector<std::vector<PlanarPrimitive>> runs(2);
  runs[0].push_back(grid(top, {0.5, 0.5, 1}, 1.0, 10, 0.9f));
  runs[0].push_back(grid(Plane::fromPointAndNormal({1, 0, 0}, {1, 0, 0}), {1, 0.5, 0.5}, 1.0, 6, 0.8f));
  runs[1].push_back(grid(top2, {0.5, 0.5, 1.005}, 1.0, 8, 0.7f));
  runs[1].push_back(grid(Plane::fromPointAndNormal({0, 1, 0}, {0, 1, 0}), {0.5, 1, 0.5}, 1.0, 6, 0.9f));

  TurnEnsembleOptions options;
  options.threshold = 0.5;
  const auto merged = mergeTurnPredictions(runs, 1.0, options);
  // The two guesses score 0.8 / 2 and 0.9 / 2, below 0.5; the top (0.9 + 0.7) / 2 = 0.8.
  ASSERT_EQ(merged.size(), 1u);
  EXPECT_NEAR(merged[0].confidence, 0.8, 1e-6);
  // The confidence-weighted mean of the two planes.
  const Eigen::Vector3d normal = (0.9 * top.normal + 0.7 * top2.normal).normalized();
  const double offset = (0.9 * top.offset + 0.7 * top2.offset) / (0.9 + 0.7) /
                        ((0.9 * top.normal + 0.7 * top2.normal) / 1.6).norm();
  EXPECT_NEAR(merged[0].plane.normal.dot(normal), 1.0, 1e-9);
  EXPECT_NEAR(merged[0].plane.offset, offset, 1e-9);
  // The most confident member's count (100) from both members' 164 points, all on the plane.
  ASSERT_EQ(merged[0].points.size(), 100u);
  int from_second = 0;
  for (const auto& p : merged[0].points) {
    EXPECT_LT(std::abs(merged[0].plane.signedDistance(p.getVector3fMap().cast<double>())), 1e-5);
    EXPECT_NEAR(p.getNormalVector3fMap().cast<double>().dot(merged[0].plane.normal), 1.0, 1e-6);
    // The second member's grid is 8 x 8: its points sit at odd multiples of 1/16.
    if (std::abs(std::fmod(p.x * 16.0 + 32.0, 2.0) - 1.0) < 0.05) ++from_second;
  }
  EXPECT_GT(from_second, 0);  // the points come from both turns

  // A lower threshold keeps the guesses too, sorted by confidence.
  options.threshold = 0.3;
  const auto all = mergeTurnPredictions(runs, 1.0, options);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_NEAR(all[0].confidence, 0.8, 1e-6);
  EXPECT_NEAR(all[1].confidence, 0.45, 1e-6);
  EXPECT_NEAR(all[1].plane.normal.y(), 1.0, 1e-9);
  EXPECT_NEAR(all[2].confidence, 0.4, 1e-6);
  EXPECT_NEAR(all[2].plane.normal.x(), 1.0, 1e-9);
}

TEST(MergeTurnPredictions, FarTiltedOrOppositePlanesAndRepeatsOfOneTurnDoNotAddVotes) {
  TurnEnsembleOptions options;
  options.threshold = 0.0;
  const Plane top = tilted(0.0, 1.0);
  std::vector<std::vector<PlanarPrimitive>> runs(2);
  runs[0].push_back(grid(top, {0.5, 0.5, 1}, 1.0, 5, 0.9f));
  runs[0].push_back(grid(tilted(3.0, 1.0), {0.5, 0.5, 1}, 1.0, 5, 0.6f));  // a repeat within turn 1
  runs[1].push_back(grid(tilted(15.0, 1.0), {0.5, 0.5, 1}, 1.0, 5, 0.8f));  // beyond 10 degrees
  runs[1].push_back(grid(tilted(0.0, 1.05), {0.5, 0.5, 1.05}, 1.0, 5, 0.8f));  // 0.05 away, diagonal 1
  runs[1].push_back(grid(top.flipped(), {0.5, 0.5, 1}, 1.0, 5, 0.8f));  // facing the other way
  const auto merged = mergeTurnPredictions(runs, 1.0, options);
  ASSERT_EQ(merged.size(), 4u);
  // Turn 1's two members count once, at its best: (0.9 + 0) / 2; the others 0.8 / 2 each.
  EXPECT_NEAR(merged.front().confidence, 0.45, 1e-6);
  EXPECT_NEAR(merged.front().plane.normal.z(), 1.0, 1e-3);
  for (std::size_t i = 1; i < merged.size(); ++i) EXPECT_NEAR(merged[i].confidence, 0.4, 1e-6);
  // With a diagonal of 10 the 0.05 gap is within 2 % of it: that plane joins the top.
  const auto wide = mergeTurnPredictions(runs, 10.0, options);
  EXPECT_EQ(wide.size(), 3u);
  EXPECT_NEAR(wide.front().confidence, (0.9 + 0.8) / 2, 1e-6);
}

TEST(MergeTurnPredictions, RejectsBadInput) {
  const std::vector<std::vector<PlanarPrimitive>> one_run(1);
  TurnEnsembleOptions options;
  EXPECT_THROW(mergeTurnPredictions({}, 1.0, options), InvalidInputError);
  EXPECT_THROW(mergeTurnPredictions(one_run, 0.0, options), InvalidInputError);
  EXPECT_THROW(mergeTurnPredictions(one_run, std::nan(""), options), InvalidInputError);
  options.max_angle_degrees = 0.0;
  EXPECT_THROW(mergeTurnPredictions(one_run, 1.0, options), InvalidInputError);
  options = {};
  options.threshold = 1.5;
  EXPECT_THROW(mergeTurnPredictions(one_run, 1.0, options), InvalidInputError);
  options = {};
  EXPECT_TRUE(mergeTurnPredictions(one_run, 1.0, options).empty());
}

}  // namespace
}  // namespace paco
