#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/completion/observed_fusion.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace paco {
namespace {

// A square patch of side `size` on the plane, centred at the plane's point nearest to `centre`,
// as a k x k grid of points with the plane's normal.
PlanarPrimitive patch(const Plane& plane, const Eigen::Vector3d& centre, double size, int k, float confidence) {
  PlanarPrimitive primitive;
  primitive.plane = plane;
  primitive.confidence = confidence;
  const Eigen::Vector3d n = plane.normal;
  const Eigen::Vector3d u = n.unitOrthogonal();
  const Eigen::Vector3d v = n.cross(u);
  const Eigen::Vector3d origin = plane.project(centre);
  for (int i = 0; i < k; ++i)
    for (int j = 0; j < k; ++j) {
      const Eigen::Vector3d q = origin + size * ((i + 0.5) / k - 0.5) * u + size * ((j + 0.5) / k - 0.5) * v;
      pcl::PointNormal p;
      p.x = float(q.x()), p.y = float(q.y()), p.z = float(q.z());
      p.normal_x = float(n.x()), p.normal_y = float(n.y()), p.normal_z = float(n.z());
      primitive.points.push_back(p);
    }
  return primitive;
}

// Fusion alone, without the box fill, the thinning of unseen primitives and the check of seen
// faces' predicted points (which these tests of matching would otherwise see).
ObservedFusionOptions fusionOnly() {
  ObservedFusionOptions options;
  options.fill_spacing = 0.0;
  options.unseen_point_fraction = 1.0;
  options.contradiction_radius = 0.0;
  return options;
}

// Seen: the bottom z = 0 (a 10 x 10 grid, x and y in 0.05..0.95) and the side x = 0 (8 x 8, y
// and z in 0.0625..0.9375).
std::vector<PlanarPrimitive> seenBottomAndSide() {
  return {patch(Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1}), {0.5, 0.5, 0}, 1.0, 10, 1.0f),
          patch(Plane::fromPointAndNormal({0, 0, 0}, {-1, 0, 0}), {0, 0.5, 0.5}, 1.0, 8, 1.0f)};
}

// The defaults with a coarse box fill: grid points 0.05 of the diagonal apart, each kept where no
// fused point lies within 0.05 of the diagonal (0.08 on seenBottomAndSide()'s box).
ObservedFusionOptions coarseFill() {
  ObservedFusionOptions options;
  options.fill_spacing = 0.05;
  options.fill_empty_radius = 0.05;
  return options;
}

double maxDistanceToPlane(const PlanarPrimitive& primitive, const Plane& plane) {
  double largest = 0.0;
  for (const auto& p : primitive.points) largest = std::max(largest, std::abs(plane.signedDistance({p.x, p.y, p.z})));
  return largest;
}

TEST(ObservedFusion, APredictedPlaneTakesTheObservedPlaneAndPoints) {
  // Observed: the top z = 1 of a unit-ish part, its normal pointing down (segmenters do not
  // orient). Predicted: the same face 3° tilted and 0.01 too high, oriented outward (+z).
  const Plane observed_plane = Plane::fromPointAndNormal({0, 0, 1}, {0, 0, -1});
  const double tilt = paco::degreesToRadians(3.0);
  const Plane predicted_plane =
      Plane::fromPointAndNormal({0, 0, 1.01}, {std::sin(tilt), 0.0, std::cos(tilt)});
  const std::vector<PlanarPrimitive> observed = {patch(observed_plane, {0, 0, 1}, 1.0, 10, 1.0f)};
  std::vector<PlanarPrimitive> completed = {patch(predicted_plane, {0, 0, 1}, 1.0, 8, 0.9f)};

  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, fusionOnly(), &report);
  ASSERT_EQ(fused.size(), 1u);
  EXPECT_EQ(report.snapped, 1u);
  EXPECT_EQ(report.added, 0u);
  // The observed plane, with the predicted (outward) orientation.
  EXPECT_NEAR(fused[0].plane.normal.z(), 1.0, 1e-12);
  EXPECT_NEAR(fused[0].plane.signedDistance({0, 0, 1}), 0.0, 1e-12);
  // 64 predicted points moved onto it, plus the 100 observed ones.
  EXPECT_EQ(fused[0].points.size(), 164u);
  EXPECT_LT(maxDistanceToPlane(fused[0], fused[0].plane), 1e-6);
  EXPECT_FLOAT_EQ(fused[0].confidence, 1.0f);  // a seen face, no longer a guess
}

TEST(ObservedFusion, UnseenPredictionsStayAndUnmatchedObservationsAreAdded) {
  // Observed: x = 0 (seen). Predicted: only x = 1 (the unseen opposite face).
  const Plane seen = Plane::fromPointAndNormal({0, 0, 0}, {-1, 0, 0});
  const Plane hidden = Plane::fromPointAndNormal({1, 0, 0}, {1, 0, 0});
  const std::vector<PlanarPrimitive> observed = {patch(seen, {0, 0.5, 0.5}, 1.0, 10, 1.0f)};
  const std::vector<PlanarPrimitive> completed = {patch(hidden, {1, 0.5, 0.5}, 1.0, 8, 0.8f)};
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, fusionOnly(), &report);
  ASSERT_EQ(fused.size(), 2u);
  EXPECT_EQ(report.snapped, 0u);
  EXPECT_EQ(report.added, 1u);
  EXPECT_NEAR(fused[0].plane.signedDistance({1, 0, 0}), 0.0, 1e-12);  // unchanged
  EXPECT_EQ(fused[0].points.size(), 64u);
  EXPECT_FLOAT_EQ(fused[0].confidence, 0.8f);
  EXPECT_NEAR(fused[1].plane.signedDistance({0, 0, 0}), 0.0, 1e-12);
  EXPECT_EQ(fused[1].points.size(), 100u);
  EXPECT_FLOAT_EQ(fused[1].confidence, 1.0f);
}

TEST(ObservedFusion, ASplitObservedFaceJoinsOnePrimitiveAndTinySegmentsAreIgnored) {
  const Plane face = Plane::fromPointAndNormal({0, 0, 0}, {0, 1, 0});
  // Two observed halves of y = 0 (over-segmentation), one 3-point crumb, and a prediction.
  std::vector<PlanarPrimitive> observed = {patch(face, {-0.5, 0, 0}, 0.9, 6, 1.0f),
                                           patch(face, {0.5, 0, 0}, 0.9, 8, 1.0f)};
  PlanarPrimitive crumb = patch(Plane::fromPointAndNormal({0, 0, 5}, {0, 0, 1}), {0, 0, 5}, 0.1, 1, 1.0f);
  crumb.points.push_back(crumb.points[0]);
  crumb.points.push_back(crumb.points[0]);
  observed.push_back(crumb);
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0.005, 0}, {0, 1, 0}), {0, 0, 0}, 2.0, 5, 0.95f)};
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, fusionOnly(), &report);
  ASSERT_EQ(fused.size(), 1u);
  EXPECT_EQ(report.snapped, 1u);  // the larger half (64 points) sets the plane
  EXPECT_EQ(report.joined, 1u);   // the other half (36) adds its points
  EXPECT_EQ(report.ignored, 1u);
  EXPECT_EQ(fused[0].points.size(), 25u + 64u + 36u);
  EXPECT_NEAR(fused[0].plane.signedDistance({0, 0, 0}), 0.0, 1e-12);
}

TEST(ObservedFusion, WithASmallJoinDistanceAParallelSeenFaceOffTheSnappedPlaneKeepsItsOwnPlane) {
  // Seen: a floor y = 0 (81 points) and a step y = 0.03 beside it (36 points), both within the
  // matching distance (0.02 of the diagonal, about 0.05 here) of the one prediction y = 0.01.
  // The floor takes the prediction; the step is 0.03 off that plane, beyond join_distance
  // set to 0.005 (about 0.012 here), so it stays a face of its own instead of being flattened
  // into the floor. With the default join_distance, the matching distance, it joins the floor.
  const Plane floor = Plane::fromPointAndNormal({0, 0, 0}, {0, 1, 0});
  const Plane step = Plane::fromPointAndNormal({0, 0.03, 0}, {0, 1, 0});
  const std::vector<PlanarPrimitive> observed = {patch(floor, {-0.6, 0, 0}, 1.0, 9, 1.0f),
                                                 patch(step, {0.6, 0.03, 0}, 1.0, 6, 1.0f)};
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0.01, 0}, {0, 1, 0}), {0, 0.01, 0}, 2.0, 5, 0.95f)};
  ObservedFusionOptions apart = fusionOnly();
  apart.join_distance = 0.005;
  ObservedFusionReport report;
  auto fused = fuseWithObserved(completed, observed, apart, &report);
  ASSERT_EQ(fused.size(), 2u);
  EXPECT_EQ(report.snapped, 1u);
  EXPECT_EQ(report.joined, 0u);
  EXPECT_EQ(report.added, 1u);
  EXPECT_NEAR(fused[0].plane.signedDistance({0, 0, 0}), 0.0, 1e-12);
  EXPECT_EQ(fused[0].points.size(), 25u + 81u);
  EXPECT_NEAR(fused[1].plane.signedDistance({0, 0.03, 0}), 0.0, 1e-12);
  EXPECT_EQ(fused[1].points.size(), 36u);
  EXPECT_FLOAT_EQ(fused[1].confidence, 1.0f);

  ObservedFusionOptions before = fusionOnly();
  EXPECT_EQ(before.join_distance, before.max_distance);
  fused = fuseWithObserved(completed, observed, before, &report);
  ASSERT_EQ(fused.size(), 1u);
  EXPECT_EQ(report.joined, 1u);
  EXPECT_EQ(fused[0].points.size(), 25u + 81u + 36u);
  EXPECT_NE(describe(report).find("1 seen segments joined a larger seen face"), std::string::npos) << describe(report);

  for (double bad : {-0.01, std::nan(""), std::numeric_limits<double>::infinity()}) {
    before.join_distance = bad;
    EXPECT_THROW(fuseWithObserved(completed, observed, before), InvalidInputError);
  }
}

TEST(ObservedFusion, DuplicatePredictionsOfASeenFaceAreAbsorbed) {
  // Two predictions of the seen face z = 0 (one 2° and 0.01 off, one 4° and 0.015 off) and one of
  // the unseen face z = 1: the seen face ends up once, with the points of both duplicates.
  const Plane seen = Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1});
  const double a2 = paco::degreesToRadians(2.0), a4 = paco::degreesToRadians(4.0);
  const std::vector<PlanarPrimitive> observed = {patch(seen, {0, 0, 0}, 1.0, 10, 1.0f)};
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0, -0.01}, {std::sin(a2), 0, -std::cos(a2)}), {0, 0, 0}, 1.0, 4, 0.9f),
      patch(Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1}), {0, 0, 1}, 1.0, 4, 0.85f),
      patch(Plane::fromPointAndNormal({0, 0, 0.015}, {0, std::sin(a4), -std::cos(a4)}), {0, 0, 0}, 1.0, 5, 0.8f)};
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, fusionOnly(), &report);
  ASSERT_EQ(fused.size(), 2u);
  EXPECT_EQ(report.snapped, 1u);
  EXPECT_EQ(report.absorbed, 1u);
  EXPECT_NEAR(fused[0].plane.normal.z(), -1.0, 1e-12);
  EXPECT_EQ(fused[0].points.size(), 16u + 100u + 25u);
  EXPECT_LT(maxDistanceToPlane(fused[0], seen), 1e-6);
  EXPECT_NEAR(fused[1].plane.signedDistance({0, 0, 1}), 0.0, 1e-12);  // the unseen face, unchanged
}

TEST(ObservedFusion, TolerancesDecideAndBadOptionsAreRejected) {
  const Plane observed_plane = Plane::fromPointAndNormal({0, 0, 0}, {0, 0, 1});
  const std::vector<PlanarPrimitive> observed = {patch(observed_plane, {0, 0, 0}, 1.0, 10, 1.0f)};
  // 15° away: beyond the default 10°, so the observation is added instead of snapped.
  const double tilt = paco::degreesToRadians(15.0);
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0, 0}, {std::sin(tilt), 0, std::cos(tilt)}), {0, 0, 0}, 1.0, 4, 0.9f)};
  ObservedFusionReport report;
  EXPECT_EQ(fuseWithObserved(completed, observed, fusionOnly(), &report).size(), 2u);
  EXPECT_EQ(report.added, 1u);
  ObservedFusionOptions wide = fusionOnly();
  wide.max_angle_degrees = 20.0;
  wide.max_distance = 0.1;
  EXPECT_EQ(fuseWithObserved(completed, observed, wide, &report).size(), 1u);
  EXPECT_EQ(report.snapped, 1u);
  ObservedFusionOptions bad;
  bad.max_distance = -1.0;
  EXPECT_THROW(fuseWithObserved(completed, observed, bad), InvalidInputError);
  bad = ObservedFusionOptions{};
  bad.max_angle_degrees = std::nan("");
  EXPECT_THROW(fuseWithObserved(completed, observed, bad), InvalidInputError);
  for (const double margin : {-0.1, std::nan("")}) {
    bad = ObservedFusionOptions{};
    bad.tilt_margin = margin;
    EXPECT_THROW(fuseWithObserved(completed, observed, bad), InvalidInputError);
  }
  // Nothing observed: the completion is returned as it is.
  EXPECT_EQ(fuseWithObserved(completed, {}).size(), 1u);  // (nor a box to fill)
}

TEST(ObservedFusion, ANoisySeenFaceOffABoxAxisByLessThanItsFitErrorIsSquaredToIt) {
  // seenBottomAndSide() and a strip of the far side y = 1, 0.1 tall (z in 0.45..0.55) and 0.9
  // long, seen with 100 points on a plane tilted 3 degrees about x. The network guessed the side
  // square. Noisy, the strip's points lie 0.02 off its plane in turn, and the standard error of its
  // fitted normal is about 4 degrees: the tilt is noise, and the face is squared to the box axis
  // y. Clean, the same 3 degrees are the part's own (a draft angle) and stay.
  const double tilt = 3.0 * paco::kPi / 180.0;
  const Eigen::Vector3d tilted(0, std::cos(tilt), std::sin(tilt));
  const auto strip = [&](double scatter) {
    PlanarPrimitive face;
    face.plane = Plane::fromPointAndNormal({0.5, 1.0, 0.5}, tilted);
    face.confidence = 1.0f;
    for (int i = 0; i < 20; ++i)
      for (int j = 0; j < 5; ++j) {
        const Eigen::Vector3d on = face.plane.project({0.05 + 0.9 * (i + 0.5) / 20, 1.0, 0.45 + 0.1 * (j + 0.5) / 5});
        const Eigen::Vector3d q = on + ((i + j) % 2 ? scatter : -scatter) * tilted;
        pcl::PointNormal p;
        p.getVector3fMap() = q.cast<float>();
        p.getNormalVector3fMap() = tilted.cast<float>();
        face.points.push_back(p);
      }
    return face;
  };
  const std::vector<PlanarPrimitive> guess = {
      patch(Plane::fromPointAndNormal({0.5, 1.0, 0.5}, {0, 1, 0}), {0.5, 1.0, 0.5}, 1.0, 6, 0.9f)};
  ObservedFusionReport report;

  std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  observed.push_back(strip(0.02));
  auto fused = fuseWithObserved(guess, observed, fusionOnly(), &report);
  ASSERT_EQ(report.snapped, 1u);
  EXPECT_EQ(report.squared, 1u);  // the strip only: the bottom and the side are square already
  EXPECT_NE(describe(report).find("1 seen faces squared to the box's axes (off them by less than their fit's error)"),
            std::string::npos)
      << describe(report);
  EXPECT_TRUE(fused[0].plane.normal.isApprox(Eigen::Vector3d(0, 1, 0), 1e-9)) << fused[0].plane.normal.transpose();
  EXPECT_NEAR(fused[0].plane.signedDistance({0.5, 1.0, 0.5}), 0.0, 1e-6);  // through the strip's centroid
  EXPECT_LT(maxDistanceToPlane(fused[0], fused[0].plane), 1e-6);  // seen and predicted points on it

  observed.back() = strip(0.0);
  fused = fuseWithObserved(guess, observed, fusionOnly(), &report);
  EXPECT_EQ(report.squared, 0u);
  EXPECT_NEAR(fused[0].plane.normal.normalized().z(), std::sin(tilt), 1e-6);
}

TEST(ObservedFusion, UnseenPlanesNearASeenDirectionAreTurnedParallelToIt) {
  // Seen: the bottom z = 0 and the side x = 0 of a unit part. Predicted, unseen: the top, 4° off
  // the seen bottom's direction, the far side y = 1, 6° off the third dominant axis (no seen
  // face has it), and a 45° chamfer that matches no seen direction.
  const double deg = paco::kPi / 180.0;
  const std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0.5, 0.5, 1.0}, {std::sin(4 * deg), 0, std::cos(4 * deg)}), {0.5, 0.5, 1}, 1.0, 6, 0.9f),
      patch(Plane::fromPointAndNormal({0.5, 1.0, 0.5}, {0, std::cos(6 * deg), std::sin(6 * deg)}), {0.5, 1, 0.5}, 1.0, 6, 0.9f),
      patch(Plane::fromPointAndNormal({1, 1, 1}, Eigen::Vector3d(1, 0, 1).normalized()), {1, 0.5, 1}, 0.4, 4, 0.85f)};
  ObservedFusionReport report;
  const auto unchanged = fuseWithObserved(completed, observed, fusionOnly(), &report);  // off by default
  EXPECT_EQ(report.aligned, 0u);
  EXPECT_NEAR(unchanged[0].plane.normal.z(), std::cos(4 * deg), 1e-12);

  ObservedFusionOptions options = fusionOnly();
  options.align_unseen_degrees = 10.0;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 5u);  // 3 completed + 2 seen faces added
  EXPECT_EQ(report.aligned, 2u);
  EXPECT_NE(describe(report).find("2 unseen aligned"), std::string::npos) << describe(report);
  // The top: exactly +z (its outward side kept), through its points' centroid, points on it.
  EXPECT_TRUE(fused[0].plane.normal.isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
  EXPECT_NEAR(fused[0].plane.signedDistance({0.5, 0.5, 1.0}), 0.0, 1e-6);
  EXPECT_LT(maxDistanceToPlane(fused[0], fused[0].plane), 1e-6);
  // The far side: exactly +y, the axis the two seen faces imply.
  EXPECT_TRUE(fused[1].plane.normal.isApprox(Eigen::Vector3d(0, 1, 0), 1e-12));
  EXPECT_NEAR(fused[1].plane.signedDistance({0.5, 1.0, 0.5}), 0.0, 1e-6);
  // The chamfer is 45° from everything seen: left alone.
  EXPECT_TRUE(fused[2].plane.normal.isApprox(Eigen::Vector3d(1, 0, 1).normalized(), 1e-12));
  options.align_unseen_degrees = -1.0;
  EXPECT_THROW(fuseWithObserved(completed, observed, options), InvalidInputError);
}

TEST(ObservedFusion, PredictionsFarOutsideTheSeenBoxAreClipped) {
  // Seen: the bottom z = 0 (x, y in 0.05..0.95) and the side x = 0 (y, z in 0.0625..0.9375).
  // Their box, grown by 0.1 of its diagonal (1.61): x in [-0.16, 1.11], y in [-0.11, 1.11],
  // z in [-0.16, 1.10].
  const std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  // Predicted: the seen bottom, too wide (a 10 x 10 grid at -0.4, -0.2, ..., 1.4: 6 x 6 inside);
  // the unseen top, a little too wide (14 x 14 at -0.15, -0.05, ..., 1.15: 13 x 12 inside); and
  // a face at x = 2.5, far outside.
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1}), {0.5, 0.5, 0}, 2.0, 10, 0.9f),
      patch(Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1}), {0.5, 0.5, 1}, 1.4, 14, 0.9f),
      patch(Plane::fromPointAndNormal({2.5, 0, 0}, {1, 0, 0}), {2.5, 0.5, 0.5}, 1.0, 6, 0.85f)};
  ObservedFusionReport report;
  EXPECT_EQ(fuseWithObserved(completed, observed, fusionOnly(), &report).size(), 4u);  // off by default
  EXPECT_EQ(report.clipped_points, 0u);

  ObservedFusionOptions options = fusionOnly();
  options.clip_margin = 0.1;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 3u);  // the far face is gone; the seen side is added
  EXPECT_EQ(report.clipped_points, 64u + 40u + 36u);
  EXPECT_EQ(report.clipped, 1u);
  EXPECT_NE(describe(report).find("140 points outside the seen box dropped (1 unseen"), std::string::npos)
      << describe(report);
  // A seen face loses its outside points but stays, whatever it lost.
  EXPECT_EQ(fused[0].points.size(), 36u + 100u);
  EXPECT_NEAR(fused[1].plane.signedDistance({0, 0, 1}), 0.0, 1e-12);
  EXPECT_EQ(fused[1].points.size(), 13u * 12u);
  EXPECT_EQ(fused[2].points.size(), 64u);
  for (double bad : {-0.1, std::nan("")}) {
    options.clip_margin = bad;
    EXPECT_THROW(fuseWithObserved(completed, observed, options), InvalidInputError);
  }
}

TEST(ObservedFusion, TheUncoveredFacesOfTheSeenBoxAreFilled) {
  // Seen: the bottom z = 0 (x, y in 0.05..0.95) and the side x = 0 (y, z in 0.0625..0.9375); box
  // x in [0, 0.95], y in [0.05, 0.95], z in [0, 0.9375], diagonal 1.61. Predicted: the top,
  // covering the box's top face. Left uncovered: the faces x = 0.95, y = 0.05 and y = 0.95.
  const std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0, 0.9375}, {0, 0, 1}), {0.5, 0.5, 0.9375}, 1.0, 10, 0.9f)};
  ObservedFusionReport report;
  EXPECT_EQ(fuseWithObserved(completed, observed, fusionOnly(), &report).size(), 3u);
  EXPECT_EQ(report.filled_points, 0u);
  EXPECT_EQ(ObservedFusionOptions{}.fill_spacing, 0.02);  // on by default

  ObservedFusionOptions options = coarseFill();
  options.unseen_point_fraction = 1.0;  // the predicted top keeps all its points
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  EXPECT_EQ(report.filled_faces, 3u);
  ASSERT_EQ(fused.size(), 6u);
  EXPECT_EQ(fused[0].points.size(), 100u);  // the predicted top covered its face: nothing added
  EXPECT_NE(describe(report).find("3 new box faces"), std::string::npos) << describe(report);
  const Eigen::Vector3d expected_normals[] = {{1, 0, 0}, {0, -1, 0}, {0, 1, 0}};
  const double expected_offsets[] = {0.95, 0.05, 0.95};
  std::size_t new_points = 0;
  for (int f = 0; f < 3; ++f) {
    const PlanarPrimitive& face = fused[3 + f];
    EXPECT_TRUE(face.plane.normal.isApprox(expected_normals[f], 1e-9)) << face.plane.normal.transpose();
    EXPECT_NEAR(face.plane.signedDistance(expected_offsets[f] * expected_normals[f].cwiseAbs()), 0.0, 1e-6);
    EXPECT_FLOAT_EQ(face.confidence, 0.99f);  // above the network's guesses, below a seen face
    // A 0.95 x 0.9375 face at 0.08 spacing holds about 13 x 13 points, less the rows near seen ones.
    EXPECT_GT(face.points.size(), 100u);
    new_points += face.points.size();
    for (const auto& p : face.points) {
      EXPECT_LT(std::abs(face.plane.signedDistance({p.x, p.y, p.z})), 1e-6);
      // Off the box's edges: there PolyFit's candidate faces meet, and rounding would decide
      // which of them counts the point (half a step, 0.04, from the other faces of the box).
      const Eigen::Vector3d box_lo(0, 0.05, 0), box_hi(0.95, 0.95, 0.9375);
      for (int axis = 0; axis < 3; ++axis) {
        if (std::abs(face.plane.normal[axis]) > 0.5) continue;
        EXPECT_GT(std::min(p.getVector3fMap()[axis] - box_lo[axis], box_hi[axis] - p.getVector3fMap()[axis]), 0.03)
            << "a point on an edge of the box: " << p.getVector3fMap().transpose();
      }
      for (const auto& seen : observed)
        for (const auto& q : seen.points)
          ASSERT_GT((Eigen::Vector3d(p.x, p.y, p.z) - Eigen::Vector3d(q.x, q.y, q.z)).norm(), 0.05 * 1.6);
    }
  }
  // Whatever else was filled (a few points at the seen faces' edges) joined the seen faces.
  EXPECT_EQ(report.filled_points, new_points + (fused[1].points.size() - 100u) + (fused[2].points.size() - 64u));
  for (double bad : {-0.1, 1e-5}) {  // negative; so fine the grid would hold billions of points
    options.fill_spacing = bad;
    EXPECT_THROW(fuseWithObserved(completed, observed, options), InvalidInputError);
  }
}

TEST(ObservedFusion, TheRimOfAThinPlateIsFilled) {
  // A plate 1 x 1 x 0.04 seen on both sides (20 x 20 grids; diagonal 1.415): its four rims are
  // 0.04 wide, narrower than twice the fill's default empty radius (0.05 of the diagonal, 0.071),
  // so the top's and bottom's points alone would cover them, and with no rim the assemblers
  // cannot close the plate. Each rim must become a box face with points in its middle.
  const std::vector<PlanarPrimitive> observed = {
      patch(Plane::fromPointAndNormal({0, 0, 0.04}, {0, 0, 1}), {0.5, 0.5, 0.04}, 1.0, 20, 1.0f),
      patch(Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1}), {0.5, 0.5, 0}, 1.0, 20, 1.0f)};
  ObservedFusionReport report;
  const auto fused = fuseWithObserved({}, observed, ObservedFusionOptions{}, &report);
  ASSERT_EQ(fused.size(), 6u) << describe(report);
  EXPECT_EQ(report.filled_faces, 4u);
  const Eigen::Vector3d rim_normals[] = {{1, 0, 0}, {0, 1, 0}};
  for (std::size_t f = 2; f < 6; ++f) {
    const PlanarPrimitive& rim = fused[f];
    EXPECT_TRUE(rim.plane.normal.cwiseAbs().isApprox(rim_normals[0], 1e-9) ||
                rim.plane.normal.cwiseAbs().isApprox(rim_normals[1], 1e-9))
        << rim.plane.normal.transpose();
    EXPECT_GE(rim.points.size(), 10u);  // the assemblers drop a primitive with fewer
    bool middle = false;
    for (const auto& p : rim.points) middle = middle || std::abs(p.z - 0.02f) < 0.01f;
    EXPECT_TRUE(middle) << "no point in the middle half of rim " << f;
  }
  // A flat scan has no rim to fill: its box is no thicker than the fusion's plane tolerance
  // (max_distance, 0.02 of the diagonal), and nothing is added.
  ObservedFusionReport flat;
  EXPECT_EQ(fuseWithObserved({}, {observed[1]}, ObservedFusionOptions{}, &flat).size(), 1u);
  EXPECT_EQ(flat.filled_points, 0u) << describe(flat);
}

// A rectangle on the plane through `corner` spanned by `a` and `b`, as an na x nb grid of points
// (cell centres) with the given outward normal.
PlanarPrimitive rectangle(const Eigen::Vector3d& corner, const Eigen::Vector3d& a, const Eigen::Vector3d& b, int na,
                          int nb, const Eigen::Vector3d& normal) {
  PlanarPrimitive primitive;
  primitive.plane = Plane::fromPointAndNormal(corner, normal);
  primitive.confidence = 1.0f;
  for (int i = 0; i < na; ++i)
    for (int j = 0; j < nb; ++j) {
      const Eigen::Vector3d q = corner + (i + 0.5) / na * a + (j + 0.5) / nb * b;
      pcl::PointNormal p;
      p.getVector3fMap() = q.cast<float>();
      p.getNormalVector3fMap() = normal.cast<float>();
      primitive.points.push_back(p);
    }
  return primitive;
}

TEST(ObservedFusion, TheEndsOfAProfileSeenOnlyFromItsSidesAreClosedOverTheProfile) {
  // An L profile of sheet metal 0.05 thick (legs x 0..1 and y 0..0.8), 1 tall along z, seen on
  // its long sides only, points 0.02 apart: the end x = 1 of one leg and both ends along z were too
  // thin to segment. Every seen plane is parallel to z, so no plane can close the solid there, and
  // the walls' own points cover the box faces.
  const Eigen::Vector3d up(0, 0, 1);
  const std::vector<PlanarPrimitive> observed = {
      rectangle({0, 0, 0}, {1, 0, 0}, up, 50, 50, {0, -1, 0}),         // outside of the long leg
      rectangle({0.05, 0.05, 0}, {0.95, 0, 0}, up, 48, 50, {0, 1, 0}),  // its inside
      rectangle({0, 0, 0}, {0, 0.8, 0}, up, 40, 50, {-1, 0, 0}),        // outside of the short leg
      rectangle({0.05, 0.05, 0}, {0, 0.75, 0}, up, 38, 50, {1, 0, 0}),  // its inside
      rectangle({0, 0.8, 0}, {0.05, 0, 0}, up, 3, 50, {0, 1, 0})};      // its end
  ObservedFusionReport report;
  const auto fused = fuseWithObserved({}, observed, ObservedFusionOptions{}, &report);
  EXPECT_GT(report.profile_cap_points, 0u) << describe(report);
  // The profile: both legs, widened by the raster (cells of 1.5 spacings, 0.03).
  const auto onProfile = [](const pcl::PointNormal& p) {
    return (p.y <= 0.05f + 0.031f) || (p.x <= 0.05f + 0.031f);
  };
  for (const float z : {0.0f, 1.0f}) {
    // On the seen box, which ends at the outermost rows of points, half a spacing in.
    const auto cap = std::find_if(fused.begin(), fused.end(), [&](const PlanarPrimitive& primitive) {
      return primitive.plane.normal.normalized().isApprox(Eigen::Vector3d(0, 0, z > 0.5f ? 1 : -1), 1e-9) &&
             std::abs(primitive.plane.signedDistance(Eigen::Vector3d(0.5, 0.5, z))) < 0.011;
    });
    ASSERT_NE(cap, fused.end()) << "no cap at z = " << z << ": " << describe(report);
    bool long_leg = false, short_leg = false;
    for (const auto& p : cap->points) {
      EXPECT_TRUE(onProfile(p)) << "cap point in the L's opening: " << p.x << " " << p.y;
      EXPECT_NEAR(p.z, z, 0.011f);
      long_leg = long_leg || (p.x > 0.5f && p.x < 0.6f && p.y < 0.05f);
      short_leg = short_leg || (p.y > 0.4f && p.y < 0.5f && p.x < 0.05f);
    }
    EXPECT_TRUE(long_leg && short_leg) << "the cap at z = " << z << " misses a leg";
  }
  // The long leg's end reaches the box face x = 1, where no plane lies: that face closes it, over
  // the leg's width only.
  const auto end = std::find_if(fused.begin(), fused.end(), [](const PlanarPrimitive& primitive) {
    return primitive.plane.normal.normalized().isApprox(Eigen::Vector3d(1, 0, 0), 1e-9) &&
           std::abs(primitive.plane.signedDistance(Eigen::Vector3d(1, 0, 0))) < 0.011;
  });
  ASSERT_NE(end, fused.end()) << describe(report);
  ASSERT_GE(end->points.size(), 10u);  // the assemblers drop a primitive with fewer
  for (const auto& p : end->points) EXPECT_LE(p.y, 0.05f + 0.031f);
  // With one seen cap the profile is not open along z, and nothing is added.
  std::vector<PlanarPrimitive> capped = observed;
  capped.push_back(rectangle({0, 0, 1}, {1, 0, 0}, {0, 0.05, 0}, 50, 3, {0, 0, 1}));
  ObservedFusionReport with_cap;
  fuseWithObserved({}, capped, ObservedFusionOptions{}, &with_cap);
  EXPECT_EQ(with_cap.profile_cap_points, 0u) << describe(with_cap);
}

TEST(ObservedFusion, AKnownExtentMovesTheFilledFacesOutToIt) {
  // The scene of the test above. The object is known to reach x = 1.5 and y = 1.2: the filled
  // faces x = 0.95 and y = 0.95 move out to x = 1.5 and y = 1.2; y = 0.05 stays. The predicted
  // top no longer covers the grown box's top face (it stops at x, y = 1), so the rest of that
  // face is filled too and joins it.
  const std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  const std::vector<PlanarPrimitive> completed = {
      patch(Plane::fromPointAndNormal({0, 0, 0.9375}, {0, 0, 1}), {0.5, 0.5, 0.9375}, 1.0, 10, 0.9f)};
  ObservedFusionOptions options = coarseFill();
  options.unseen_point_fraction = 1.0;
  options.known_extent_points = {{1.5, 0.5, 0.5}, {0.5, 1.2, 0.5}};
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  EXPECT_EQ(report.filled_faces, 3u);
  ASSERT_EQ(fused.size(), 6u);
  EXPECT_GT(fused[0].points.size(), 100u);  // the top's uncovered part joined the predicted top
  const Eigen::Vector3d expected_normals[] = {{1, 0, 0}, {0, -1, 0}, {0, 1, 0}};
  const double expected_offsets[] = {1.5, 0.05, 1.2};
  for (int f = 0; f < 3; ++f) {
    const PlanarPrimitive& face = fused[3 + f];
    EXPECT_TRUE(face.plane.normal.isApprox(expected_normals[f], 1e-9)) << face.plane.normal.transpose();
    EXPECT_NEAR(face.plane.signedDistance(expected_offsets[f] * expected_normals[f].cwiseAbs()), 0.0, 1e-6);
    // The faces span the grown box: x up to 1.5, y up to 1.2, less half a grid step (the grid's
    // points are the centres of its cells, 0.05 of the box's diagonal of about 2.1 wide).
    double x_max = 0.0, y_max = 0.0;
    for (const auto& p : face.points) {
      x_max = std::max(x_max, double(p.x));
      y_max = std::max(y_max, double(p.y));
    }
    const double reach = f == 0 ? y_max : x_max, extent = f == 0 ? 1.2 : 1.5;
    EXPECT_LT(reach, extent);
    EXPECT_GT(reach, extent - 0.06);
  }
  // Points inside the seen box change nothing: the result of the test above.
  options.known_extent_points = {{0.5, 0.5, 0.5}};
  const auto unchanged = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(unchanged.size(), 6u);
  EXPECT_NEAR(unchanged[3].plane.signedDistance({0.95, 0, 0}), 0.0, 1e-6);
  options.known_extent_points = {{std::nan(""), 0.0, 0.0}};
  EXPECT_THROW(fuseWithObserved(completed, observed, options), InvalidInputError);
}

TEST(ObservedFusion, TheBoxFillLeavesOutSpaceTheScanShowsEmpty) {
  // seenBottomAndSide() (box x in [0, 0.95], y in [0.05, 0.95], z in [0, 0.9375]) plus a seen step:
  // a floor at z = 0.5 facing up over x in [0.5, 0.95]. Above the floor the part is not there:
  // the top face z = 0.9375 must be filled only over x < 0.5, the face x = 0.95 only below z = 0.5.
  std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  const Plane floor = Plane::fromPointAndNormal({0, 0, 0.5}, {0, 0, 1});
  observed.push_back(patch(floor, {0.725, 0.275, 0.5}, 0.45, 6, 1.0f));
  observed.push_back(patch(floor, {0.725, 0.725, 0.5}, 0.45, 6, 1.0f));
  ObservedFusionOptions options = coarseFill();
  ObservedFusionReport report;
  const auto fused = fuseWithObserved({}, observed, options, &report);
  EXPECT_GT(report.fill_in_seen_free_space, 0u);
  EXPECT_NE(describe(report).find("in space the seen faces show empty"), std::string::npos) << describe(report);
  std::size_t top_points = 0, side_points = 0;
  for (const auto& primitive : fused) {
    if (primitive.plane.normal.isApprox(Eigen::Vector3d(0, 0, 1), 1e-9) &&
        std::abs(primitive.plane.signedDistance({0, 0, 0.9375})) < 1e-9) {
      for (const auto& p : primitive.points) EXPECT_LT(p.x, 0.5) << "filled over the seen floor";
      top_points += primitive.points.size();
    }
    if (primitive.plane.normal.isApprox(Eigen::Vector3d(1, 0, 0), 1e-9)) {
      for (const auto& p : primitive.points) EXPECT_LT(p.z, 0.5 + 0.08) << "filled above the seen floor";
      side_points += primitive.points.size();
    }
  }
  // The top over x < 0.5 - 0.08 and the side below the floor still get their box faces: 5 x 12
  // and 12 x 6 grid points, less the rows near seen points.
  EXPECT_GT(top_points, 30u);
  EXPECT_GT(side_points, 30u);
  // Without the floor, no box point is in space the seen faces show empty.
  EXPECT_FALSE(fuseWithObserved({}, seenBottomAndSide(), options, &report).empty());
  EXPECT_EQ(report.fill_in_seen_free_space, 0u);
  // With a zero empty radius every grid point is uncovered and no line meets a seen point.
  options.fill_empty_radius = 0.0;
  EXPECT_FALSE(fuseWithObserved({}, observed, options, &report).empty());
  EXPECT_EQ(report.fill_in_seen_free_space, 0u);
  EXPECT_GT(report.filled_points, 0u);
}

TEST(ObservedFusion, TheBoxSideOfANoisySeenFaceIsThatFace) {
  // seenBottomAndSide() (box x in [0, 0.95], y in [0.05, 0.95], z in [0, 0.9375]; diagonal 1.6)
  // plus the top z = 0.9375, seen over x < 0.45 only, its points 0.06 above and below it in turn:
  // noise takes the seen points' box up to z = 0.9975, twice the fusion's plane tolerance (0.02
  // of the diagonal) above the top. The box's top side is the seen top: the fill adds its points
  // over x > 0.45 to it, and the side x = 0.95 ends there, rather than a second top plane 0.06
  // above it (with the seen top, a thin slab).
  std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  const Plane top = Plane::fromPointAndNormal({0, 0, 0.9375}, {0, 0, 1});
  PlanarPrimitive noisy_top = patch(top, {0.225, 0.5, 0.9375}, 0.45, 8, 1.0f);
  for (std::size_t i = 0; i < noisy_top.points.size(); ++i) noisy_top.points[i].z += (i + i / 8) % 2 ? 0.06f : -0.06f;
  observed.push_back(noisy_top);
  ObservedFusionOptions options = coarseFill();
  ObservedFusionReport report;
  const auto fused = fuseWithObserved({}, observed, options, &report);
  EXPECT_GT(report.filled_points, 0u);
  std::size_t tops = 0;
  for (const auto& primitive : fused) {
    const Eigen::Vector3d n = primitive.plane.normal.normalized();
    if (std::abs(n.z()) > 0.99 && primitive.plane.signedDistance({0, 0, 0}) < -0.5) {
      ++tops;
      EXPECT_NEAR(primitive.plane.signedDistance({0, 0, 0.9375}), 0.0, 1e-6) << "a top plane off the seen top";
      // The seen top's 64 points and the fill's over x > 0.45.
      EXPECT_GT(primitive.points.size(), 64u + 20u);
    }
    if (n.isApprox(Eigen::Vector3d(1, 0, 0), 1e-9)) {
      EXPECT_GT(primitive.points.size(), 50u);
      for (const auto& p : primitive.points) EXPECT_LT(p.z, 0.9375f) << "the side x = 0.95 runs past the seen top";
    }
  }
  EXPECT_EQ(tops, 1u);
}

TEST(ObservedFusion, TheNetworksPointsOfASeenFaceShowFreeSpaceWhereTheScanMissedIt) {
  // As above, but the scan saw the step's floor (z = 0.5, facing up, x in [0.5, 0.95]) only over
  // y < 0.5. The network predicts the whole floor, in two halves. Its points over y > 0.5 show the
  // space above them empty too: the top face z = 0.9375 is filled only over x < 0.5.
  std::vector<PlanarPrimitive> observed = seenBottomAndSide();
  const Plane floor = Plane::fromPointAndNormal({0, 0, 0.5}, {0, 0, 1});
  observed.push_back(patch(floor, {0.725, 0.275, 0.5}, 0.45, 6, 1.0f));
  const std::vector<PlanarPrimitive> completed = {patch(floor, {0.725, 0.275, 0.5}, 0.45, 6, 0.8f),
                                                  patch(floor, {0.725, 0.725, 0.5}, 0.45, 6, 0.8f)};
  ObservedFusionOptions options = coarseFill();
  const auto topPointsBeyond = [](const std::vector<PlanarPrimitive>& fused, double x) {
    std::size_t count = 0;
    for (const auto& primitive : fused)
      if (primitive.plane.normal.isApprox(Eigen::Vector3d(0, 0, 1), 1e-9) &&
          std::abs(primitive.plane.signedDistance({0, 0, 0.9375})) < 1e-9)
        for (const auto& p : primitive.points) count += p.x >= x ? 1 : 0;
    return count;
  };
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  EXPECT_EQ(report.snapped, 1u);
  EXPECT_EQ(report.absorbed, 1u);
  EXPECT_EQ(report.contradicted_points, 0u);
  EXPECT_EQ(topPointsBeyond(fused, 0.5), 0u);
  EXPECT_GT(topPointsBeyond(fused, 0.0), 30u);  // the top over x < 0.5 is still filled
  // With the scan alone, the top over the unseen half of the floor is filled.
  EXPECT_GT(topPointsBeyond(fuseWithObserved({}, observed, options), 0.5), 10u);
}

TEST(ObservedFusion, AnUnseenGuessOfABoxFaceTakesTheFaceAndOutranksTheOtherGuesses) {
  // The box of seenBottomAndSide() is x in [0, 0.95], y in [0.05, 0.95], z in [0, 0.9375].
  // Predicted: a small patch of its face x = 0.95, 5 degrees off and 0.01 outside, with the
  // confidence of a guess. The box fill puts the rest of that face's points on it.
  const double tilt = paco::degreesToRadians(5.0);
  const Plane guess = Plane::fromPointAndNormal({0.96, 0.2, 0.2}, {std::cos(tilt), std::sin(tilt), 0.0});
  const std::vector<PlanarPrimitive> completed = {patch(guess, {0.96, 0.2, 0.2}, 0.3, 5, 0.75f)};
  ObservedFusionOptions options = coarseFill();
  options.unseen_point_fraction = 1.0;
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, seenBottomAndSide(), options, &report);
  EXPECT_EQ(report.box_faces_taken, 1u);
  EXPECT_EQ(report.filled_faces, 3u);  // y = 0.05, y = 0.95 and the top
  EXPECT_NE(describe(report).find("1 unseen primitives turned onto a box face"), std::string::npos)
      << describe(report);
  ASSERT_EQ(fused.size(), 6u);
  const PlanarPrimitive& face = fused[0];
  EXPECT_TRUE(face.plane.normal.isApprox(Eigen::Vector3d(1, 0, 0), 1e-9)) << face.plane.normal.transpose();
  EXPECT_NEAR(face.plane.signedDistance({0.95, 0.5, 0.5}), 0.0, 1e-6);
  EXPECT_FLOAT_EQ(face.confidence, 0.99f);  // like a new box face: the candidate budget keeps it
  EXPECT_GT(face.points.size(), 25u + 100u);
  EXPECT_LT(maxDistanceToPlane(face, face.plane), 1e-6);
  // Seen faces host box points without a change of plane or confidence.
  EXPECT_FLOAT_EQ(fused[1].confidence, 1.0f);
  EXPECT_TRUE(fused[1].plane.normal.isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
}

TEST(ObservedFusion, UnseenPredictionsKeepAFractionOfTheirPointsSeenFacesKeepAll) {
  // Seen and predicted: the top z = 1. Predicted only: the sides x = 1 (256 points, as many as
  // the shipped model gives a primitive) and y = 1 (64 points).
  const Plane top = Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1});
  const Plane side = Plane::fromPointAndNormal({1, 0, 0}, {1, 0, 0});
  const Plane back = Plane::fromPointAndNormal({0, 1, 0}, {0, 1, 0});
  const std::vector<PlanarPrimitive> observed = {patch(top, {0.5, 0.5, 1}, 1.0, 10, 1.0f)};
  const std::vector<PlanarPrimitive> completed = {patch(top, {0.5, 0.5, 1}, 1.0, 8, 0.9f),
                                                  patch(side, {1, 0.5, 0.5}, 1.0, 16, 0.85f),
                                                  patch(back, {0.5, 1, 0.5}, 1.0, 8, 0.85f)};
  EXPECT_EQ(ObservedFusionOptions{}.unseen_point_fraction, 0.25);  // on by default
  ObservedFusionOptions options = fusionOnly();
  options.unseen_point_fraction = 0.25;
  ASSERT_EQ(options.unseen_min_points, 32u);
  ObservedFusionReport report;
  auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 3u);
  EXPECT_EQ(fused[0].points.size(), 64u + 100u);  // a seen face keeps every predicted point
  EXPECT_EQ(fused[1].points.size(), 64u);         // one in four, evenly spaced
  EXPECT_EQ(fused[2].points.size(), 32u);         // one in two: not below the minimum
  EXPECT_EQ(report.thinned_points, 192u + 32u);
  EXPECT_NE(describe(report).find("224 points of unseen primitives thinned out"), std::string::npos)
      << describe(report);
  EXPECT_LT(maxDistanceToPlane(fused[1], side), 1e-6);
  // Evenly spaced: kept point k is the 4k-th, not one of the first 64.
  const auto& original = completed[1].points;
  for (std::size_t k = 0; k < fused[1].points.size(); ++k) {
    EXPECT_EQ(fused[1].points[k].y, original[4 * k].y);
    EXPECT_EQ(fused[1].points[k].z, original[4 * k].z);
  }

  options.unseen_point_fraction = 0.3;  // 1 + floor(255 * 0.3)
  EXPECT_EQ(fuseWithObserved(completed, observed, options, &report)[1].points.size(), 77u);
  options.unseen_min_points = 100;  // at least 100 of 256; all 64 of the smaller one
  fused = fuseWithObserved(completed, observed, options, &report);
  EXPECT_EQ(fused[1].points.size(), 100u);
  EXPECT_EQ(fused[2].points.size(), 64u);
  options.unseen_point_fraction = 1.0;
  EXPECT_EQ(fuseWithObserved(completed, observed, options, &report)[1].points.size(), 256u);
  EXPECT_EQ(report.thinned_points, 0u);
  for (double bad : {0.0, -0.25, 1.5, std::nan("")}) {
    options.unseen_point_fraction = bad;
    EXPECT_THROW(fuseWithObserved(completed, observed, options), InvalidInputError);
  }
}

// How many of the primitive's points satisfy `where`.
template <typename Where>
std::size_t countPoints(const PlanarPrimitive& primitive, Where where) {
  std::size_t n = 0;
  for (const auto& p : primitive.points) n += where(Eigen::Vector3d(p.x, p.y, p.z)) ? 1 : 0;
  return n;
}

TEST(ObservedFusion, ASeenFacesPredictedPointsWhereTheScanSawNoSuchFaceAreDropped) {
  // Seen: the top z = 1 of a block (x in -0.57..0.5, y in -0.03..1.03, its last row at x = 0.5)
  // and its side, a wall x = 0.5 (normal +x), up to z = 0.5 only. The network spreads the wall's
  // points (rows 0.025 apart) up to z = 1. The observed diagonal is about 1.8, so the radius 0.03
  // is 0.054: the wall's two top rows (z = 0.9625 and 0.9875) are that close to the top's last
  // row, where the scan saw the top and no wall, and go. The rows below, down to z = 0.55, are
  // near no seen point, and no seen surface hangs over the space in front of them (the top ends
  // 1.5 radii short of it): the scan says nothing there, and they stay.
  const Plane top = Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1});
  const Plane wall = Plane::fromPointAndNormal({0.5, 0, 0}, {1, 0, 0});
  const std::vector<PlanarPrimitive> observed = {patch(top, {0.5 - 0.55 * 22.0 / 23.0, 0.5, 1}, 1.1, 23, 1.0f),
                                                 patch(wall, {0.5, 0.5, 0.25}, 0.5, 10, 1.0f)};
  std::vector<PlanarPrimitive> completed = {patch(wall, {0.5, 0.5, 0.5}, 1.0, 40, 0.9f)};
  EXPECT_EQ(ObservedFusionOptions{}.contradiction_radius, 0.03);  // on by default
  ObservedFusionOptions options = fusionOnly();
  options.contradiction_radius = 0.03;
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 2u);  // the wall, and the top added as seen
  const PlanarPrimitive& fused_wall = fused[0];
  EXPECT_LT(maxDistanceToPlane(fused_wall, wall), 1e-6);
  const auto high = [](const Eigen::Vector3d& p) { return p.z() > 0.95; };
  const auto middle = [](const Eigen::Vector3d& p) { return p.z() > 0.56 && p.z() < 0.94; };
  EXPECT_EQ(countPoints(completed[0], high), 80u);
  EXPECT_EQ(countPoints(fused_wall, high), 0u);
  EXPECT_EQ(countPoints(fused_wall, middle), countPoints(completed[0], middle));
  EXPECT_EQ(report.contradicted_points, 80u);
  EXPECT_EQ(fused_wall.points.size(), 100u + 1600u - 80u);
  EXPECT_NE(describe(report).find(" points of seen faces dropped where the scan contradicts them"), std::string::npos)
      << describe(report);
  // Off, every predicted point stays.
  options.contradiction_radius = 0.0;
  EXPECT_EQ(fuseWithObserved(completed, observed, options)[0].points.size(), 100u + 1600u);
  for (double bad : {-0.03, std::nan(""), std::numeric_limits<double>::infinity()}) {
    options.contradiction_radius = bad;
    EXPECT_THROW(fuseWithObserved(completed, observed, options), InvalidInputError);
  }
}

TEST(ObservedFusion, ASeenFacesPredictedPointsInsideTheSeenSolidAreDropped) {
  // Seen: the bottom z = 0 (normal -z) over x, y in 0..1, the top z = 1 (normal +z) over x in
  // 0.3..1.3, and a small step face z = 0.5 (normal +z) at x in 0..0.2. The network spreads the
  // step's points over x, y in 0..1. Looking up and down from one at x > 0.4, the first seen
  // surfaces (the top, the bottom) face away from it: it is inside the solid, and goes. Over the
  // seen step (x < 0.2) nothing is above: they stay. No seen point but the step's own lies within
  // the radius (about 0.056) of any of them.
  const Plane bottom = Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1});
  const Plane top = Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1});
  const Plane step = Plane::fromPointAndNormal({0, 0, 0.5}, {0, 0, 1});
  const std::vector<PlanarPrimitive> observed = {patch(bottom, {0.5, 0.5, 0}, 1.0, 20, 1.0f),
                                                 patch(top, {0.8, 0.5, 1}, 1.0, 20, 1.0f),
                                                 patch(step, {0.1, 0.5, 0.5}, 0.2, 5, 1.0f)};
  std::vector<PlanarPrimitive> completed = {patch(step, {0.5, 0.5, 0.5}, 1.0, 20, 0.9f)};
  ObservedFusionOptions options = fusionOnly();
  options.contradiction_radius = 0.03;
  ObservedFusionReport report;
  auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 3u);
  const auto over_the_solid = [](const Eigen::Vector3d& p) { return p.x() > 0.4; };
  const auto over_the_step = [](const Eigen::Vector3d& p) { return p.x() < 0.2; };
  EXPECT_EQ(countPoints(completed[0], over_the_solid), 240u);
  EXPECT_EQ(countPoints(fused[0], over_the_solid), 0u);
  EXPECT_EQ(countPoints(fused[0], over_the_step), 25u + countPoints(completed[0], over_the_step));
  EXPECT_GE(report.contradicted_points, 240u);
  // The same with the network's normal the other way: looking down and up is symmetric.
  completed[0].plane = step.flipped();
  fused = fuseWithObserved(completed, observed, options, &report);
  EXPECT_EQ(countPoints(fused[0], over_the_solid), 0u);
  EXPECT_EQ(countPoints(fused[0], over_the_step), 25u + countPoints(completed[0], over_the_step));
}

TEST(ObservedFusion, ASeenWallsPredictedPointsPastASeenCeilingAreDropped) {
  // A pocket: its ceiling z = 0 (normal -z) seen over x in 0..1 and y in 0.05..1.05, and its wall
  // y = 0 (normal +y) seen below it, z in -0.5..-0.05. The network runs the wall on above the
  // ceiling, through the solid, up to z = 0.5. The observed diagonal is about 1.48, so the radius
  // 0.03 is 0.044, the spot checked lies 1.5 radii (0.066) in front of the wall and the reach is 6
  // radii (0.27). Looking down from the spot in front of a point above the ceiling, the first seen
  // surface is the ceiling, which faces away: the spot is in the solid, and the point goes. Up to
  // the reach only: farther up, the line might have crossed an unseen surface first. In the pocket
  // the ceiling faces the spot, and the points stay.
  const Plane ceiling = Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1});
  const Plane wall = Plane::fromPointAndNormal({0, 0, 0}, {0, 1, 0});
  const std::vector<PlanarPrimitive> observed = {patch(ceiling, {0.5, 0.55, 0}, 1.0, 20, 1.0f),
                                                 patch(wall, {0.5, 0, -0.275}, 0.45, 9, 1.0f)};
  // Rows z = -0.475, -0.425, ..., 0.475, x = 0.025, ..., 0.975.
  std::vector<PlanarPrimitive> completed = {patch(wall, {0.5, 0, 0}, 1.0, 20, 0.9f)};
  ObservedFusionOptions options = fusionOnly();
  options.contradiction_radius = 0.03;
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 2u);  // the wall, and the ceiling added as seen
  const PlanarPrimitive& fused_wall = fused[0];
  ASSERT_LT(maxDistanceToPlane(fused_wall, wall), 1e-6);
  const auto within_reach_above = [](const Eigen::Vector3d& p) { return p.z() > 0.0 && p.z() < 0.26; };
  const auto beyond_reach = [](const Eigen::Vector3d& p) { return p.z() > 0.3; };
  const auto in_the_pocket = [](const Eigen::Vector3d& p) { return p.z() < 0.0; };
  EXPECT_EQ(countPoints(completed[0], within_reach_above), 100u);
  EXPECT_EQ(countPoints(fused_wall, within_reach_above), 0u);
  EXPECT_EQ(countPoints(fused_wall, beyond_reach), countPoints(completed[0], beyond_reach));
  EXPECT_EQ(countPoints(fused_wall, in_the_pocket), 81u + countPoints(completed[0], in_the_pocket));
  EXPECT_GE(report.contradicted_points, 100u);

  // Seen with the wall's normal the other way (air at y < 0), the ceiling no longer hangs over the
  // spot in front: every point above it stays. It hangs over the spot behind the points below it
  // instead, and faces it, as it faces the air under it: those within the reach go.
  const Plane wall_facing_back = wall.flipped();
  const std::vector<PlanarPrimitive> observed_back = {observed[0],
                                                      patch(wall_facing_back, {0.5, 0, -0.275}, 0.45, 9, 1.0f)};
  const PlanarPrimitive fused_back = fuseWithObserved(completed, observed_back, options)[0];
  const auto above = [](const Eigen::Vector3d& p) { return p.z() > 0.0; };
  const auto within_reach_below = [](const Eigen::Vector3d& p) { return p.z() < 0.0 && p.z() > -0.26; };
  EXPECT_EQ(countPoints(fused_back, above), countPoints(completed[0], above));
  EXPECT_EQ(countPoints(completed[0], within_reach_below), 100u);
  EXPECT_EQ(countPoints(fused_back, within_reach_below), countPoints(observed_back[1], within_reach_below));
  EXPECT_EQ(fused_back.points.size(), 81u + 400u - 100u);

  // Off with the radius, as every check of the seen faces' predicted points.
  options.contradiction_radius = 0.0;
  EXPECT_EQ(fuseWithObserved(completed, observed, options)[0].points.size(), 81u + 400u);
}

TEST(ObservedFusion, ASeenTopsPredictedPointsOverASeenSlotAreDropped) {
  // A slot through a block: the top z = 1 (normal +z) seen at y in 0..0.4 and 0.6..1 (x in
  // 0.3..0.7), and the slot's walls y = 0.4 (normal +y) and y = 0.6 (normal -y) seen at z in
  // 0.5..1. The network spreads the top over the slot's opening (rows 0.05 apart). The observed
  // diagonal is about 1.15, so the radius 0.03 is 0.035, the spot checked lies 1.5 radii (0.052)
  // below a point and the reach is 6 radii (0.21). Looking along y from the spot below a point
  // over the opening, the first seen wall faces back at it: the spot is in air, and the point goes.
  // Below a point over the block the first wall met faces away: it stays.
  const Plane top = Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1});
  const Plane near_wall = Plane::fromPointAndNormal({0, 0.4, 0}, {0, 1, 0});
  const Plane far_wall = Plane::fromPointAndNormal({0, 0.6, 0}, {0, -1, 0});
  const std::vector<PlanarPrimitive> observed = {
      patch(top, {0.5, 0.2, 1}, 0.4, 8, 1.0f), patch(top, {0.5, 0.8, 1}, 0.4, 8, 1.0f),
      patch(near_wall, {0.5, 0.4, 0.75}, 0.5, 10, 1.0f), patch(far_wall, {0.5, 0.6, 0.75}, 0.5, 10, 1.0f)};
  // Rows x, y = 0.025, 0.075, ..., 0.975.
  std::vector<PlanarPrimitive> completed = {patch(top, {0.5, 0.5, 1}, 1.0, 20, 0.9f)};
  ObservedFusionOptions options = fusionOnly();
  options.contradiction_radius = 0.03;
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(completed, observed, options, &report);
  ASSERT_EQ(fused.size(), 3u);  // the top, and the two walls added as seen
  const PlanarPrimitive& fused_top = fused[0];
  ASSERT_LT(maxDistanceToPlane(fused_top, top), 1e-6);
  // Along the walls' seen length, away from every seen point by more than the radius.
  const auto over_the_opening = [](const Eigen::Vector3d& p) {
    return p.x() > 0.3 && p.x() < 0.7 && p.y() > 0.45 && p.y() < 0.55;
  };
  const auto over_the_block = [](const Eigen::Vector3d& p) {
    return p.x() > 0.3 && p.x() < 0.7 && (p.y() < 0.35 || p.y() > 0.65);
  };
  EXPECT_EQ(countPoints(completed[0], over_the_opening), 16u);
  EXPECT_EQ(countPoints(fused_top, over_the_opening), 0u);
  EXPECT_EQ(countPoints(fused_top, over_the_block), 2u * 56u + countPoints(completed[0], over_the_block));
  EXPECT_GE(report.contradicted_points, 16u);

  // Off with the radius, as every check of the seen faces' predicted points.
  options.contradiction_radius = 0.0;
  EXPECT_EQ(countPoints(fuseWithObserved(completed, observed, options)[0], over_the_opening), 16u);
}

// Seen from above: a roof z = 1 (10 x 10 points, x and y in 0.05..0.95, spacing 0.1). Predicted:
// the roof, too wide; a wall under its edge; a wall far off; a face floating above the roof; and
// the bottom, a little too wide.
struct RoofScan {
  std::vector<PlanarPrimitive> observed = {
      patch(Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1}), {0.5, 0.5, 1}, 1.0, 10, 1.0f)};
  std::vector<PlanarPrimitive> completed = {
      // x and y at -0.4, -0.2, ..., 1.4: those at 0 .. 1.0 lie within a line of sight of the roof
      patch(Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1}), {0.5, 0.5, 1}, 2.0, 10, 0.9f),
      patch(Plane::fromPointAndNormal({0, 0, 0}, {-1, 0, 0}), {0, 0.5, 0.5}, 1.0, 6, 0.9f),
      patch(Plane::fromPointAndNormal({2, 0, 0}, {1, 0, 0}), {2, 0.5, 0.5}, 1.0, 6, 0.9f),
      patch(Plane::fromPointAndNormal({0, 0, 1.5}, {0, 0, 1}), {0.5, 0.5, 1.5}, 0.5, 5, 0.9f),
      // x and y at -0.2, 0, ..., 1.2
      patch(Plane::fromPointAndNormal({0, 0, 0}, {0, 0, -1}), {0.5, 0.5, 0}, 1.6, 8, 0.9f)};
};

TEST(ObservedFusion, CompletedPointsADistantScannerWouldHaveSeenAreDropped) {
  const RoofScan scan;
  ObservedFusionReport report;
  EXPECT_EQ(fuseWithObserved(scan.completed, scan.observed, fusionOnly(), &report).size(), 5u);  // off by default
  EXPECT_EQ(report.seen_empty_points, 0u);

  // Airborne: the scanner looked down from +z. A line of sight is twice the roof's point spacing
  // wide (0.2), wider than the cell of 0.03 of the diagonal (0.038).
  ObservedFusionOptions options = fusionOnly();
  options.scanner_direction = {0, 0, 2};
  const auto fused = fuseWithObserved(scan.completed, scan.observed, options, &report);
  ASSERT_EQ(fused.size(), 3u);  // the far wall and the floating face are gone
  // The roof keeps its seen points and the 6 x 6 predicted ones over it; the bottom loses its
  // outer ring (28 of 64, less than half) and stays.
  EXPECT_EQ(fused[0].points.size(), 100u + 36u);
  EXPECT_NEAR(fused[1].plane.signedDistance({0, 0.5, 0.5}), 0.0, 1e-12);
  EXPECT_EQ(fused[1].points.size(), 36u);
  EXPECT_NEAR(fused[2].plane.signedDistance({0.5, 0.5, 0}), 0.0, 1e-12);
  EXPECT_EQ(fused[2].points.size(), 36u);
  EXPECT_EQ(report.seen_empty_points, 64u + 36u + 25u + 28u);
  EXPECT_EQ(report.seen_empty, 2u);
  EXPECT_NE(describe(report).find("153 completed points dropped where the scanner would have seen them (2 unseen"),
            std::string::npos)
      << describe(report);

  // Seen from below, the roof hides nothing beneath it: everything under it would have been seen.
  options.scanner_direction = {0, 0, -1};
  const auto from_below = fuseWithObserved(scan.completed, scan.observed, options, &report);
  ASSERT_EQ(from_below.size(), 2u);  // the roof and the face above it, which the roof hides
  EXPECT_EQ(from_below[0].points.size(), 100u + 36u);
  EXPECT_NEAR(from_below[1].plane.signedDistance({0.5, 0.5, 1.5}), 0.0, 1e-12);
}

TEST(ObservedFusion, CompletedPointsAScannerAtAPointWouldHaveSeenAreDropped) {
  const RoofScan scan;
  ObservedFusionOptions options = fusionOnly();
  options.scanner_position = Eigen::Vector3d(0.5, 0.5, 3.0);
  ObservedFusionReport report;
  const auto fused = fuseWithObserved(scan.completed, scan.observed, options, &report);
  ASSERT_EQ(fused.size(), 3u);
  EXPECT_EQ(fused[0].points.size(), 100u + 36u);
  EXPECT_EQ(fused[1].points.size(), 36u);
  // Lines of sight through a point spread: the roof's shadow covers the whole bottom.
  EXPECT_EQ(fused[2].points.size(), 64u);
  EXPECT_EQ(report.seen_empty_points, 64u + 36u + 25u);
  EXPECT_EQ(report.seen_empty, 2u);

  // What cannot be a scanner is rejected.
  options.scanner_position = Eigen::Vector3d(0.5, 0.5, 1.0);  // at the seen points' centre
  EXPECT_THROW(fuseWithObserved(scan.completed, scan.observed, options), InvalidInputError);
  options.scanner_position = Eigen::Vector3d(0.5, 0.5, 3.0);
  options.scanner_direction = {0, 0, 1};  // both ways
  EXPECT_THROW(fuseWithObserved(scan.completed, scan.observed, options), InvalidInputError);
  options.scanner_position.reset();
  options.scanner_direction = {0, 0, std::nan("")};
  EXPECT_THROW(fuseWithObserved(scan.completed, scan.observed, options), InvalidInputError);
  options.scanner_direction = {0, 0, 1};
  for (double bad : {0.0, -0.1, std::nan("")}) {
    options.scanner_cell = bad;
    EXPECT_THROW(fuseWithObserved(scan.completed, scan.observed, options), InvalidInputError);
  }
}

// An airborne scan of a gable roof: two slopes at 20 degrees either side of a ridge at height 1
// that runs at 30 degrees to x, each 0.5 wide. No two seen planes are perpendicular. Seen from
// above, the box's walls run along the lines of sight (z) and the ridge, and its floor is level
// under the lowest seen point. Without the scanner, the slopes are mirror images of each other and
// their bisectors give the same box; with one slope much smaller than the other, the box takes the
// larger slope's normal as an axis and closes the hidden side with a floor parallel to that slope.
// Seen from above, no seen plane runs along the lines of sight (no wall): the report says so.
TEST(ObservedFusion, ADistantScannersLinesOfSightAreAnAxisOfTheSeenBox) {
  const Eigen::Matrix3d heading =
      Eigen::AngleAxisd(degreesToRadians(30.0), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d ridge = heading * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d across = heading * Eigen::Vector3d::UnitY();
  const double slope = degreesToRadians(20.0);
  std::vector<PlanarPrimitive> observed;
  for (const double side : {-1.0, 1.0}) {
    const Eigen::Vector3d normal = side * std::sin(slope) * across + std::cos(slope) * Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d centre = 0.5 * ridge + (0.5 + 0.25 * side) * across +
                                   (1.0 - 0.25 * std::tan(slope)) * Eigen::Vector3d::UnitZ();
    observed.push_back(patch(Plane::fromPointAndNormal(centre, normal), centre, 0.5, 12, 1.0f));
  }
  observed[1].points.resize(120);
  double lowest = 1.0;
  for (const auto& primitive : observed)
    for (const auto& p : primitive.points) lowest = std::min(lowest, double(p.z));
  const auto isOneOf = [](const Eigen::Vector3d& normal, std::initializer_list<Eigen::Vector3d> directions) {
    for (const Eigen::Vector3d& d : directions)
      if (std::abs(normal.normalized().dot(d)) > 1.0 - 1e-9) return true;
    return false;
  };
  // The faces the fill adds after the seen ones are level, along the ridge or across it, and one
  // of them is a floor under the lowest seen point.
  const auto expectALevelBox = [&](const std::vector<PlanarPrimitive>& fused, std::size_t seen) {
    bool floor = false;
    for (std::size_t i = seen; i < fused.size(); ++i) {
      EXPECT_TRUE(isOneOf(fused[i].plane.normal, {Eigen::Vector3d::UnitZ(), ridge, across}))
          << fused[i].plane.normal.transpose();
      if (fused[i].plane.normal.isApprox(-Eigen::Vector3d::UnitZ(), 1e-9)) {
        floor = true;
        EXPECT_NEAR(fused[i].plane.signedDistance({0, 0, lowest}), 0.0, 1e-6);
      }
    }
    EXPECT_TRUE(floor);
  };
  ObservedFusionOptions options;
  options.unseen_point_fraction = 1.0;
  options.contradiction_radius = 0.0;
  ObservedFusionReport report;

  const auto mirrored = fuseWithObserved({}, observed, options, &report);
  ASSERT_GT(report.filled_faces, 0u);
  EXPECT_TRUE(report.box_on_mirror_pair);
  EXPECT_FALSE(report.box_on_one_plane);
  EXPECT_NE(describe(report).find("so the box lies on the bisectors of mirror-image planes"), std::string::npos)
      << describe(report);
  ASSERT_EQ(mirrored.size(), 2u + report.filled_faces);
  expectALevelBox(mirrored, 2);

  std::vector<PlanarPrimitive> lopsided = observed;
  lopsided[1].points.resize(30);  // too small to be the larger slope's mirror image
  const auto tilted = fuseWithObserved({}, lopsided, options, &report);
  ASSERT_GT(report.filled_faces, 0u);
  EXPECT_TRUE(report.box_on_one_plane);
  EXPECT_FALSE(report.box_on_mirror_pair);
  EXPECT_NE(describe(report).find("no two seen planes are perpendicular, so the box lies on the largest one"),
            std::string::npos)
      << describe(report);
  std::size_t parallel_to_the_slope = 0;
  for (std::size_t i = 2; i < tilted.size(); ++i) {
    EXPECT_FALSE(isOneOf(tilted[i].plane.normal, {Eigen::Vector3d::UnitZ()})) << tilted[i].plane.normal.transpose();
    parallel_to_the_slope += isOneOf(tilted[i].plane.normal, {observed[0].plane.normal});
  }
  EXPECT_GT(parallel_to_the_slope, 0u);
  // One slope seen from both sides (parallel planes only, a plate): the box's first axis is sure.
  PlanarPrimitive underside = observed[0];
  underside.plane = Plane::fromPointAndNormal(underside.plane.foot() - 0.05 * underside.plane.normal,
                                              -underside.plane.normal);
  for (auto& p : underside.points) p.getVector3fMap() -= (0.05 * observed[0].plane.normal).cast<float>();
  fuseWithObserved({}, {observed[0], underside}, options, &report);
  EXPECT_FALSE(report.box_on_one_plane);
  EXPECT_FALSE(report.box_on_mirror_pair);

  options.scanner_direction = {0, 0, 1};
  for (const auto* scan : {&observed, &lopsided}) {
    const auto level = fuseWithObserved({}, *scan, options, &report);
    ASSERT_GT(report.filled_faces, 0u);
    EXPECT_FALSE(report.box_on_one_plane);
    EXPECT_FALSE(report.box_on_mirror_pair);
    EXPECT_TRUE(report.no_seen_plane_along_sight);  // no wall: the box ends at the eaves
    ASSERT_EQ(level.size(), 2u + report.filled_faces);
    expectALevelBox(level, 2);
  }
  // Seen along the ridge, the slopes run along the lines of sight; without a scanner, no flag.
  options.scanner_direction = ridge;
  fuseWithObserved({}, observed, options, &report);
  EXPECT_FALSE(report.no_seen_plane_along_sight);
  options.scanner_direction = Eigen::Vector3d::Zero();
  fuseWithObserved({}, observed, options, &report);
  EXPECT_FALSE(report.no_seen_plane_along_sight);
}

// A gable roof seen from above, turned 30 degrees about the vertical: no two seen planes are
// perpendicular. The network carries one slope on along the ridge past the seen box, which is kept
// (a seen face may run on past the scan), and down the slope past the eaves, which is dropped:
// there it would hang below the roof (on an airborne scan, tens of metres sideways).
TEST(ObservedFusion, ATiltedSeenFaceEndsAtTheSeenBoxAlongItsSlope) {
  const Eigen::Matrix3d heading =
      Eigen::AngleAxisd(degreesToRadians(30.0), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d ridge = heading * Eigen::Vector3d::UnitX();
  const Eigen::Vector3d across = heading * Eigen::Vector3d::UnitY();
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  const double slope = degreesToRadians(20.0);
  const double run = 0.5 / std::cos(slope);  // ridge to eaves, along the slope
  const Eigen::Vector3d top = 0.5 * across + up;  // the ridge line starts here
  std::vector<PlanarPrimitive> roof;
  std::vector<Eigen::Vector3d> downhill;
  for (const double side : {-1.0, 1.0}) {
    const Eigen::Vector3d normal = side * std::sin(slope) * across + std::cos(slope) * up;
    downhill.push_back(side * std::cos(slope) * across - std::sin(slope) * up);
    roof.push_back(rectangle(top, ridge, run * downhill.back(), 20, 10, normal));
  }
  PlanarPrimitive predicted = rectangle(top + 1.1 * ridge, 0.3 * ridge, 0.5 * run * downhill[0], 6, 5,
                                        roof[0].plane.normal);  // along the ridge, past the box
  const PlanarPrimitive past_the_eaves = rectangle(top + 0.4 * ridge + (run + 0.2) * downhill[0], 0.2 * ridge,
                                                   0.3 * downhill[0], 4, 6, roof[0].plane.normal);
  const std::size_t along_the_ridge = predicted.points.size();
  predicted.points += past_the_eaves.points;
  predicted.confidence = 0.9f;

  ObservedFusionReport report;
  const auto fused = fuseWithObserved({predicted}, roof, fusionOnly(), &report);
  ASSERT_EQ(fused.size(), 2u);
  EXPECT_EQ(report.snapped, 1u);
  EXPECT_EQ(report.tilted_points, past_the_eaves.points.size()) << describe(report);
  EXPECT_EQ(fused[0].points.size(), roof[0].points.size() + along_the_ridge);
  EXPECT_NE(describe(report).find(std::to_string(past_the_eaves.points.size()) +
                                  " points of tilted seen faces past the seen box dropped"),
            std::string::npos)
      << describe(report);
  // With the gable's end wall seen too (perpendicular to both slopes) the box's axes are not a
  // guess and the rule is left alone: the points past the eaves stay.
  std::vector<PlanarPrimitive> with_gable = roof;
  with_gable.push_back(rectangle(Eigen::Vector3d::Zero(), across, 0.9 * up, 10, 9, -ridge));
  const auto gabled = fuseWithObserved({predicted}, with_gable, fusionOnly(), &report);
  EXPECT_EQ(report.tilted_points, 0u);
  EXPECT_FALSE(report.box_on_mirror_pair);
  EXPECT_EQ(gabled[0].points.size(), roof[0].points.size() + predicted.points.size());
  // Within a margin as wide as their reach, or with the margin off, they stay.
  for (const double margin : {0.6, std::numeric_limits<double>::infinity()}) {
    ObservedFusionOptions wide = fusionOnly();
    wide.tilt_margin = margin;
    const auto kept = fuseWithObserved({predicted}, roof, wide, &report);
    EXPECT_EQ(report.tilted_points, 0u);
    EXPECT_EQ(kept[0].points.size(), roof[0].points.size() + predicted.points.size());
  }
}

TEST(ObservedFusion, CoordinatesNear1e20DoNotCrashIt) {
  // Squared distances overflow a float there, and the nearest-point searches found no neighbour
  // (a segfault before). What comes out is not checked: such a cloud has no sensible answer.
  RoofScan scan;
  for (auto* primitives : {&scan.observed, &scan.completed})
    for (auto& primitive : *primitives) {
      for (auto& p : primitive.points) p.x *= 1e20f, p.y *= 1e20f, p.z *= 1e20f;
      primitive.plane.offset *= 1e20;
    }
  ObservedFusionOptions options;
  options.scanner_direction = {0, 0, 1};
  EXPECT_FALSE(fuseWithObserved(scan.completed, scan.observed, options).empty());
}

}  // namespace
}  // namespace paco
