#pragma once
// Baseline: sequential RANSAC plane extraction with pcl::SACSegmentation.
// Usage:
//   paco::RansacSegmenter<pcl::PointNormal> seg;
//   seg.setInputCloud(cloud); seg.setMaxIterations(2000);
//   paco::PlanarSegmentation result; seg.segment(result);
#include <paco/segmentation/planar_segmenter.h>

namespace paco {

/// Repeatedly finds the plane with most points within ε (pcl::SACSegmentation, RANSAC, refined
/// by least squares), keeps its inliers whose normal agrees within τ, and removes them, until
/// the best plane has fewer than σ such points. Deterministic (fixed random seed).
template <typename PointT>
class RansacSegmenter : public PlanarSegmenter<PointT> {
 public:
  using Ptr = std::shared_ptr<RansacSegmenter<PointT>>;
  std::string name() const override { return "ransac"; }

  /// RANSAC iterations per extracted plane. Range >= 1; default 1000.
  void setMaxIterations(int iterations);
  int getMaxIterations() const { return max_iterations_; }
  /// Stop after this many planes. Range >= 1; default 1000.
  void setMaxPlanes(int planes);
  int getMaxPlanes() const { return max_planes_; }

 protected:
  void performSegmentation(std::vector<int>& labels) override;
  int max_iterations_ = 1000;
  int max_planes_ = 1000;
};

extern template class RansacSegmenter<pcl::PointXYZ>;
extern template class RansacSegmenter<pcl::PointNormal>;

}  // namespace paco
