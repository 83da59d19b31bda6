#pragma once
// Usage:
//   std::vector<Eigen::Vector3d> normals = ...;  // one per seen planar segment
//   std::vector<double> sizes = ...;             // its number of points
//   Eigen::Matrix3d turn = paco::seenPlanesRotation(normals, sizes);
//   auto frame = paco::Normalization::fromBoundingBox(cloud, turn);
//
// Piecewise-planar objects (CAD parts, buildings, rooms) are built around a few orthogonal
// directions. Turning a scan so that its dominant seen faces lie on the coordinate axes gives
// the network one orientation to learn instead of all of them, whatever the scan's frame.
#include <paco/common/primitive.h>

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace paco {

/// Orthonormal axes (the columns, a proper rotation) of the dominant planes. Each pair of planes
/// within `tolerance_degrees` of perpendicular spans a frame: the heavier one's normal, the other
/// made exactly perpendicular, their cross product. The frame with the largest support wins; on
/// ties, the pair of heavier planes. A plane within the tolerance of an axis supports the frame by
/// the square root of its weight times its closeness (1 on the axis, 0 at the tolerance). One more
/// frame competes (and is the only one when no two planes are perpendicular): the largest
/// plane's normal and the coordinate axis least aligned with it, made perpendicular. Normals need
/// not be unit or consistently oriented; planes with a zero or non-finite normal or a weight <= 0
/// are ignored. Empty when no plane counts.
std::optional<Eigen::Matrix3d> dominantPlaneAxes(const std::vector<Eigen::Vector3d>& normals,
                                                 const std::vector<double>& weights,
                                                 double tolerance_degrees = 10.0);

/// True when two of the planes (zero, non-finite or non-positive weights ignored, the 64 heaviest
/// only, as dominantPlaneAxes) are within `tolerance_degrees` of perpendicular: without such a
/// pair, dominantPlaneAxes falls back to the largest plane and a coordinate axis.
bool hasPerpendicularPlanes(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights,
                            double tolerance_degrees = 10.0);

/// True when two of the planes (zero, non-finite or non-positive weights ignored; all of them) are
/// more than `tolerance_degrees` from parallel: without such a pair every plane is parallel to the
/// largest, and the first axis of dominantPlaneAxes is sure.
bool hasPlanesAtAnAngle(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights,
                        double tolerance_degrees = 10.0);

/// Orthonormal axes (the columns, a proper rotation) from the mirror symmetry of planes that meet
/// at angles but never at right angles, where dominantPlaneAxes falls back to the largest plane:
/// a gable or hip roof seen from above, whose slopes are mirror images of each other across the
/// vertical plane through the ridge. Each pair of the 64 heaviest planes more than
/// `tolerance_degrees` from parallel spans the frame of its bisectors: the normalised sum and
/// difference of the two unit normals, and their cross product (for a roof's two slopes: up, across
/// the ridge, along it). A plane supports a frame as in dominantPlaneAxes when it lies near one of
/// its axes, and also when its mirror image across one of the frame's planes lies within the
/// tolerance of another plane: then by the square root of the smaller of the two weights times
/// the closeness, so that a small chamfer does not tilt the frame off the large face it cuts. The
/// pair's frame with the most support is returned when it carries more than the largest plane's
/// frame (dominantPlaneAxes' fallback), weighed the same way; empty otherwise, and when two of the
/// planes are perpendicular (dominantPlaneAxes then has a frame of its own). Throws
/// InvalidInputError when the lists differ in length.
std::optional<Eigen::Matrix3d> mirrorPlaneAxes(const std::vector<Eigen::Vector3d>& normals,
                                               const std::vector<double>& weights, double tolerance_degrees = 10.0);

/// Orthonormal axes (the columns, a proper rotation) whose first column is `axis` (normalised, any
/// length but zero) and whose other two follow the planes: each normal is projected perpendicular
/// to `axis`, weighted by its weight times the projection's length (a plane nearly perpendicular
/// to `axis` says little about the other two directions), and the two are chosen among those
/// projections as dominantPlaneAxes chooses. Projections shorter than sin 2 degrees are ignored:
/// their direction is noise. Without any, the coordinate axis least aligned with `axis` is the
/// second. For a distant scanner whose lines of sight run along `axis`: a gable roof seen from
/// above has no two perpendicular planes, and dominantPlaneAxes would tilt the frame onto one of its
/// slopes. Throws InvalidInputError when the lists differ in length or `axis` is zero or not finite.
Eigen::Matrix3d dominantPlaneAxesAround(const Eigen::Vector3d& axis, const std::vector<Eigen::Vector3d>& normals,
                                        const std::vector<double>& weights, double tolerance_degrees = 10.0);

/// The axes of the box that closes a scan's hidden side, and how they were found.
struct ClosingBoxAxes {
  std::optional<Eigen::Matrix3d> axes;  ///< empty when no plane counts
  /// No scanner direction, planes at an angle but none perpendicular: the axes are a guess, from
  /// mirror-image planes (a roof's slopes) or else from the largest plane.
  bool on_mirror_pair = false;
  bool on_one_plane = false;
};

/// The box fill's axes for seen planes (ObservedFusion; the hidden-extent head takes the same, so
/// that its box and the fill's are one box). With a distant scanner's direction (non-zero),
/// dominantPlaneAxesAround it: the box's walls run along the lines of sight. Otherwise
/// dominantPlaneAxes, except when planes meet at an angle and no two are perpendicular (a gable
/// roof): then mirrorPlaneAxes when it finds a frame, the largest plane's frame when not. Throws
/// InvalidInputError when the lists differ in length or the direction is not finite.
ClosingBoxAxes closingBoxAxes(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights,
                              const Eigen::Vector3d& scanner_direction = Eigen::Vector3d::Zero());

/// Of the 24 rotations that take the columns of `axes` (a proper rotation) onto the coordinate
/// axes, up to order and sign, the one closest to the identity (largest trace): a scan whose
/// dominant faces are already axis-aligned is left as it is.
Eigen::Matrix3d rotationOntoAxesClosestToIdentity(const Eigen::Matrix3d& axes);

/// rotationOntoAxesClosestToIdentity(dominantPlaneAxes(...)), or the identity when no plane
/// counts. Throws InvalidInputError when the two lists differ in length.
Eigen::Matrix3d seenPlanesRotation(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights);

/// The same for a segmentation: each segment's plane normal weighted by its number of points (the
/// turn PlaneProxyEncoder gives a "seen-planes" model; the hidden-extent head takes the box fill's
/// axes instead, paco::closingBoxRotation).
Eigen::Matrix3d seenPlanesRotation(const PlanarSegmentation& segmentation);

}  // namespace paco
