#pragma once
// The point types paco's templates are instantiated for. Keeping this list short keeps builds
// fast (PCL's own build time comes from 18 point types x 6 normal types).
#include <pcl/point_types.h>

#define PACO_POINT_TYPES (pcl::PointXYZ)(pcl::PointNormal)

namespace paco {
/// Point type used between stages: position and normal.
using PointN = pcl::PointNormal;
using CloudN = pcl::PointCloud<PointN>;
}  // namespace paco
