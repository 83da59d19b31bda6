#pragma once
// Usage:
//   std::vector<paco::PlanarPrimitive> observed = paco::makePrimitives(*cloud, segmentation);
//   paco::ObservedFusionReport report;
//   primitives = paco::fuseWithObserved(std::move(primitives), observed, {}, &report);
//
// The network predicts every plane of the complete shape, the seen ones included, from a
// 2,048-point subsample and a fixed-size latent code; a plane fitted to the observed points of
// a segment is more accurate than its prediction. Fusion keeps the network for what was not
// seen and the observation for what was.
#include <paco/common/primitive.h>

#include <Eigen/Core>

#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace paco {

/// The finest box-fill grid fuseWithObserved accepts (ObservedFusionOptions::fill_spacing).
constexpr double kMinFillSpacing = 0.001;

struct ObservedFusionOptions {
  /// A completed primitive may take an observed segment's plane when their normals are within
  /// this angle (unoriented, degrees)...
  double max_angle_degrees = 10.0;
  /// ...and the observed points lie on average within this distance of the completed plane,
  /// as a fraction of the bounding-box diagonal of the observed points.
  double max_distance = 0.02;
  /// A later observed segment joins a completed primitive that already took another segment's
  /// plane only when its points lie on average within this distance of that plane (fraction of
  /// the observed points' diagonal). Below `max_distance`, a parallel seen face a little off that
  /// plane, such as a shallow step, takes another completed primitive or is added as it is,
  /// instead of lending its points to a plane they lie off. The default, equal to
  /// `max_distance`, joins every segment that matches: 0.005 kept more of the GT's planes on
  /// MFCAD validation parts but scored the same CD, HD and NC, and on a real roof scan it let
  /// PolyFit stretch the hidden side to three times the scan's width (doc/results.md).
  double join_distance = 0.02;
  /// Observed segments with fewer points are ignored (too few to trust their plane).
  std::size_t min_observed_points = 10;
  /// A completed primitive that took no seen plane is turned to be exactly parallel to a seen
  /// face, or to one of the dominant seen axes (paco::dominantPlaneAxes), when its normal is
  /// within this angle of it (degrees; about its points' centroid, points projected; 0 = off).
  /// Piecewise-planar objects repeat a few directions: an unseen face a few degrees off a seen
  /// direction is almost always the network's error, and slivers in the mesh follow from it.
  double align_unseen_degrees = 0.0;
  /// Completed points farther than this beyond the box of the observed points (a box on the
  /// dominant seen axes; fraction of the observed points' diagonal) are dropped, and so is an
  /// unseen primitive that loses more than half of its points (infinity = off). Most scans of a
  /// part span its extent along most axes, and a prediction far outside them is the network's
  /// error; a margin lets a part extend beyond what was seen.
  double clip_margin = std::numeric_limits<double>::infinity();
  /// When no two seen planes are perpendicular and no scanner is given (the box's axes are a
  /// guess: ObservedFusionReport::box_on_mirror_pair or box_on_one_plane), a seen face tilted
  /// against the box (more than `max_angle_degrees` off every box axis: a roof's slope) keeps the
  /// network's points only within this far (fraction of the observed points' diagonal) of the box
  /// along the axes it tilts towards; along an axis it lies parallel to it may run on, like any
  /// seen face (infinity = off). Nothing else bounds such a face: on an airborne scan of a gable
  /// roof the network ran the slopes 6 m below the eaves, and the cell complex closed a solid 58 m
  /// across over a 23 m roof.
  double tilt_margin = 0.02;
  /// Covers the faces of the observed points' box (on the dominant seen axes; a side that a seen
  /// face parallel to it lies on, within four times the RMS distance of its points to its plane,
  /// is that face's plane: noise carries a scan's outermost points that far off it) with a grid of
  /// points of this spacing (fraction of the box diagonal, at least kMinFillSpacing; 0 = off;
  /// at least four steps across a face), keeping those farther than `fill_empty_radius` (on a
  /// face narrower than four times that but wider than `max_distance`, a quarter of its width, so
  /// that the rim of a thin plate is not covered by the points of its two sides) from every
  /// fused point and outside the
  /// space the seen faces show empty (in front of a seen face, looking along a box axis: over a
  /// seen step, notch or chamfer the part's boundary is that surface, not the box face; a seen
  /// face's points are the scan's and the network's that the scan does not contradict). Each
  /// face's points join a fused primitive on (nearly) the face's plane, or become a new
  /// primitive (confidence 0.99). An unseen primitive that hosts them takes the face's plane
  /// and confidence 0.99 too.
  /// PolyFit closes an under-supported hidden side with too small a solid (median volume 0.51
  /// of the part's at 75 % missing); most scans of a part span its extent, and the box faces
  /// give that side an outer hull where the network put nothing (doc/results.md).
  /// When every fused plane is then parallel (within `max_angle_degrees`) to one box axis, none
  /// can close the ends along it: the primitives are the sides of a prism, such as a sheet-metal
  /// profile whose end faces are too thin for the segmenter or a building's walls scanned from
  /// the side. Both box faces across that axis are then added over the profile: the cells of a
  /// raster (1.5 seen-point spacings) that the fused points, projected along the axis, enclose.
  double fill_spacing = 0.02;
  double fill_empty_radius = 0.05;
  /// The network's points of a seen face that the scan contradicts are dropped (fraction of the
  /// observed points' diagonal; 0 = off). The network spreads its points over the whole plane it
  /// predicts; on a seen face they carry the face into its hidden part, but on a small face (a
  /// step, a slot's wall) most fall where the face is not, often right through the solid, and the
  /// assemblers then build faces there (on MFCAD validation parts at 25 % missing, half of those
  /// away from the face's seen points lie off the face; doc/results.md). A point is contradicted when
  ///  - an observed point lies within this distance but none of the face's own seen points does:
  ///    the scan saw that spot, and not this face there; or
  ///  - looking along the face's normal both ways, the first seen surface met within this
  ///    distance of the line on each side faces away from it: it lies inside the seen solid; or
  ///  - the spot 1.5 times this distance in front of it (on the side the scan saw the face from)
  ///    is in the seen solid: looking from there along a seen box axis that lies in the face's
  ///    plane, the first seen surface square to the line (within 25 degrees), within 6 times this
  ///    distance, faces away. A pocket's wall carried on past its seen ceiling goes; or
  ///  - the spot as far behind it (on the side where the face has solid) is in seen air: looking
  ///    from there along such an axis, the first seen surface met within the same reach faces
  ///    back at it. A top carried on over a seen slot's opening goes.
  /// Points the scan says nothing about stay.
  double contradiction_radius = 0.03;
  /// Unseen completed primitives keep this fraction of their points, evenly spaced (in (0, 1];
  /// 1 = all), but at least `unseen_min_points` (all when they have fewer). PolyFit weighs
  /// every point alike, and the network's points of an unseen face are a guess: at full weight
  /// its planes, often 20-40 degrees off the part's faces, carve the hidden side. Thinned, they
  /// stay candidates that close the solid where nothing else does, while seen faces and the box
  /// fill carry the hull (doc/results.md). Applied before the box fill, which sees only the
  /// points kept.
  double unseen_point_fraction = 0.25;
  /// The assemblers drop a primitive with fewer than 10 points: thinning must not.
  std::size_t unseen_min_points = 32;
  /// Points the object is known to reach, in the primitives' frame (default none). The box of
  /// the observed points (on the dominant seen axes) is grown to enclose them before its faces
  /// are filled and before the clip. A scan shows where the object ends on its seen side only;
  /// on the hidden side the fill closes it at the seen box, short of the object wherever the
  /// scan stopped early (with the GT's extent, MFCAD validation parts at 75 % missing score CD
  /// 4.03 instead of 4.73 with PolyFit; doc/results.md). When the extent is known from
  /// elsewhere (a building's footprint and height, a part's stock size, a detector's box), give
  /// that box's corners.
  std::vector<Eigen::Vector3d> known_extent_points;
  /// Where the scanner was, when known (at most one of the two; default: unknown, off).
  ///  - `scanner_direction`: the direction towards a distant scanner, whose lines of sight are
  ///    parallel (e.g. 0,0,1 for airborne LiDAR with Z up; any length but zero; zero = unknown);
  ///  - `scanner_position`: the scanner's position, its lines of sight through it (e.g. a depth
  ///    camera at the origin of its cloud).
  /// The scanner would have seen any surface in front of what it saw: a completed point whose
  /// line of sight passes no seen point within `scanner_cell` (outside the scan's silhouette), or
  /// that lies more than `scanner_cell` nearer to the scanner than every seen point near its line
  /// of sight, is dropped; an unseen primitive that loses more than half of its points goes with
  /// them. Seen points always stay, and so does the box fill, which closes the hull where nothing
  /// else does (tested too, it left the walls of roof scans without support and the assemblers
  /// built fragments). This bounds the hidden side across the lines of sight, where the network
  /// otherwise guesses: on a sparse roof scan it reached 2.6 times the building's width
  /// (doc/results.md). Only the segments' points count as seen, so a scan with much clutter that
  /// the segmenter left out may lose completed points there.
  /// A distant scanner's direction is also an axis of the box the fill closes
  /// (paco::dominantPlaneAxesAround): its walls run along the lines of sight and its far face
  /// across them, where the seen planes alone could tilt it onto a roof slope.
  Eigen::Vector3d scanner_direction = Eigen::Vector3d::Zero();
  std::optional<Eigen::Vector3d> scanner_position;
  /// Width of a line of sight for the test above, a fraction of the observed points' diagonal
  /// (> 0; at the seen points' median distance for a scanner position), and at least twice the
  /// seen points' median spacing: a gap in the scan up to twice this wide does not count as seen
  /// empty.
  double scanner_cell = 0.03;
};

struct ObservedFusionReport {
  std::size_t snapped = 0;  ///< completed primitives that took an observed plane
  std::size_t joined = 0;   ///< further observed segments on a snapped primitive's plane (join_distance) that joined it
  std::size_t absorbed = 0; ///< further completed primitives of a seen face, merged into the one that took it
  std::size_t added = 0;    ///< observed segments that matched no completed primitive, added as they are
  std::size_t ignored = 0;  ///< observed segments below min_observed_points
  /// Seen faces turned onto a seen box axis: off it by less than 4 standard errors of their
  /// fitted normal (from their points' scatter about the plane; at most max_angle_degrees), as on
  /// a noisy scan
  std::size_t squared = 0;
  std::size_t aligned = 0;  ///< unseen completed primitives turned parallel to a seen direction
  std::size_t clipped_points = 0;  ///< completed points dropped outside the observed box + margin
  std::size_t clipped = 0;         ///< unseen completed primitives dropped by the clip
  /// The network's points of seen faces tilted against the box (more than max_angle_degrees off
  /// every box axis), dropped past the box along the axes the face tilts towards (only when no
  /// two seen planes are perpendicular; ObservedFusionOptions::tilt_margin)
  std::size_t tilted_points = 0;
  std::size_t filled_points = 0;   ///< box-face points added where nothing covered the box
  std::size_t filled_faces = 0;    ///< box faces added as new primitives (the rest joined one)
  std::size_t box_faces_taken = 0; ///< unseen completed primitives that hosted box-face points and took the face's plane
  std::size_t fill_in_seen_free_space = 0;  ///< uncovered box-face points left out: the seen faces show them in empty space
  /// Points of the two box faces added across the one axis every fused plane was parallel to (the
  /// ends of a profile; see ObservedFusionOptions::fill_spacing)
  std::size_t profile_cap_points = 0;
  std::size_t thinned_points = 0;  ///< points of unseen completed primitives left out (unseen_point_fraction)
  std::size_t contradicted_points = 0;  ///< the network's points of seen faces the scan contradicts, dropped
  std::size_t seen_empty_points = 0;   ///< completed points the scanner would have seen, dropped (scanner_direction/position)
  std::size_t seen_empty = 0;          ///< unseen completed primitives dropped with them
  /// Seen planes meet at an angle but no two are perpendicular, and no scanner direction was given:
  /// the seen box lies on the largest seen plane and a coordinate axis (paco::dominantPlaneAxes),
  /// so where the fill closes the hidden side is a guess (a gable roof seen from above would get a
  /// box tilted onto one slope; ObservedFusionOptions::scanner_direction sets the box's axes
  /// instead). Parallel planes only (a plate seen on both sides) do not count.
  bool box_on_one_plane = false;
  /// The same case, but seen planes come in mirror-image pairs that outweigh the largest plane
  /// (a gable or hip roof's slopes): the box lies on their bisectors (paco::mirrorPlaneAxes),
  /// level under a symmetric roof. Still a guess without the scanner's direction.
  bool box_on_mirror_pair = false;
  /// A distant scanner's direction was given (ObservedFusionOptions::scanner_direction), and no
  /// trusted seen plane runs along its lines of sight (within max_angle_degrees: no wall seen, as
  /// on an airborne scan of a roof). The box then ends at the seen point farthest from the
  /// scanner (the lowest eave), so the hidden side closes there unless known_extent_points reach
  /// further (a point on the ground).
  bool no_seen_plane_along_sight = false;
  /// The seen box's axes (the columns, a rotation), in the primitives' frame: a known extent is
  /// enclosed by a box on these axes (known_extent_points).
  Eigen::Matrix3d box_axes = Eigen::Matrix3d::Identity();
};

/// One line for logs: "N primitives took a seen plane, N duplicates absorbed, N seen faces added"
/// (and ", N unseen aligned with seen directions" when alignment is on).
std::string describe(const ObservedFusionReport& report);

/// Fuses completed primitives (stage 3's output) with the observed ones (the input's segments,
/// same frame). Observed segments are taken largest first. Each is matched to the completed
/// primitive whose plane is nearest to its points within the tolerances; the first match
/// replaces that primitive's plane by the observed one (keeping the predicted orientation),
/// projects its predicted points onto it (dropping those the scan contradicts, see
/// `contradiction_radius`), adds the observed points and sets its confidence to 1
/// (the face was seen); later segments on that plane (within `join_distance`) add their points
/// to it, and parallel ones farther off cannot take it. A seen face off a seen box axis by less
/// than four standard errors of its fitted normal (at most `max_angle_degrees`) is turned onto it
/// (ObservedFusionReport::squared). Other completed
/// primitives within the tolerances of the same observed segment are duplicates: their points
/// are projected onto the chosen one and they are removed. Unmatched observed segments are
/// appended with confidence 1; unmatched completed primitives are kept, turned parallel to a seen
/// direction when `align_unseen_degrees` allows, clipped to the observed box when `clip_margin`
/// is finite, and thinned to `unseen_point_fraction` of their points; then the box faces are
/// filled when `fill_spacing` > 0, on the box grown to `known_extent_points` (and the ends of a
/// profile closed, when every plane is parallel to one box axis); with a scanner
/// direction or position, completed points the scanner would have seen go. Throws
/// InvalidInputError on tolerances that are negative or not finite (the margin may be infinite),
/// on a fraction outside (0, 1], on a known extent point that is not finite, and on a scanner
/// given both ways, not finite, or with a cell that is not positive.
std::vector<PlanarPrimitive> fuseWithObserved(std::vector<PlanarPrimitive> completed,
                                              const std::vector<PlanarPrimitive>& observed,
                                              const ObservedFusionOptions& options = {},
                                              ObservedFusionReport* report = nullptr);

}  // namespace paco
