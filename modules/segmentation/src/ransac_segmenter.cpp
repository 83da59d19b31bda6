#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/segmentation/ransac_segmenter.h>

#include <pcl/ModelCoefficients.h>
#include <pcl/console/print.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <cmath>
#include <string>

namespace paco {

template <typename PointT>
void RansacSegmenter<PointT>::setMaxIterations(int iterations) {
  if (iterations < 1)
    throw InvalidInputError("RansacSegmenter::setMaxIterations: needs >= 1; got " + std::to_string(iterations));
  max_iterations_ = iterations;
}

template <typename PointT>
void RansacSegmenter<PointT>::setMaxPlanes(int planes) {
  if (planes < 1) throw InvalidInputError("RansacSegmenter::setMaxPlanes: needs >= 1; got " + std::to_string(planes));
  max_planes_ = planes;
}

template <typename PointT>
void RansacSegmenter<PointT>::performSegmentation(std::vector<int>& labels) {
  const auto& prepared = this->prepared_;
  const auto& points = *prepared.points;
  pcl::IndicesPtr remaining(new pcl::Indices(points.size()));
  for (std::size_t i = 0; i < points.size(); ++i) (*remaining)[i] = static_cast<pcl::index_t>(i);
  const auto min_points = static_cast<std::size_t>(this->used_min_points_);

  pcl::SACSegmentation<pcl::PointNormal> sac(false);  // fixed seed: repeatable
  sac.setModelType(pcl::SACMODEL_PLANE);
  sac.setMethodType(pcl::SAC_RANSAC);
  sac.setDistanceThreshold(this->used_distance_threshold_);
  sac.setMaxIterations(max_iterations_);
  sac.setOptimizeCoefficients(true);
  sac.setInputCloud(prepared.points);

  int planes = 0;
  while (remaining->size() >= min_points && planes < max_planes_ && !interruptRequested()) {
    sac.setIndices(remaining);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    {
      // PCL logs every degenerate 3-point sample as an error; on CAD data they are routine.
      const auto verbosity = pcl::console::getVerbosityLevel();
      pcl::console::setVerbosityLevel(pcl::console::L_ALWAYS);
      sac.segment(inliers, coefficients);
      pcl::console::setVerbosityLevel(verbosity);
    }
    if (inliers.indices.size() < min_points || coefficients.values.size() != 4) break;
    Eigen::Vector3f normal(coefficients.values[0], coefficients.values[1], coefficients.values[2]);
    if (!(normal.norm() > 0.0f)) break;
    normal.normalize();
    // Points of other faces cross the plane within ε: keep those whose normal agrees.
    std::vector<char> taken(points.size(), 0);
    std::size_t kept = 0;
    for (const auto i : inliers.indices) {
      const Eigen::Vector3f n = points[static_cast<std::size_t>(i)].getNormalVector3fMap();
      if (n.squaredNorm() > 0.5f && std::abs(n.dot(normal)) < this->normal_threshold_) continue;
      taken[static_cast<std::size_t>(i)] = 1;
      ++kept;
    }
    if (kept < min_points) break;
    pcl::IndicesPtr rest(new pcl::Indices);
    rest->reserve(remaining->size() - kept);
    for (const auto i : *remaining) {
      if (taken[static_cast<std::size_t>(i)])
        labels[static_cast<std::size_t>(i)] = planes;
      else
        rest->push_back(i);
    }
    remaining = rest;
    ++planes;
  }
}

template class RansacSegmenter<pcl::PointXYZ>;
template class RansacSegmenter<pcl::PointNormal>;

}  // namespace paco
