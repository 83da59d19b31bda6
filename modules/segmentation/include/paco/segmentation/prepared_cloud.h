#pragma once
// What every segmentation backend works on: the finite input points, moved to a frame with the
// bounding box centred at the origin and a unit diagonal, each with a unit normal.
// Usage (inside a PlanarSegmenter subclass's performSegmentation):
//   const paco::PreparedCloud& in = prepared();           // in.points: normalised PointNormal cloud
//   const auto& knn = in.neighbours(20);                   // k nearest neighbours, self excluded
//   labels[i] = ...;                                       // one label per in.points point, or -1
#include <paco/common/normalization.h>
#include <paco/common/primitive.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

namespace paco {

/// The normalised working copy of a segmenter's input. Distances measured in this frame are
/// fractions of the input's bounding-box diagonal, so relative thresholds apply as they are.
struct PreparedCloud {
  /// Finite selected points (centre 0, diagonal 1) with unit normals; a point whose normal could
  /// not be estimated has a zero normal and curvature 1.
  pcl::PointCloud<pcl::PointNormal>::Ptr points{new pcl::PointCloud<pcl::PointNormal>};
  /// For each working point, its index in the user's input cloud.
  std::vector<int> source_indices;
  /// Input points at exactly the coordinates of an earlier one: (input index, working index of
  /// that earlier point). They are left out of the working cloud, since copies would fill every
  /// k-nearest neighbourhood and cut the neighbourhood graph into islands, and they share the
  /// earlier point's label.
  std::vector<std::pair<int, int>> repeats;
  /// User frame -> working frame.
  Normalization normalization;
  /// Size of the user's input cloud (labels of the result have this size).
  std::size_t input_size = 0;
  /// True when at least one normal was estimated rather than given.
  bool normals_estimated = false;
  /// For each working point, 1 when its normal was estimated rather than given.
  std::vector<char> estimated_normal;
  /// Neighbours the estimated normals were taken from: the segmenter's k, or twice it when the
  /// points are noisy for that k (median surface variation above 0.045); 0 when none was estimated.
  int normal_neighbours_used = 0;
  /// True when estimated normals were turned towards a viewpoint the user gave.
  bool oriented_towards_viewpoint = false;
  /// True when all points are collinear: no plane can be segmented.
  bool collinear = false;
  /// Kd-tree (FLANN) over `points`.
  pcl::search::KdTree<pcl::PointNormal>::Ptr tree;

  std::size_t size() const { return points->size(); }
  /// The k nearest neighbours of every point (self excluded, nearest first), computed once per k.
  const std::vector<std::vector<int>>& neighbours(int k) const;
  /// Mean distance of a point to its 6 nearest neighbours, averaged over the cloud (working frame).
  double averageSpacing() const;
  /// How far points scatter off their surface (working frame): for each point, the RMS distance
  /// of those of its k nearest neighbours and itself whose normals are within about 32 degrees
  /// of its own (at least 6, else the point is skipped) to their least-squares plane; the
  /// `quantile` of those over the cloud (on clouds above 10,000 points, every (n / 5,000)-th;
  /// 0 when no point is read). The normal test leaves the neighbours across an edge out (they
  /// made parts with many small faces read as noisy), and a low quantile reads the flat parts:
  /// on clean scans it is 0, on noisy ones near the noise's standard deviation. A neighbourhood
  /// whose distances to that plane fall into two layers, with a gap over four times their own
  /// spread, counts its spread within the layers: the two sides of a wall a few point spacings
  /// thin are not noise.
  double noiseLevel(int k, double quantile) const;

 private:
  mutable std::vector<std::vector<int>> neighbours_;
  mutable int neighbours_k_ = -1;
  mutable std::optional<double> average_spacing_;
};

namespace detail {

/// Options of PreparedCloud construction shared by every segmenter.
struct PrepareOptions {
  int normal_neighbours = 20;        ///< k of normal estimation
  unsigned int threads = 0;          ///< normal estimation threads (0: all cores)
  std::optional<Eigen::Vector3d> viewpoint;  ///< orient estimated normals towards it (user frame)
};

/// Builds the working cloud from points already gathered in the user frame (normals NaN or zero
/// when unknown; non-finite coordinates are dropped with one warning). Throws InvalidInputError
/// for fewer than 3 finite points or coincident points.
void prepareCloud(const pcl::PointCloud<pcl::PointNormal>& gathered, std::vector<int> source_indices,
                  std::size_t input_size, const PrepareOptions& options, PreparedCloud& prepared);

/// Turns per-working-point labels into the user's PlanarSegmentation: drops segments with fewer
/// than `min_points` points (at least 3) or no unique plane, fits every plane by least squares in
/// the working frame and maps it back to the user frame, orients it with the majority of its
/// point normals (or, when they were estimated, by orientEstimatedSegments), and sorts the
/// segments by decreasing size.
PlanarSegmentation finalizeSegmentation(const PreparedCloud& prepared, const std::vector<int>& labels,
                                        std::size_t min_points);

/// Orients the planes of segments whose normals were mostly estimated (working frame). An
/// estimated normal only knows its line; turning each away from the box centre gets the faces of
/// steps, notches and pockets wrong whenever they lie on the centre's far side. Instead:
/// - neighbouring segments are oriented consistently across the edge they share: at a convex edge
///   each one's points lie behind the other's plane, at a concave edge in front of it; adjacent
///   near-coplanar segments face alike (near-parallel ones with an offset tell nothing and are
///   skipped);
/// - the best-supported relations (most points near the edge that tell) join segments into
///   groups; one that would close a loop is left out;
/// - each group as a whole then faces like the given normals it holds; or else as rays from its
///   points say, when enough of them tell and agree (a ray leaving a closed surface outwards
///   crosses it an even number of times, inwards an odd number; on a partial scan most rays leave
///   through its holes and say nothing); or else away from the box centre by a majority of its
///   points, which the outer hull of a part dominates. The rays orient the inner faces of a
///   sheet-metal channel, which no shared edge ties to the hull and which face the centre.
/// Segments whose points mostly had given normals keep their orientation. `members` holds the
/// working points of each segment, `planes` their planes, oriented in place.
void orientEstimatedSegments(const PreparedCloud& prepared, const std::vector<std::vector<int>>& members,
                             std::vector<Plane>& planes);

/// Gives small planes a second chance: a face of a pocket or a step, seen by a handful of points,
/// is usually parallel to a large face. Segments of fewer than `min_points` points are freed
/// (label -1); then, for the direction of each remaining segment (parallel ones once, most
/// supported first), the free points whose normals agree with it (|cos| >= min_abs_cosine) are
/// sorted by their offset along it, and the 2 x `distance` wide window holding the most of them
/// becomes a new segment while it holds at least `min_parallel_points` points (>= 3) and its own
/// least-squares plane is parallel to the direction. On a `noisy_scan` (the segmenter widened its
/// inlier distance to the noise) a window that is a remaining segment's noise tail stays free:
/// within 4 times the RMS distance of that segment's points to its plane, on average, with 90 % of
/// its points within two point spacings of one of the segment's points (both projected onto its
/// plane); those are the points of a face that the inlier distance cut off. On other scans such a
/// window may be a bend of a face that is not quite flat (a milk carton's top), and is kept. Works
/// in the working frame on `labels` (one per working point); returns the number of segments added.
std::size_t recoverParallelPlanes(const PreparedCloud& prepared, std::vector<int>& labels, std::size_t min_points,
                                  std::size_t min_parallel_points, double distance, double min_abs_cosine,
                                  bool noisy_scan);

/// The indices of the points of each label 0..max (empty for unused labels; -1 left out).
std::vector<std::vector<int>> membersByLabel(const std::vector<int>& labels);

/// Least-squares plane of some working points (throws InvalidInputError when degenerate).
Plane fitPlane(const pcl::PointCloud<pcl::PointNormal>& points, const std::vector<int>& indices);

}  // namespace detail
}  // namespace paco
