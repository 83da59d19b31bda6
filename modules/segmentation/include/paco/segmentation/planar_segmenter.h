#pragma once
// Stage 1 of the pipeline: group a point cloud into planar segments.
// Usage:
//   auto seg = paco::makePlanarSegmenter<pcl::PointNormal>("gocopp");  // or "region-growing", ...
//   seg->setInputCloud(cloud); seg->setDistanceThreshold(0.004);      // fraction of bbox diagonal
//   paco::PlanarSegmentation result; seg->segment(result);             // labels, planes, segments
#include <paco/common/primitive.h>
#include <paco/common/scan_shares.h>
#include <paco/segmentation/prepared_cloud.h>

#include <pcl/pcl_base.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <cstddef>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace paco {

namespace detail {
/// `fraction` of `points`, rounded, and at least 3 (the fewest points of any plane).
inline int shareOfPoints(std::size_t points, double fraction) {
  const double share = fraction * static_cast<double>(points) + 0.5;
  return share < 3.0 ? 3 : static_cast<int>(share);
}

/// A parallel-plane minimum as the tools read --min-parallel-points: `requested` when > 0; 0
/// (off) when negative; `fraction` of `points` (shareOfPoints) when 0.
inline int parallelPlaneMinimum(std::size_t points, int requested, double fraction) {
  if (requested > 0) return requested;
  if (requested != 0) return 0;
  return shareOfPoints(points, fraction);
}
}  // namespace detail

/// kScanMinPlaneFraction of `points`, rounded, and at least 3: the tools' default
/// PlanarSegmenter::setMinPointsPerPlane for a cloud of that many points.
inline int scanMinPointsPerPlane(std::size_t points) { return detail::shareOfPoints(points, kScanMinPlaneFraction); }

/// The fewest points per plane the tools give the segmenter of a cloud of `points` points:
/// `requested` when it is > 0 (--min-points), else scanMinPointsPerPlane(points).
inline int scanMinPointsPerPlane(std::size_t points, int requested) {
  return requested > 0 ? requested : scanMinPointsPerPlane(points);
}

/// The fewest points per plane the tools give the segmenter of an exact scan
/// (PlanarSegmenter::setExactScanMinPointsPerPlane) of `points` points: `requested` when it is > 0
/// (--min-points holds on every scan), else kExactScanMinPlaneFraction of the points, rounded and
/// at least 3.
inline int exactScanMinPointsPerPlane(std::size_t points, int requested) {
  return requested > 0 ? requested : detail::shareOfPoints(points, kExactScanMinPlaneFraction);
}

/// The fewest points of a plane parallel to a larger one the tools give the segmenter of a cloud
/// of `points` points: `requested` when > 0; 0 (off) when negative; kScanMinParallelPlaneFraction of
/// the points, rounded and at least 3, when 0 (the tools' default).
inline int scanMinPointsPerParallelPlane(std::size_t points, int requested) {
  return detail::parallelPlaneMinimum(points, requested, kScanMinParallelPlaneFraction);
}

/// The noisy-scan counterpart of the one above
/// (PlanarSegmenter::setNoisyScanMinPointsPerParallelPlane): a requested count (> 0) holds on
/// every scan; 0 (off) when negative; otherwise kNoisyScanMinParallelPlaneFraction of the points,
/// rounded and at least 3.
inline int noisyScanMinPointsPerParallelPlane(std::size_t points, int requested) {
  return detail::parallelPlaneMinimum(points, requested, kNoisyScanMinParallelPlaneFraction);
}

/// The noise level PlanarSegmenter::setNoiseAdaptation reads: PreparedCloud::noiseLevel with
/// these neighbours and this quantile (on clean MFCAD scans 0; with noise of 1 % of the
/// diagonal about 0.8 % of it).
constexpr int kNoiseNeighbours = 20;
constexpr double kNoiseQuantile = 0.25;
/// The largest ε noise adaptation sets (fraction of the diagonal): beyond it a scan is noise more
/// than surface, and a wider ε would merge distinct faces.
constexpr double kMaxNoiseAdaptedDistance = 0.05;
/// The tools' noise adaptation (PlanarSegmenter::setNoiseAdaptation): ε is at least this many
/// times the noise level. 2.5 until the forty-eighth session, when the level stopped counting
/// neighbours across edges and read 7 to 16 % lower on noisy scans; 2.8 keeps their ε (the noisy
/// validation parts scored the same, the shipped sample CD 2.70 as before, 3.19 with 2.5).
constexpr double kScanNoiseMultiple = 2.8;
/// The noise level (fraction of the diagonal, as above) at or under which a scan is exact and
/// PlanarSegmenter::setExactScanMinPointsPerPlane applies. Samples of a CAD model measure 0 (the
/// points lie on their faces to float precision); the real scans in ../shared/data/scans measure
/// 1.8e-4 to 1.3e-3.
constexpr double kExactScanNoiseLevel = 2e-5;

/// Base of every planar segmentation backend, shaped like a PCL algorithm: setInputCloud,
/// setIndices, optional setInputNormals, parameter setters, then segment().
///
/// segment() validates the input, drops non-finite points (with one warning; they get label -1),
/// moves the points to a frame of unit bounding-box diagonal, estimates the normals that are
/// missing (k nearest neighbours, oriented away from the bounding-box centre or towards a
/// viewpoint) and calls the protected virtual performSegmentation(). It then fits every plane
/// by least squares on its inliers, in the user's frame and units.
///
/// To add a backend, derive from PlanarSegmenter<PointT>, implement performSegmentation() (label
/// the points of prepared()) and name(). Instantiated for pcl::PointXYZ and pcl::PointNormal; for
/// another point type include <paco/segmentation/impl/planar_segmenter.hpp>.
template <typename PointT>
class PlanarSegmenter : public pcl::PCLBase<PointT> {
 public:
  using Ptr = std::shared_ptr<PlanarSegmenter<PointT>>;
  using ConstPtr = std::shared_ptr<const PlanarSegmenter<PointT>>;
  using PointCloud = pcl::PointCloud<PointT>;
  using NormalCloud = pcl::PointCloud<pcl::Normal>;

  PlanarSegmenter() = default;
  ~PlanarSegmenter() override = default;

  /// The backend's name, as accepted by makePlanarSegmenter ("gocopp", "ransac", ...).
  virtual std::string name() const = 0;

  /// Normals for the input cloud (same size as it). Points whose normal here is finite and
  /// non-zero use it; the others get an estimated one. Pass nullptr to forget them.
  /// For pcl::PointNormal input without this call, the points' own normals are used likewise.
  void setInputNormals(const NormalCloud::ConstPtr& normals) { input_normals_ = normals; }
  NormalCloud::ConstPtr getInputNormals() const { return input_normals_; }

  /// ε, the largest point-to-plane distance of an inlier, as a fraction of the bounding-box
  /// diagonal of the (selected, finite) input. Range (0, 1); default 0.004.
  void setDistanceThreshold(double fraction_of_diagonal);
  double getDistanceThreshold() const { return distance_threshold_; }

  /// Noisy scans: ε grows to `multiple` × the scan's noise level when that is larger (the
  /// quarter quantile of the points' scatter off their 20-neighbour planes,
  /// PreparedCloud::noiseLevel). A face scattered over more than ε splits into many small
  /// planes, and the assembly then fails or carves slivers; on clean scans the level is about 0
  /// and ε stays as set. Range >= 0; default 0 (off); the tools use kScanNoiseMultiple.
  void setNoiseAdaptation(double multiple);
  double getNoiseAdaptation() const { return noise_multiple_; }

  /// The ε (fraction of the diagonal) the last segment() used: the distance threshold, or more
  /// on a noisy scan with noise adaptation on.
  double getUsedDistanceThreshold() const { return used_distance_threshold_; }

  /// τ, the smallest |cos| between a point's normal and its plane's normal for the point to join
  /// the plane. Range [0, 1]; default 0.85 (about 32°).
  void setNormalThreshold(double min_abs_cosine);
  double getNormalThreshold() const { return normal_threshold_; }

  /// σ, the fewest points a plane may have. Range >= 3; default 50.
  void setMinPointsPerPlane(int min_points);
  int getMinPointsPerPlane() const { return min_points_; }

  /// The fewest points of a plane on an exact scan, one whose noise level
  /// (PreparedCloud::noiseLevel, as noise adaptation reads it) is at most kExactScanNoiseLevel:
  /// segment() uses this where it is below getMinPointsPerPlane(). Without noise a few points
  /// that fit a plane with agreeing normals are a face (a small pocket's wall); with noise they
  /// are as likely a piece of the scatter. 0 (default, no change) or >= 3; the tools ask
  /// kExactScanMinPlaneFraction of the points.
  void setExactScanMinPointsPerPlane(int min_points);
  int getExactScanMinPointsPerPlane() const { return exact_min_points_; }

  /// The fewest points of a plane the last segment() used: getMinPointsPerPlane(), or on an
  /// exact scan the exact-scan minimum where smaller. Backends read this.
  int getUsedMinPointsPerPlane() const { return used_min_points_; }

  /// Smaller planes parallel to a plane found: after the backend, segments below
  /// getUsedMinPointsPerPlane() are freed, and the free points that lie on a plane parallel to a
  /// kept one (within the distance threshold, normals within 20 degrees) form a segment once
  /// there are this many (detail::recoverParallelPlanes). Pocket floors and step faces seen by
  /// a few points are nearly always parallel to a large face. On a noisy scan (noise adaptation
  /// widened ε), free points that are a kept face's noise (within 4 RMS of its plane and over its
  /// points) form no plane. 0 (default) turns it off; else >= 3; at or above
  /// getUsedMinPointsPerPlane() it changes nothing.
  void setMinPointsPerParallelPlane(int min_points);
  int getMinPointsPerParallelPlane() const { return min_parallel_points_; }

  /// The fewest points of a plane parallel to a larger one on a noisy scan: when noise adaptation
  /// widens ε, segment() uses this where it exceeds getMinPointsPerParallelPlane() (parallel
  /// planes stay off when that is off). Noise scatters a face's points off its plane, and a plane
  /// of a handful of them is a piece of the scatter. 0 (default, no change) or >= 3; the tools ask
  /// kNoisyScanMinParallelPlaneFraction of the points.
  void setNoisyScanMinPointsPerParallelPlane(int min_points);
  int getNoisyScanMinPointsPerParallelPlane() const { return noisy_min_parallel_points_; }

  /// The fewest points of a parallel plane (0: none) the last segment() used:
  /// getMinPointsPerParallelPlane(), or on a noisy scan the noisy-scan minimum where larger.
  int getUsedMinPointsPerParallelPlane() const { return used_min_parallel_points_; }

  /// k, the neighbours used to estimate normals and to grow regions. Range >= 3; default 20.
  void setNumberOfNeighbours(int k);
  int getNumberOfNeighbours() const { return neighbours_; }

  /// Threads for normal estimation (0: all cores). Default 0. The backends run on one thread.
  void setNumberOfThreads(unsigned int threads) { threads_ = threads; }
  unsigned int getNumberOfThreads() const { return threads_; }

  /// Orient estimated normals towards this viewpoint (user frame) instead of away from the
  /// bounding-box centre. Given normals are never flipped. A viewpoint inside the object (a room
  /// scanned from inside) makes the planes face into it, and the assemblers then take the room as
  /// outside: leave it unset there, or see paco/common/normal_sides.h for given normals.
  void setViewpoint(const Eigen::Vector3d& viewpoint) { viewpoint_ = viewpoint; }
  void clearViewpoint() { viewpoint_.reset(); }

  /// Segments the input. output.labels has one entry per input point (-1: no plane, also for
  /// points outside the indices or with non-finite coordinates); planes are in the input's frame
  /// and units, oriented like the majority of their points' normals; segments are sorted by
  /// decreasing size. Throws InvalidInputError when there is no input, an index is out of
  /// range, fewer than 3 finite points remain, or all points coincide. Collinear input gives
  /// an empty result (with a warning).
  void segment(PlanarSegmentation& output);

  /// The working cloud of the last segment() call (normalised frame, with normals).
  const PreparedCloud& prepared() const { return prepared_; }

 protected:
  /// Labels the points of prepared(): `labels` arrives with prepared().size() entries set to -1;
  /// set each to a segment number (any non-negative integers; they are renumbered) or leave -1.
  /// Thresholds in the working frame are the relative ones above, as they are; read ε and the
  /// plane minimum of this call from used_distance_threshold_ and used_min_points_ (a noisy scan
  /// widens the one, an exact scan lowers the other).
  virtual void performSegmentation(std::vector<int>& labels) = 0;

  using pcl::PCLBase<PointT>::input_;
  using pcl::PCLBase<PointT>::indices_;
  using pcl::PCLBase<PointT>::initCompute;
  using pcl::PCLBase<PointT>::deinitCompute;

  double distance_threshold_ = 0.004;
  double noise_multiple_ = 0.0;
  /// ε of the current segment() call, what the backends use (distance_threshold_ or, on a noisy
  /// scan with noise adaptation on, more).
  double used_distance_threshold_ = 0.004;
  double normal_threshold_ = 0.85;
  int min_points_ = 50;
  int exact_min_points_ = 0;
  /// The plane minimum of the current segment() call.
  int used_min_points_ = 50;
  int min_parallel_points_ = 0;
  int noisy_min_parallel_points_ = 0;
  /// The parallel-plane minimum of the current segment() call.
  int used_min_parallel_points_ = 0;
  int neighbours_ = 20;
  unsigned int threads_ = 0;
  std::optional<Eigen::Vector3d> viewpoint_;
  NormalCloud::ConstPtr input_normals_;
  PreparedCloud prepared_;

 private:
  void gatherInput(pcl::PointCloud<pcl::PointNormal>& gathered, std::vector<int>& source_indices) const;
};

/// The names of the built-in backends, default first: gocopp, region-growing, ransac and, when
/// paco was built with CGAL, efficient-ransac.
std::vector<std::string> availablePlanarSegmenters();

/// The tools' plane minimums for a cloud of `points` points: setMinPointsPerPlane(
/// scanMinPointsPerPlane(points, min_points)), setExactScanMinPointsPerPlane(
/// exactScanMinPointsPerPlane(points, min_points)) and setMinPointsPerParallelPlane(
/// scanMinPointsPerParallelPlane(points, min_parallel_points)); part of setScanDefaults.
template <typename PointT>
void setScanMinimums(PlanarSegmenter<PointT>& segmenter, std::size_t points, int min_points, int min_parallel_points) {
  segmenter.setMinPointsPerPlane(scanMinPointsPerPlane(points, min_points));
  segmenter.setExactScanMinPointsPerPlane(exactScanMinPointsPerPlane(points, min_points));
  segmenter.setMinPointsPerParallelPlane(scanMinPointsPerParallelPlane(points, min_parallel_points));
  segmenter.setNoisyScanMinPointsPerParallelPlane(noisyScanMinPointsPerParallelPlane(points, min_parallel_points));
}

/// The tools' segmentation settings for a cloud of `points` points: setScanMinimums and noise
/// adaptation (setNoiseAdaptation(noise_multiple); --noise-adaptation, 0 turns it off).
/// paco_reconstruct, paco_complete, paco_eval and the data set's input labels all segment this way.
template <typename PointT>
void setScanDefaults(PlanarSegmenter<PointT>& segmenter, std::size_t points, int min_points, int min_parallel_points,
                     double noise_multiple = kScanNoiseMultiple) {
  setScanMinimums(segmenter, points, min_points, min_parallel_points);
  segmenter.setNoiseAdaptation(noise_multiple);
}

/// A built-in backend by name (see availablePlanarSegmenters()). Throws InvalidInputError for an
/// unknown name, listing the known ones.
template <typename PointT>
typename PlanarSegmenter<PointT>::Ptr makePlanarSegmenter(const std::string& name = "gocopp");

extern template class PlanarSegmenter<pcl::PointXYZ>;
extern template class PlanarSegmenter<pcl::PointNormal>;
extern template PlanarSegmenter<pcl::PointXYZ>::Ptr makePlanarSegmenter<pcl::PointXYZ>(const std::string&);
extern template PlanarSegmenter<pcl::PointNormal>::Ptr makePlanarSegmenter<pcl::PointNormal>(const std::string&);

}  // namespace paco
