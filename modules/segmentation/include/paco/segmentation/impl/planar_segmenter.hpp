#pragma once
// Template definitions of PlanarSegmenter. Only needed for point types other than pcl::PointXYZ
// and pcl::PointNormal, which libpaco_segmentation instantiates already.
#include <paco/common/error.h>
#include <paco/segmentation/planar_segmenter.h>

#include <pcl/common/point_tests.h>
#include <pcl/type_traits.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace paco {

namespace detail {
// The check of the plane-count setters whose 0 means `zero_means` ("off", "no change"): else a
// count needs at least 3 points, the fewest of a plane.
inline void checkOptionalPlaneCount(const std::string& setter, const std::string& zero_means, int min_points) {
  if (min_points != 0 && min_points < 3)
    throw InvalidInputError("PlanarSegmenter::" + setter + ": 0 (" + zero_means + ") or at least 3 points; got " +
                            std::to_string(min_points));
}
}  // namespace detail

template <typename PointT>
void PlanarSegmenter<PointT>::setDistanceThreshold(double fraction_of_diagonal) {
  if (!(fraction_of_diagonal > 0.0 && fraction_of_diagonal < 1.0))
    throw InvalidInputError("PlanarSegmenter::setDistanceThreshold: the distance threshold is a "
                            "fraction of the bounding-box diagonal in (0, 1); got " +
                            std::to_string(fraction_of_diagonal));
  distance_threshold_ = fraction_of_diagonal;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setNoiseAdaptation(double multiple) {
  if (!(multiple >= 0.0 && std::isfinite(multiple)))
    throw InvalidInputError("PlanarSegmenter::setNoiseAdaptation: the multiple of the noise level must be finite "
                            "and >= 0 (0: off); got " + std::to_string(multiple));
  noise_multiple_ = multiple;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setNormalThreshold(double min_abs_cosine) {
  if (!(min_abs_cosine >= 0.0 && min_abs_cosine <= 1.0))
    throw InvalidInputError("PlanarSegmenter::setNormalThreshold: the normal threshold is a |cosine| "
                            "in [0, 1]; got " + std::to_string(min_abs_cosine));
  normal_threshold_ = min_abs_cosine;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setMinPointsPerPlane(int min_points) {
  if (min_points < 3)
    throw InvalidInputError("PlanarSegmenter::setMinPointsPerPlane: a plane needs at least 3 points; got " +
                            std::to_string(min_points));
  min_points_ = min_points;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setExactScanMinPointsPerPlane(int min_points) {
  detail::checkOptionalPlaneCount("setExactScanMinPointsPerPlane", "no change", min_points);
  exact_min_points_ = min_points;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setMinPointsPerParallelPlane(int min_points) {
  detail::checkOptionalPlaneCount("setMinPointsPerParallelPlane", "off", min_points);
  min_parallel_points_ = min_points;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setNoisyScanMinPointsPerParallelPlane(int min_points) {
  detail::checkOptionalPlaneCount("setNoisyScanMinPointsPerParallelPlane", "no change", min_points);
  noisy_min_parallel_points_ = min_points;
}

template <typename PointT>
void PlanarSegmenter<PointT>::setNumberOfNeighbours(int k) {
  if (k < 3)
    throw InvalidInputError("PlanarSegmenter::setNumberOfNeighbours: k must be at least 3; got " +
                            std::to_string(k));
  neighbours_ = k;
}

template <typename PointT>
void PlanarSegmenter<PointT>::gatherInput(pcl::PointCloud<pcl::PointNormal>& gathered,
                                          std::vector<int>& source_indices) const {
  const auto& cloud = *input_;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  gathered.clear();
  gathered.reserve(indices_->size());
  source_indices.clear();
  source_indices.reserve(indices_->size());
  for (const auto index : *indices_) {
    if (index < 0 || static_cast<std::size_t>(index) >= cloud.size())
      throw InvalidInputError("PlanarSegmenter: index " + std::to_string(index) +
                              " is outside the input cloud of " + std::to_string(cloud.size()) +
                              " points; check setIndices()");
    const PointT& p = cloud[static_cast<std::size_t>(index)];
    pcl::PointNormal q;
    q.x = p.x;
    q.y = p.y;
    q.z = p.z;
    q.normal_x = q.normal_y = q.normal_z = nan;
    q.curvature = 0.0f;
    if (input_normals_) {
      const pcl::Normal& n = (*input_normals_)[static_cast<std::size_t>(index)];
      q.normal_x = n.normal_x;
      q.normal_y = n.normal_y;
      q.normal_z = n.normal_z;
      q.curvature = std::isfinite(n.curvature) ? n.curvature : 0.0f;
    } else if constexpr (pcl::traits::has_normal_v<PointT>) {
      q.normal_x = p.normal_x;
      q.normal_y = p.normal_y;
      q.normal_z = p.normal_z;
    }
    gathered.push_back(q);
    source_indices.push_back(static_cast<int>(index));
  }
}

template <typename PointT>
void PlanarSegmenter<PointT>::segment(PlanarSegmentation& output) {
  output = PlanarSegmentation{};
  if (!input_)
    throw InvalidInputError("PlanarSegmenter(" + name() +
                            "): no input cloud; call setInputCloud() before segment()");
  if (!initCompute())
    throw InvalidInputError("PlanarSegmenter(" + name() + "): the input could not be prepared");
  try {
    if (input_normals_ && input_normals_->size() != input_->size())
      throw InvalidInputError("PlanarSegmenter(" + name() + "): setInputNormals() gave " +
                              std::to_string(input_normals_->size()) + " normals for " +
                              std::to_string(input_->size()) + " points; give one per point");
    pcl::PointCloud<pcl::PointNormal> gathered;
    std::vector<int> source_indices;
    gatherInput(gathered, source_indices);
    detail::PrepareOptions options;
    options.normal_neighbours = neighbours_;
    options.threads = threads_;
    options.viewpoint = viewpoint_;
    prepared_ = PreparedCloud{};
    detail::prepareCloud(gathered, std::move(source_indices), input_->size(), options, prepared_);
    // Adaptation only widens ε, and never beyond kMaxNoiseAdaptedDistance (a wider ε set by the
    // user stays).
    used_distance_threshold_ = distance_threshold_;
    used_min_points_ = min_points_;
    const bool exact_minimum_applies = exact_min_points_ > 0 && exact_min_points_ < min_points_;
    if ((noise_multiple_ > 0.0 || exact_minimum_applies) && !prepared_.collinear) {
      const double noise_level = prepared_.noiseLevel(kNoiseNeighbours, kNoiseQuantile);
      if (noise_multiple_ > 0.0)
        used_distance_threshold_ =
            std::max(distance_threshold_, std::min(kMaxNoiseAdaptedDistance, noise_multiple_ * noise_level));
      if (exact_minimum_applies && noise_level <= kExactScanNoiseLevel) used_min_points_ = exact_min_points_;
    }
    // A widened ε means a noisy scan: the noisy-scan parallel minimum applies where larger.
    used_min_parallel_points_ = min_parallel_points_;
    if (used_distance_threshold_ > distance_threshold_ && min_parallel_points_ > 0)
      used_min_parallel_points_ = std::max(min_parallel_points_, noisy_min_parallel_points_);
    std::vector<int> labels(prepared_.size(), -1);
    if (!prepared_.collinear) performSegmentation(labels);
    if (labels.size() != prepared_.size())
      throw Error("PlanarSegmenter(" + name() + "): the backend returned " + std::to_string(labels.size()) +
                  " labels for " + std::to_string(prepared_.size()) + " points");
    std::size_t smallest = static_cast<std::size_t>(used_min_points_);
    if (used_min_parallel_points_ > 0 && used_min_parallel_points_ < used_min_points_ && !prepared_.collinear) {
      // Within 20 degrees: stricter than a backend's own threshold, since a handful of points
      // has no neighbourhood to vouch for it.
      const double min_abs_cosine = std::max(normal_threshold_, 0.94);
      detail::recoverParallelPlanes(prepared_, labels, smallest, static_cast<std::size_t>(used_min_parallel_points_),
                                    used_distance_threshold_, min_abs_cosine,
                                    used_distance_threshold_ > distance_threshold_);
      smallest = static_cast<std::size_t>(used_min_parallel_points_);
    }
    output = detail::finalizeSegmentation(prepared_, labels, smallest);
  } catch (...) {
    deinitCompute();
    throw;
  }
  deinitCompute();
}

}  // namespace paco
