#pragma once
// Thinning a dense scan to a working size before segmentation, and leaving out repeated points.
// Usage:
//   pcl::PointCloud<pcl::PointNormal> working;
//   const paco::ThinningReport r = paco::thinToPointBudget(*scan, 8192, working);
//   if (r.thinned()) std::printf("%zu -> %zu points\n", r.input_points, r.output_points);
#include <paco/common/primitive.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <functional>
#include <vector>

namespace paco {

/// The smallest point budget thinToPointBudget accepts: below it a part's smaller faces keep
/// too few points to be segmented at all.
constexpr std::size_t kMinPointBudget = 256;

/// The point budget paco_reconstruct, paco_complete and paco_eval thin scans to by default.
/// Above it a scan's seen faces outnumber the completed points and the box fill so much that
/// PolyFit often leaves the hidden side out, and a 250,000-point scan takes 20 s. Of budgets
/// 8,192, 20,000, 40,000, 100,000 and all, 20,000 did best or close to it on 40,000- and
/// 250,000-point MFCAD scans (doc/results.md, "Dense and repeated scans").
constexpr std::size_t kDefaultScanPointBudget = 20000;

/// What thinToPointBudget did.
struct ThinningReport {
  std::size_t input_points = 0;   ///< points of the input cloud (finite or not)
  std::size_t output_points = 0;  ///< points kept
  double voxel_size = 0.0;        ///< voxel edge in the cloud's units; 0 when nothing was thinned
  bool thinned() const { return output_points < input_points; }
};

/// Keeps at most `max_points` points of `input`, evenly spread: the input point nearest the
/// centre of each occupied voxel (pcl::UniformSampling), with the voxel edge searched so that
/// the count lands between 85 % and 100 % of the budget when it can.
///
/// Why: PolyFit weighs a scan's seen points against the completed ones and the box fill, and
/// the points of a dense scan outweigh them, so the hidden side is left out; every later stage
/// also takes time in proportion to the points. Kept points are input points as they are:
/// normals stay exact, where a voxel grid's centroids would average them across edges.
///
/// A cloud with at most `max_points` points is copied as it is, non-finite points included.
/// Otherwise non-finite points are left out. Throws InvalidInputError when `max_points` is
/// below kMinPointBudget or the input has no finite point. `input` and `output` may not be
/// the same object. Instantiated for pcl::PointXYZ and pcl::PointNormal.
template <typename PointT>
ThinningReport thinToPointBudget(const pcl::PointCloud<PointT>& input, std::size_t max_points,
                                 pcl::PointCloud<PointT>& output);

/// Labels every point of `cloud` from a segmentation of a thinned copy of it (`thinned`, for
/// example thinToPointBudget's output, labelled by `segmentation`): each point takes the label of
/// the nearest of its 8 nearest thinned points (FLANN) whose plane it lies within `max_distance`
/// of (in the cloud's units), else -1. With `nearest` given, it receives each point's nearest thinned
/// point (-1 for a non-finite point), e.g. to copy normals estimated on the thinned copy. Why:
/// segmenting 10 million points took minutes; one nearest-neighbour query per point takes
/// seconds. The points are searched on `threads` threads (0: OpenMP's default, all cores), in
/// chunks of 65,536; `on_progress`, when given, is called between chunks with the number of
/// points done (a progress bar; an interrupt can throw from it). Throws InvalidInputError when
/// `segmentation.labels` does not have one label per thinned point, a label names no plane, or
/// `thinned` has no finite point while `cloud` has one.
std::vector<int> labelsFromThinned(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                   const pcl::PointCloud<pcl::PointNormal>& thinned,
                                   const PlanarSegmentation& segmentation, double max_distance,
                                   std::vector<int>* nearest = nullptr,
                                   const std::function<void(std::size_t)>& on_progress = {},
                                   unsigned int threads = 0);

/// For each point, the index of the first point at exactly the same coordinates, or -1 when it
/// is the first there (non-finite points are never repeats). Repeats add no information, but a
/// scan merged with itself carries them, and they fill k-nearest neighbourhoods and outweigh the
/// completed points. Instantiated for pcl::PointXYZ and pcl::PointNormal.
template <typename PointT>
std::vector<int> findRepeatedPoints(const pcl::PointCloud<PointT>& cloud);

/// `input` without its repeated points (findRepeatedPoints), in input order; returns how many
/// were left out. `input` and `output` may not be the same object.
template <typename PointT>
std::size_t removeRepeatedPoints(const pcl::PointCloud<PointT>& input, pcl::PointCloud<PointT>& output);

/// Indices (ascending) of the stray points of a scan: small groups of points far from the rest,
/// such as a stray return metres away from a scanned part. Points are grouped when a chain of
/// points less than 5 % of the bounding-box diagonal apart joins them (pcl::EuclideanClusterExtraction
/// on a voxel grid, which may merge groups up to 2.7 times that apart but never splits one); a
/// group is stray when it holds at most 0.5 % of the points (at least 1) and every other point
/// lies farther from it than the bounding-box diagonal of the largest group. In all at most 0.5 %
/// of the points (at least 1) are stray: beyond that, and when no group holds most of the points,
/// the far points are a sparse scan's, not strays, and none is.
///
/// Why: the pipeline closes a mesh around everything it is given, so one stray point 40 times
/// the part's size away turns the part into a 40-unit tetrahedron; it also stretches the box
/// the scan is normalised by. A real piece of the object (a few points of a sparsely scanned
/// wall, ground returns below a roof edge) lies nearer the rest than its width, or holds more
/// points. Non-finite points are never stray.
/// Instantiated for pcl::PointXYZ and pcl::PointNormal.
template <typename PointT>
std::vector<int> findStrayPoints(const pcl::PointCloud<PointT>& cloud);

/// What prepareScanPoints did.
struct ScanPreparationReport {
  std::size_t repeats_removed = 0;  ///< points left out as repeats
  std::size_t strays_removed = 0;   ///< points left out as stray (findStrayPoints)
  ThinningReport thinning;          ///< of the points left after the repeats and strays
  bool changed() const { return repeats_removed > 0 || strays_removed > 0 || thinning.thinned(); }
};

/// A scan as the pipeline works on it (paco_reconstruct, paco_complete, paco_eval): `input`
/// without its repeated points (removeRepeatedPoints) and, when `remove_strays`, its stray
/// points (findStrayPoints), then thinned to `max_points` (thinToPointBudget) when more remain;
/// 0 keeps them all. `input` and `output` may not be the same object.
template <typename PointT>
ScanPreparationReport prepareScanPoints(const pcl::PointCloud<PointT>& input, std::size_t max_points,
                                        pcl::PointCloud<PointT>& output, bool remove_strays = true);

}  // namespace paco
