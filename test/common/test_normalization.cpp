#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/common/orientation.h>

#include <Eigen/Geometry>
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

namespace {
Eigen::Matrix3d turn(double degrees, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(paco::degreesToRadians(degrees), axis.normalized()).toRotationMatrix();
}
}  // namespace

TEST(Normalization, TurnedFrameMovesPointsPlanesAndNormalsConsistently) {
  const Eigen::Matrix3d R = turn(37.0, Eigen::Vector3d(1, 2, 3));
  pcl::PointCloud<pcl::PointNormal> cloud;
  for (const auto& x : {Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, -1, 0), Eigen::Vector3d(2, 5, 7)}) {
    pcl::PointNormal p;
    p.getVector3fMap() = x.cast<float>();
    p.getNormalVector3fMap() = Eigen::Vector3f(0, 0, 1);
    cloud.push_back(p);
  }
  const auto n = paco::Normalization::fromBoundingBox(cloud, R);
  EXPECT_TRUE(n.rotation.isApprox(R));
  auto moved = cloud;
  n.apply(moved);
  // Centred with unit diagonal in the turned axes.
  Eigen::Vector3f lo = moved[0].getVector3fMap(), hi = lo;
  for (const auto& p : moved) {
    lo = lo.cwiseMin(p.getVector3fMap());
    hi = hi.cwiseMax(p.getVector3fMap());
  }
  EXPECT_NEAR((hi - lo).norm(), 1.0, 1e-5);
  EXPECT_LT(((hi + lo) * 0.5f).norm(), 1e-5);
  // Normals turn with the frame and come back.
  EXPECT_TRUE(moved[0].getNormalVector3fMap().cast<double>().isApprox(R * Eigen::Vector3d(0, 0, 1), 1e-6));
  n.applyInverse(moved);
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    EXPECT_LT((moved[i].getVector3fMap() - cloud[i].getVector3fMap()).norm(), 1e-4);
    EXPECT_LT((moved[i].getNormalVector3fMap() - cloud[i].getNormalVector3fMap()).norm(), 1e-6);
  }
  // A plane through two cloud points still passes through their images, with a turned normal.
  const paco::Plane p = paco::Plane::fromPointAndNormal(Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(1, 1, 0));
  const paco::Plane q = n.apply(p);
  EXPECT_TRUE(q.normal.isApprox(R * p.normal));
  EXPECT_NEAR(q.signedDistance(n.apply(Eigen::Vector3d(1, 2, 3))), 0, 1e-12);
  EXPECT_NEAR(q.signedDistance(n.apply(Eigen::Vector3d(0, 3, -8))), 0, 1e-12);
  const paco::Plane back = n.applyInverse(q);
  EXPECT_TRUE(back.normal.isApprox(p.normal));
  EXPECT_NEAR(back.offset, p.offset, 1e-12);
}

TEST(Normalization, TurnedCompositionAndInverse) {
  paco::Normalization a{Eigen::Vector3d(1, 0, 0), 2.0, turn(30, Eigen::Vector3d(0, 0, 1))};
  paco::Normalization b{Eigen::Vector3d(0, 3, 0), 0.5, turn(-50, Eigen::Vector3d(1, 1, 0))};
  const Eigen::Vector3d x(7, -2, 5);
  EXPECT_TRUE(a.then(b).apply(x).isApprox(b.apply(a.apply(x))));
  EXPECT_TRUE(a.inverse().apply(a.apply(x)).isApprox(x));
  EXPECT_TRUE(a.inverse().rotation.isApprox(a.rotation.transpose()));
}

TEST(Normalization, RejectsATurnThatIsNotARotation) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back({0, 0, 0});
  cloud.push_back({1, 1, 1});
  EXPECT_THROW(paco::Normalization::fromBoundingBox(cloud, Eigen::Matrix3d::Identity() * 2.0), paco::InvalidInputError);
  Eigen::Matrix3d mirror = Eigen::Matrix3d::Identity();
  mirror(2, 2) = -1.0;
  EXPECT_THROW(paco::Normalization::fromBoundingBox(cloud, mirror), paco::InvalidInputError);
}

TEST(Orientation, TurnsTheDominantSeenFacesOntoTheAxes) {
  // Three faces of a box turned by R0, with noisy normals: the largest first.
  const Eigen::Matrix3d R0 = turn(23.0, Eigen::Vector3d(0.3, -1, 0.5));
  const std::vector<Eigen::Vector3d> normals = {R0 * Eigen::Vector3d(0, 0, 1), -(R0 * Eigen::Vector3d(1, 0.01, 0)),
                                                R0 * Eigen::Vector3d(0, 1, 0), R0 * Eigen::Vector3d(1, 1, 1)};
  const std::vector<double> sizes = {500, 300, 200, 100};
  const Eigen::Matrix3d R = paco::seenPlanesRotation(normals, sizes);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  EXPECT_TRUE((R.transpose() * R).isApprox(Eigen::Matrix3d::Identity()));
  // The largest face lands exactly on an axis, the second within its noise (0.6 degrees).
  const auto on_axis = [](const Eigen::Vector3d& v) { return v.normalized().cwiseAbs().maxCoeff(); };
  EXPECT_NEAR(on_axis(R * normals[0]), 1.0, 1e-12);
  EXPECT_GT(on_axis(R * normals[1]), std::cos(paco::degreesToRadians(0.6)));
  EXPECT_GT(on_axis(R * normals[2]), std::cos(paco::degreesToRadians(0.6)));
  // Of the 24 such turns, the one closest to the identity: it undoes R0 (a 23-degree turn), up
  // to the second face's noise.
  EXPECT_LT(Eigen::AngleAxisd(R * R0).angle(), paco::degreesToRadians(0.6));
}

TEST(Orientation, LeavesAnAxisAlignedScanAsItIs) {
  const std::vector<Eigen::Vector3d> normals = {Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, 2), Eigen::Vector3d(1, 0, 0)};
  EXPECT_TRUE(paco::seenPlanesRotation(normals, {10, 5, 1}).isApprox(Eigen::Matrix3d::Identity()));
  // Nothing to go by: the identity.
  EXPECT_TRUE(paco::seenPlanesRotation({}, {}).isApprox(Eigen::Matrix3d::Identity()));
  EXPECT_TRUE(paco::seenPlanesRotation({Eigen::Vector3d::Zero()}, {4}).isApprox(Eigen::Matrix3d::Identity()));
  EXPECT_THROW(paco::seenPlanesRotation(normals, {1, 2}), paco::InvalidInputError);
}

TEST(Orientation, AChamferLargerThanEveryFaceDoesNotSetTheAxes) {
  // A box turned by R0 and seen with a 45-degree chamfer that is its largest seen plane: the
  // box's three faces outweigh it and the face perpendicular to it (square roots of the weights:
  // 49.9 against 37.3), so they set the axes.
  const Eigen::Matrix3d R0 = turn(17.0, Eigen::Vector3d(1, 2, -0.5));
  const std::vector<Eigen::Vector3d> normals = {R0 * Eigen::Vector3d(0, -1, -1), R0 * Eigen::Vector3d(-1, 0, 0),
                                                R0 * Eigen::Vector3d(0, -1, 0), R0 * Eigen::Vector3d(0, 0, -1)};
  const auto axes = paco::dominantPlaneAxes(normals, {400, 300, 280, 250});
  ASSERT_TRUE(axes.has_value());
  EXPECT_NEAR(axes->determinant(), 1.0, 1e-9);
  for (std::size_t k = 1; k < normals.size(); ++k)
    EXPECT_NEAR((axes->transpose() * normals[k]).cwiseAbs().maxCoeff(), 1.0, 1e-9) << "face " << k;
  // The chamfer and one face alone span one frame, the heavier plane (the chamfer) exactly on an axis.
  const auto chamfer = paco::dominantPlaneAxes({normals[0], normals[1]}, {400, 300});
  ASSERT_TRUE(chamfer.has_value());
  EXPECT_NEAR((chamfer->transpose() * normals[0].normalized()).cwiseAbs().maxCoeff(), 1.0, 1e-9);
}

TEST(Orientation, ManyFacesOnThePartsAxesOutweighALargeChamferAndItsPerpendicularFaces) {
  // The segments of MFCAD part 0-13-13-14-14-23 at 75 % missing, view 0 (sizes in points): faces
  // on x, y and z, a large chamfer about z, a smaller slanted face, and the faces on z, which are
  // perpendicular to the chamfer too. By plain weight the chamfer's frame wins (626 + 708 against
  // 1,227); by the sum of square roots, the part's axes do (91.6 against 66.8).
  const std::vector<Eigen::Vector3d> normals = {
      {-1, 0, 0}, {-1, 0, 0}, {0, 0, -1}, {-0.55278605, -0.8333232, 0}, {0, -1, 0},
      {0, 0, -1}, {-0.39831138, 0.9172503, 0}, {1, 0, 0}, {0, -1, 0}, {0, 0, 1}};
  const std::vector<double> sizes = {113, 175, 533, 626, 60, 102, 99, 60, 111, 73};
  EXPECT_TRUE(paco::seenPlanesRotation(normals, sizes).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  // The chamfer and the faces perpendicular to it alone do set their frame.
  const std::vector<Eigen::Vector3d> chamfer_frame = {normals[3], normals[2], normals[5], normals[9]};
  const auto axes = paco::dominantPlaneAxes(chamfer_frame, {626, 533, 102, 73});
  ASSERT_TRUE(axes.has_value());
  EXPECT_NEAR((axes->transpose() * normals[3].normalized()).cwiseAbs().maxCoeff(), 1.0, 1e-9);
}

TEST(Orientation, AFrameTurnedOntoASlightlySlantedFaceLosesToThePartsOwnAxes) {
  // The segments of MFCAD part 1-4-7-11-13-23 at 25 % missing, view 0: faces on the axes, and a
  // face 7.4 degrees off x. A frame with that face on its axis keeps every face of the axes within
  // the 10-degree tolerance; counted in full they made it win. Counted by their closeness, the
  // part's own axes win.
  const std::vector<Eigen::Vector3d> normals = {
      {0, 1, 0}, {0, -1, 0}, {0.99165845, -1.1677856e-05, 0.12889342}, {0, 0, -1},
      {-0.76312727, 0, -0.6462482}, {-0.20311335, 0, 0.97915524}, {1, 0, 0}, {-1, 0, 0}, {0, 0, 1},
      {-0.7745461, -0.63251746, 0}, {0, 1, 0}, {0.8714375, 0, -0.4905066}, {-1, 0, 0},
      {0, 0.9737533, -0.22760604}, {-0.77454484, 0.632519, 0}};
  const std::vector<double> sizes = {63, 373, 108, 308, 59, 80, 69, 125, 158, 124, 60, 71, 62, 100, 116};
  EXPECT_TRUE(paco::seenPlanesRotation(normals, sizes).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

TEST(Orientation, AZeroToleranceCountsThePlanesExactlyOnTheAxes) {
  // Two perpendicular planes (square roots 9 + 9) outweigh a larger plane off their axes (10).
  const auto axes = paco::dominantPlaneAxes({{1, 1, 1}, {1, 0, 0}, {0, 1, 0}}, {100, 81, 81}, 0.0);
  ASSERT_TRUE(axes.has_value());
  EXPECT_TRUE(axes->isApprox(Eigen::Matrix3d::Identity(), 1e-12)) << *axes;
}

TEST(Orientation, ALargePlaneWithoutAPerpendicularPartnerOutweighsASmallPair) {
  // Two small perpendicular planes, and a large one perpendicular to neither: the large plane's
  // frame carries more weight than the pair's, which leaves it off its axes.
  const std::vector<Eigen::Vector3d> normals = {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(1, 0, 0),
                                                Eigen::Vector3d(0, 1, 0)};
  const auto axes = paco::dominantPlaneAxes(normals, {1000, 10, 10});
  ASSERT_TRUE(axes.has_value());
  EXPECT_TRUE(axes->col(0).isApprox(normals[0].normalized(), 1e-12)) << axes->col(0).transpose();
  // Without the large plane, the pair sets the axes.
  const auto pair = paco::dominantPlaneAxes({normals[1], normals[2]}, {10, 10});
  ASSERT_TRUE(pair.has_value());
  EXPECT_TRUE(pair->isApprox(Eigen::Matrix3d::Identity(), 1e-12));
}

TEST(Orientation, OnePlaneIsTurnedOntoItsNearestAxis) {
  const Eigen::Matrix3d R0 = turn(15.0, Eigen::Vector3d(1, 0, 0));
  const Eigen::Vector3d normal = R0 * Eigen::Vector3d(0, 0, 1);
  // Parallel planes only (a slab): the second axis comes from the coordinate axes.
  const Eigen::Matrix3d R = paco::seenPlanesRotation({normal, -normal}, {3, 2});
  EXPECT_TRUE((R * normal).isApprox(Eigen::Vector3d(0, 0, 1), 1e-9));
  EXPECT_TRUE(R.isApprox(R0.transpose(), 1e-9));
}

// A gable roof seen from above: two slopes at 20 degrees either side of a ridge that runs at 30
// degrees to x. No two planes are perpendicular, so dominantPlaneAxes tilts its frame onto the
// larger slope; around the lines of sight the frame is the vertical, the ridge and across it.
TEST(Orientation, AroundTheLinesOfSightAGableRoofGivesTheVerticalAndItsRidge) {
  const Eigen::Matrix3d heading = turn(30.0, Eigen::Vector3d(0, 0, 1));
  const Eigen::Vector3d ridge = heading * Eigen::Vector3d(1, 0, 0);
  const std::vector<Eigen::Vector3d> slopes = {turn(20.0, ridge) * Eigen::Vector3d(0, 0, 1),
                                               turn(-20.0, ridge) * Eigen::Vector3d(0, 0, 1)};
  const std::vector<double> sizes = {2100, 2000};
  const auto tilted = paco::dominantPlaneAxes(slopes, sizes);
  ASSERT_TRUE(tilted.has_value());
  EXPECT_TRUE(tilted->col(0).isApprox(slopes[0], 1e-12));

  EXPECT_FALSE(paco::hasPerpendicularPlanes(slopes, sizes));
  // A wall along the ridge is perpendicular to neither slope (it is 70 degrees from each); one
  // across it is perpendicular to both.
  const Eigen::Vector3d along_the_ridge = heading * Eigen::Vector3d(0, 1, 0);  // the wall's normal
  EXPECT_FALSE(paco::hasPerpendicularPlanes({slopes[0], slopes[1], along_the_ridge}, {2100, 2000, 10}));
  EXPECT_TRUE(paco::hasPerpendicularPlanes({slopes[0], slopes[1], ridge}, {2100, 2000, 10}));
  EXPECT_FALSE(paco::hasPerpendicularPlanes({slopes[0], slopes[1], ridge}, {2100, 2000, 0}));  // no weight
  EXPECT_THROW(paco::hasPerpendicularPlanes(slopes, {1.0}), paco::InvalidInputError);
  // The two slopes are 40 degrees apart; a slope and its own underside are parallel.
  EXPECT_TRUE(paco::hasPlanesAtAnAngle(slopes, sizes));
  EXPECT_FALSE(paco::hasPlanesAtAnAngle({slopes[0], -slopes[0]}, {2100, 50}));
  EXPECT_THROW(paco::hasPlanesAtAnAngle(slopes, {1.0}), paco::InvalidInputError);

  const Eigen::Matrix3d axes = paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, 5), slopes, sizes);
  EXPECT_TRUE(axes.col(0).isApprox(Eigen::Vector3d(0, 0, 1), 1e-12)) << axes;
  EXPECT_NEAR(std::abs(axes.col(1).dot(ridge)) + std::abs(axes.col(2).dot(ridge)), 1.0, 1e-12) << axes;
  EXPECT_TRUE((axes.transpose() * axes).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_NEAR(axes.determinant(), 1.0, 1e-12);
  // The direction's sign is kept.
  EXPECT_TRUE(paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, -1), slopes, sizes)
                  .col(0)
                  .isApprox(Eigen::Vector3d(0, 0, -1), 1e-12));
}

TEST(Orientation, AroundTheLinesOfSightWallsOutweighTheNoiseOfAFlatRoof) {
  // A flat roof whose fit is 1 degree off (its projection's direction is noise, and ignored) and
  // two small walls at 50 degrees to x.
  const Eigen::Matrix3d heading = turn(50.0, Eigen::Vector3d(0, 0, 1));
  const std::vector<Eigen::Vector3d> normals = {turn(1.0, Eigen::Vector3d(1, 1, 0)) * Eigen::Vector3d(0, 0, 1),
                                                heading * Eigen::Vector3d(1, 0, 0),
                                                heading * Eigen::Vector3d(0, 1, 0)};
  const Eigen::Matrix3d axes = paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, 1), normals, {5000, 20, 20});
  EXPECT_TRUE(axes.col(0).isApprox(Eigen::Vector3d(0, 0, 1), 1e-12));
  EXPECT_NEAR(std::abs(axes.col(1).dot(normals[1])), 1.0, 1e-12) << axes;
  // The flat roof alone says nothing across the lines of sight: the coordinate axes are taken.
  Eigen::Matrix3d vertical_x_y;
  vertical_x_y << 0, 1, 0, 0, 0, 1, 1, 0, 0;  // columns z, x, y
  const Eigen::Matrix3d roof_only = paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, 1), {normals[0]}, {5000});
  EXPECT_TRUE(roof_only.isApprox(vertical_x_y, 1e-12)) << roof_only;
  EXPECT_TRUE(paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, 1), {}, {}).isApprox(vertical_x_y, 1e-12));
}

namespace {
// True when one of the columns of `axes` is `direction` (a unit vector), either way.
bool hasAxis(const Eigen::Matrix3d& axes, const Eigen::Vector3d& direction) {
  return (axes.transpose() * direction).cwiseAbs().maxCoeff() > 1.0 - 1e-9;
}
}  // namespace

// The same gable roof without the lines of sight: its slopes are mirror images across the vertical
// plane through the ridge, and their bisectors are the vertical and across the ridge. A hip roof's
// four slopes, of different sizes and with one normal pointing inwards, give the same frame.
TEST(Orientation, MirrorImageSlopesGiveTheVerticalAndTheRidge) {
  const Eigen::Matrix3d heading = turn(30.0, Eigen::Vector3d(0, 0, 1));
  const Eigen::Vector3d ridge = heading * Eigen::Vector3d(1, 0, 0);
  const Eigen::Vector3d across = heading * Eigen::Vector3d(0, 1, 0);
  const Eigen::Vector3d up(0, 0, 1);
  const std::vector<Eigen::Vector3d> gable = {turn(20.0, ridge) * up, turn(-20.0, ridge) * up};
  const auto axes = paco::mirrorPlaneAxes(gable, {2100, 2000});
  ASSERT_TRUE(axes.has_value());
  EXPECT_TRUE(hasAxis(*axes, up)) << *axes;
  EXPECT_TRUE(hasAxis(*axes, ridge)) << *axes;
  EXPECT_TRUE((axes->transpose() * *axes).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_NEAR(axes->determinant(), 1.0, 1e-12);

  const std::vector<Eigen::Vector3d> hip = {turn(20.0, ridge) * up, -(turn(-20.0, ridge) * up),
                                            turn(35.0, across) * up, turn(-35.0, across) * up};
  const auto hip_axes = paco::mirrorPlaneAxes(hip, {2100, 2000, 700, 650});
  ASSERT_TRUE(hip_axes.has_value());
  EXPECT_TRUE(hasAxis(*hip_axes, up) && hasAxis(*hip_axes, ridge)) << *hip_axes;
}

// A large face and a small chamfer at 45 degrees are mirror images across their bisector too, but
// the frame belongs to the face: the chamfer's weight is all the pair brings. Two planes that are
// perpendicular leave the frame to dominantPlaneAxes.
TEST(Orientation, AChamferIsNoMirrorImageOfTheFaceItCuts) {
  const Eigen::Vector3d face(0, 0, 1);
  const Eigen::Vector3d chamfer = Eigen::Vector3d(0, 1, 1).normalized();
  EXPECT_FALSE(paco::mirrorPlaneAxes({face, chamfer}, {1000, 100}).has_value());
  // Equal in size, the two could be a roof's slopes.
  const auto equal = paco::mirrorPlaneAxes({face, chamfer}, {1000, 1000});
  ASSERT_TRUE(equal.has_value());
  EXPECT_TRUE(hasAxis(*equal, (face + chamfer).normalized())) << *equal;
  EXPECT_FALSE(paco::mirrorPlaneAxes({face, chamfer, Eigen::Vector3d(1, 0, 0)}, {1000, 1000, 10}).has_value());
  EXPECT_FALSE(paco::mirrorPlaneAxes({face, -face}, {1000, 1000}).has_value());  // parallel only
  EXPECT_FALSE(paco::mirrorPlaneAxes({}, {}).has_value());
  EXPECT_THROW(paco::mirrorPlaneAxes({face}, {}), paco::InvalidInputError);
}

// The box fill's axes, which the hidden-extent head takes too: a gable roof's come from its mirror
// image slopes, or from the lines of sight when the scanner's direction is known; planes with a
// perpendicular pair keep dominantPlaneAxes' frame.
TEST(Orientation, TheClosingBoxOfAGableRoofLiesOnItsBisectorsOrAroundTheLinesOfSight) {
  const Eigen::Matrix3d heading = turn(30.0, Eigen::Vector3d(0, 0, 1));
  const Eigen::Vector3d ridge = heading * Eigen::Vector3d(1, 0, 0);
  const Eigen::Vector3d up(0, 0, 1);
  const std::vector<Eigen::Vector3d> gable = {turn(20.0, ridge) * up, turn(-20.0, ridge) * up};
  const std::vector<double> sizes = {2100, 2000};

  const paco::ClosingBoxAxes mirrored = paco::closingBoxAxes(gable, sizes);
  ASSERT_TRUE(mirrored.axes.has_value());
  EXPECT_TRUE(mirrored.on_mirror_pair);
  EXPECT_FALSE(mirrored.on_one_plane);
  EXPECT_TRUE(hasAxis(*mirrored.axes, up) && hasAxis(*mirrored.axes, ridge)) << *mirrored.axes;

  const paco::ClosingBoxAxes seen_from_above = paco::closingBoxAxes(gable, sizes, Eigen::Vector3d(0, 0, 2));
  ASSERT_TRUE(seen_from_above.axes.has_value());
  EXPECT_FALSE(seen_from_above.on_mirror_pair || seen_from_above.on_one_plane);
  EXPECT_TRUE(seen_from_above.axes->col(0).isApprox(up, 1e-12)) << *seen_from_above.axes;

  // A slope and a small chamfer are no mirror pair: the largest plane's frame, flagged as a guess.
  const paco::ClosingBoxAxes one_plane = paco::closingBoxAxes({gable[0], gable[1]}, {2100, 100});
  ASSERT_TRUE(one_plane.axes.has_value());
  EXPECT_TRUE(one_plane.on_one_plane);
  EXPECT_TRUE(hasAxis(*one_plane.axes, gable[0])) << *one_plane.axes;

  // An end wall across the ridge is perpendicular to both slopes: dominantPlaneAxes' frame.
  const std::vector<Eigen::Vector3d> with_wall = {gable[0], gable[1], ridge};
  const std::vector<double> with_wall_sizes = {2100, 2000, 500};
  const paco::ClosingBoxAxes walled = paco::closingBoxAxes(with_wall, with_wall_sizes);
  ASSERT_TRUE(walled.axes.has_value());
  EXPECT_FALSE(walled.on_mirror_pair || walled.on_one_plane);
  EXPECT_TRUE(walled.axes->isApprox(*paco::dominantPlaneAxes(with_wall, with_wall_sizes), 1e-12));

  EXPECT_FALSE(paco::closingBoxAxes({}, {}).axes.has_value());
  EXPECT_THROW(paco::closingBoxAxes(gable, {1.0}), paco::InvalidInputError);
  EXPECT_THROW(paco::closingBoxAxes(gable, sizes, Eigen::Vector3d(0, std::nan(""), 1)), paco::InvalidInputError);
}

TEST(Orientation, AroundRejectsAZeroAxisAndMismatchedLists) {
  EXPECT_THROW(paco::dominantPlaneAxesAround(Eigen::Vector3d::Zero(), {}, {}), paco::InvalidInputError);
  EXPECT_THROW(paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, std::nan("")), {}, {}), paco::InvalidInputError);
  EXPECT_THROW(paco::dominantPlaneAxesAround(Eigen::Vector3d(0, 0, 1), {Eigen::Vector3d(1, 0, 0)}, {}),
               paco::InvalidInputError);
}
