#pragma once
// Baseline: CGAL's Efficient RANSAC (Schnabel et al. 2007), planes only. CGAL stays inside
// libpaco_segmentation: this header does not include it.
// Usage:
//   paco::EfficientRansacSegmenter<pcl::PointNormal> seg;  // needs paco built with CGAL
//   seg.setInputCloud(cloud); seg.setProbability(0.01);
//   paco::PlanarSegmentation result; seg.segment(result);
#include <paco/segmentation/planar_segmenter.h>

#include <cstdint>

namespace paco {

/// CGAL::Shape_detection::Efficient_RANSAC with a plane factory only: ε as the distance
/// threshold, τ as the normal threshold, σ as the minimum plane size. segment() throws
/// paco::Error when paco was built without CGAL (see efficientRansacAvailable()).
template <typename PointT>
class EfficientRansacSegmenter : public PlanarSegmenter<PointT> {
 public:
  using Ptr = std::shared_ptr<EfficientRansacSegmenter<PointT>>;
  std::string name() const override { return "efficient-ransac"; }

  /// Probability to miss the largest candidate shape (lower: slower, more reliable). Range
  /// (0, 1); default 0.01.
  void setProbability(double probability);
  double getProbability() const { return probability_; }
  /// Largest gap between neighbouring points of one plane, as a fraction of the bounding-box
  /// diagonal; 0 chooses 3 × the mean point spacing. Range >= 0; default 0.
  void setClusterEpsilon(double fraction_of_diagonal);
  double getClusterEpsilon() const { return cluster_epsilon_; }
  /// Seed of CGAL's random generator, for repeatable results. Default 0.
  void setSeed(std::uint32_t seed) { seed_ = seed; }

 protected:
  void performSegmentation(std::vector<int>& labels) override;
  double probability_ = 0.01;
  double cluster_epsilon_ = 0.0;
  std::uint32_t seed_ = 0;
};

/// Whether this build of paco has the efficient-ransac backend (it needs CGAL).
bool efficientRansacAvailable();

extern template class EfficientRansacSegmenter<pcl::PointXYZ>;
extern template class EfficientRansacSegmenter<pcl::PointNormal>;

}  // namespace paco
