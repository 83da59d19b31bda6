#include <paco/common/error.h>
#include <paco/segmentation/region_growing_segmenter.h>

#include <pcl/segmentation/region_growing.h>
// PCL does not precompile RegionGrowing<PointNormal, PointNormal>: instantiate it here.
#include <pcl/segmentation/impl/region_growing.hpp>

#include <cmath>
#include <limits>
#include <string>

namespace paco {

template <typename PointT>
void RegionGrowingSegmenter<PointT>::setCurvatureThreshold(double curvature) {
  if (!(curvature >= 0.0 && curvature <= 1.0 / 3.0 + 1e-9))
    throw InvalidInputError("RegionGrowingSegmenter::setCurvatureThreshold: the curvature is a surface variation "
                            "in [0, 1/3]; got " + std::to_string(curvature));
  curvature_threshold_ = curvature;
}

template <typename PointT>
void RegionGrowingSegmenter<PointT>::performSegmentation(std::vector<int>& labels) {
  const auto& prepared = this->prepared_;
  pcl::RegionGrowing<pcl::PointNormal, pcl::PointNormal> growing;
  growing.setInputCloud(prepared.points);
  growing.setInputNormals(prepared.points);
  growing.setSearchMethod(prepared.tree);
  growing.setNumberOfNeighbours(static_cast<unsigned int>(this->neighbours_));
  growing.setMinClusterSize(this->used_min_points_);
  growing.setMaxClusterSize(std::numeric_limits<int>::max());
  // Compare with the seed's normal, not the previous point's: planes, not smooth surfaces.
  growing.setSmoothModeFlag(false);
  growing.setSmoothnessThreshold(static_cast<float>(std::acos(this->normal_threshold_)));
  growing.setCurvatureTestFlag(true);
  growing.setCurvatureThreshold(static_cast<float>(curvature_threshold_));
  growing.setResidualTestFlag(false);
  std::vector<pcl::PointIndices> clusters;
  growing.extract(clusters);
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (const auto i : clusters[c].indices) labels[static_cast<std::size_t>(i)] = static_cast<int>(c);
}

template class RegionGrowingSegmenter<pcl::PointXYZ>;
template class RegionGrowingSegmenter<pcl::PointNormal>;

}  // namespace paco
