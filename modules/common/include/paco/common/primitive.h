#pragma once
// Usage:
//   paco::PlanarSegmentation seg;                     // filled by paco::PlanarSegmenter
//   auto primitives = paco::makePrimitives(*cloud, seg);  // one PlanarPrimitive per segment
//   for (const auto& p : primitives) std::cout << p.plane.normal.transpose() << " " << p.points.size();
#include <paco/common/plane.h>

#include <pcl/PointIndices.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <vector>

namespace paco {

/// The confidence of a face that the observation implies without showing it (the observed
/// fusion's faces of the seen box): above every network guess, below an observed face (1).
/// PolyFit's candidate-face budget, which leaves out the least confident first, keeps them longer
/// than any guess.
constexpr float kImpliedFaceConfidence = 0.99f;

/// A planar primitive: a plane, the inlier points on it (with normals) and a confidence.
struct PlanarPrimitive {
  Plane plane;
  pcl::PointCloud<pcl::PointNormal> points;  ///< inliers, in the same frame as the plane
  float confidence = 1.0f;                    ///< in [0, 1]; 1 for segments of an observed cloud
};

/// The result of planar segmentation of a cloud of N points.
struct PlanarSegmentation {
  std::vector<int> labels;                      ///< N entries: segment index, or -1 for none
  std::vector<Plane> planes;                    ///< one plane per segment
  std::vector<pcl::PointIndices> segments;      ///< the point indices of each segment

  std::size_t size() const { return planes.size(); }
  bool empty() const { return planes.empty(); }
  /// Fraction of the N points that belong to a segment (0 for an empty cloud).
  double coverage() const;
  /// The number of points labelled with each segment (one entry per plane; labels out of range
  /// are ignored).
  std::vector<std::size_t> pointsPerSegment() const;
  /// Rebuilds `segments` from `labels` (labels must be -1 or < planes.size()).
  void rebuildSegmentsFromLabels();
  /// Rebuilds `labels` for `num_points` points from `segments`.
  void rebuildLabelsFromSegments(std::size_t num_points);
  /// Throws InvalidInputError when labels, planes and segments disagree.
  void validate(std::size_t num_points) const;

  /// The segmentation that stored per-point labels describe (a dataset's input labels): one
  /// segment per label >= 0, in increasing label order, with the plane fitted to its points and
  /// oriented by their summed normals. A label with fewer than 3 points or collinear points gets
  /// no segment; its points get -1. Throws InvalidInputError when the sizes differ.
  static PlanarSegmentation fromLabels(const pcl::PointCloud<pcl::PointNormal>& cloud, const std::vector<int>& labels);
};

/// One primitive per segment: its plane and its points. Points without normals get the plane's.
std::vector<PlanarPrimitive> makePrimitives(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                            const PlanarSegmentation& segmentation);
std::vector<PlanarPrimitive> makePrimitives(const pcl::PointCloud<pcl::PointXYZ>& cloud,
                                            const PlanarSegmentation& segmentation);

/// Root mean square distance of the points to `plane` (0 without points): the scatter of a face's
/// points about its fitted plane, its noise. The second form reads the points `indices` names.
double rmsDistance(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& plane);
double rmsDistance(const pcl::PointCloud<pcl::PointNormal>& points, const std::vector<int>& indices,
                   const Plane& plane);

/// All inliers of all primitives as one cloud, with a label per point (the primitive index).
void flattenPrimitives(const std::vector<PlanarPrimitive>& primitives,
                       pcl::PointCloud<pcl::PointNormal>& cloud, std::vector<int>& labels);

}  // namespace paco
