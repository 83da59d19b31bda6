#pragma once
// The point types paco's templates are instantiated for. Keeping this list short keeps builds
// fast (PCL's own build time comes from 18 point types x 6 normal types).
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Core>

#include <vector>

#define PACO_POINT_TYPES (pcl::PointXYZ)(pcl::PointNormal)

namespace paco {
/// Point type used between stages: position and normal.
using PointN = pcl::PointNormal;
using CloudN = pcl::PointCloud<PointN>;

/// The points' positions in double precision, in order (for code that works on Eigen vectors).
template <typename PointT>
std::vector<Eigen::Vector3d> positionsOf(const pcl::PointCloud<PointT>& cloud) {
  std::vector<Eigen::Vector3d> positions;
  positions.reserve(cloud.size());
  for (const auto& p : cloud) positions.emplace_back(p.x, p.y, p.z);
  return positions;
}
}  // namespace paco
