#pragma once
// Baseline: pcl::RegionGrowing on the normals, then one least-squares plane per region.
// Usage:
//   paco::RegionGrowingSegmenter<pcl::PointXYZ> seg;      // normals are estimated
//   seg.setInputCloud(cloud); seg.setCurvatureThreshold(0.05);
//   paco::PlanarSegmentation result; seg.segment(result);
#include <paco/segmentation/planar_segmenter.h>

namespace paco {

/// pcl::RegionGrowing: a region takes the neighbours (k of the base class) whose normal is within
/// acos(τ) of its seed's normal; regions of fewer than σ points are dropped. ε is not used while
/// growing (PCL's region growing has no distance test).
template <typename PointT>
class RegionGrowingSegmenter : public PlanarSegmenter<PointT> {
 public:
  using Ptr = std::shared_ptr<RegionGrowingSegmenter<PointT>>;
  std::string name() const override { return "region-growing"; }

  /// Points whose curvature (surface variation λ0/(λ0+λ1+λ2) of their neighbourhood) exceeds this
  /// join regions but do not seed them. Range [0, 1/3]; default 0.05. Given normals have
  /// curvature 0.
  void setCurvatureThreshold(double curvature);
  double getCurvatureThreshold() const { return curvature_threshold_; }

 protected:
  void performSegmentation(std::vector<int>& labels) override;
  double curvature_threshold_ = 0.05;
};

extern template class RegionGrowingSegmenter<pcl::PointXYZ>;
extern template class RegionGrowingSegmenter<pcl::PointNormal>;

}  // namespace paco
