#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/common/surface_mesh.h>

#include <cmath>
#include <limits>

namespace paco {

Normalization Normalization::fromBoundingBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  const double diagonal = (max - min).norm();
  if (!std::isfinite(diagonal) || !(diagonal > 0.0))
    throw InvalidInputError(
        "Normalization: the bounding box has zero or non-finite diagonal (all points coincide or "
        "none is finite); give a cloud with at least two distinct finite points");
  Normalization n;
  n.center = 0.5 * (min + max);
  n.scale = 1.0 / diagonal;
  return n;
}

Normalization Normalization::fromBoundingBox(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& p : points)
    if (p.allFinite()) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  return fromBoundingBox(lo, hi);
}

template <typename PointT>
Normalization Normalization::fromBoundingBox(const pcl::PointCloud<PointT>& cloud) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& q : cloud) {
    const Eigen::Vector3d p(q.x, q.y, q.z);
    if (p.allFinite()) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  }
  return fromBoundingBox(lo, hi);
}

// A plane n·x + d = 0 in the user frame; with x = x'/s + c it becomes n·x' + s(d + n·c) = 0.
Plane Normalization::apply(const Plane& plane) const {
  Plane p;
  p.normal = plane.normal;
  p.offset = scale * (plane.offset + plane.normal.dot(center));
  return p;
}

Plane Normalization::applyInverse(const Plane& plane) const {
  Plane p;
  p.normal = plane.normal;
  p.offset = plane.offset / scale - plane.normal.dot(center);
  return p;
}

template <typename PointT>
void Normalization::apply(pcl::PointCloud<PointT>& cloud) const {
  for (auto& q : cloud) {
    const Eigen::Vector3d p = apply(Eigen::Vector3d(q.x, q.y, q.z));
    q.x = static_cast<float>(p.x()); q.y = static_cast<float>(p.y()); q.z = static_cast<float>(p.z());
  }
}

template <typename PointT>
void Normalization::applyInverse(pcl::PointCloud<PointT>& cloud) const {
  for (auto& q : cloud) {
    const Eigen::Vector3d p = applyInverse(Eigen::Vector3d(q.x, q.y, q.z));
    q.x = static_cast<float>(p.x()); q.y = static_cast<float>(p.y()); q.z = static_cast<float>(p.z());
  }
}

void Normalization::apply(PlanarPrimitive& primitive) const {
  primitive.plane = apply(primitive.plane);
  apply(primitive.points);
}
void Normalization::applyInverse(PlanarPrimitive& primitive) const {
  primitive.plane = applyInverse(primitive.plane);
  applyInverse(primitive.points);
}
void Normalization::apply(std::vector<PlanarPrimitive>& primitives) const {
  for (auto& p : primitives) apply(p);
}
void Normalization::applyInverse(std::vector<PlanarPrimitive>& primitives) const {
  for (auto& p : primitives) applyInverse(p);
}
void Normalization::apply(SurfaceMesh& mesh) const {
  for (auto& v : mesh.vertices) v = apply(v);
}
void Normalization::applyInverse(SurfaceMesh& mesh) const {
  for (auto& v : mesh.vertices) v = applyInverse(v);
}

// ((x - c1) s1 - c2) s2 = (x - (c1 + c2 / s1)) s1 s2
Normalization Normalization::then(const Normalization& next) const {
  Normalization n;
  n.center = center + next.center / scale;
  n.scale = scale * next.scale;
  return n;
}

// x = x'/s + c = (x' - (-c s)) / s
Normalization Normalization::inverse() const {
  Normalization n;
  n.center = -center * scale;
  n.scale = 1.0 / scale;
  return n;
}

template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointXYZ>&);
template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointNormal>&);
template void Normalization::apply(pcl::PointCloud<pcl::PointXYZ>&) const;
template void Normalization::apply(pcl::PointCloud<pcl::PointNormal>&) const;
template void Normalization::applyInverse(pcl::PointCloud<pcl::PointXYZ>&) const;
template void Normalization::applyInverse(pcl::PointCloud<pcl::PointNormal>&) const;

}  // namespace paco
