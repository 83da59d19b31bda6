#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/common/surface_mesh.h>

#include <pcl/point_types.h>

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

// The identity turn is exact (x' = 1·x + 0·y + 0·z), so this is the axis-aligned box.
template <typename PointT>
Normalization Normalization::fromBoundingBox(const pcl::PointCloud<PointT>& cloud) {
  return fromBoundingBox(cloud, Eigen::Matrix3d::Identity());
}

template <typename PointT>
Normalization Normalization::fromBoundingBox(const pcl::PointCloud<PointT>& cloud, const Eigen::Matrix3d& rotation) {
  const bool proper = rotation.allFinite() &&
                      (rotation.transpose() * rotation - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff() < 1e-6 &&
                      rotation.determinant() > 0.0;
  if (!proper)
    throw InvalidInputError("Normalization: the rotation is not a proper rotation (orthonormal, determinant +1)");
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& q : cloud) {
    const Eigen::Vector3d p(q.x, q.y, q.z);
    if (p.allFinite()) {
      const Eigen::Vector3d turned = rotation * p;
      lo = lo.cwiseMin(turned);
      hi = hi.cwiseMax(turned);
    }
  }
  Normalization n = fromBoundingBox(lo, hi);  // centre in the turned frame
  n.center = rotation.transpose() * n.center;
  n.rotation = rotation;
  return n;
}

// A plane n·x + d = 0 in the user frame; with x = Rᵀx'/s + c it becomes (Rn)·x' + s(d + n·c) = 0.
Plane Normalization::apply(const Plane& plane) const {
  Plane p;
  p.normal = rotation * plane.normal;
  p.offset = scale * (plane.offset + plane.normal.dot(center));
  return p;
}

// n'·x' + d' = 0 with x' = R(x - c)s: (Rᵀn')·x + d'/s - (Rᵀn')·c = 0.
Plane Normalization::applyInverse(const Plane& plane) const {
  Plane p;
  p.normal = rotation.transpose() * plane.normal;
  p.offset = plane.offset / scale - p.normal.dot(center);
  return p;
}

namespace {
template <typename PointT>
void turnNormal(PointT& q, const Eigen::Matrix3d& rotation) {
  if constexpr (pcl::traits::has_normal_v<PointT>) {
    const Eigen::Vector3d n = rotation * Eigen::Vector3d(q.normal_x, q.normal_y, q.normal_z);
    q.normal_x = static_cast<float>(n.x()); q.normal_y = static_cast<float>(n.y()); q.normal_z = static_cast<float>(n.z());
  }
}
}  // namespace

template <typename PointT>
void Normalization::apply(pcl::PointCloud<PointT>& cloud) const {
  for (auto& q : cloud) {
    const Eigen::Vector3d p = apply(Eigen::Vector3d(q.x, q.y, q.z));
    q.x = static_cast<float>(p.x()); q.y = static_cast<float>(p.y()); q.z = static_cast<float>(p.z());
    turnNormal(q, rotation);
  }
}

template <typename PointT>
void Normalization::applyInverse(pcl::PointCloud<PointT>& cloud) const {
  const Eigen::Matrix3d back = rotation.transpose();
  for (auto& q : cloud) {
    const Eigen::Vector3d p = applyInverse(Eigen::Vector3d(q.x, q.y, q.z));
    q.x = static_cast<float>(p.x()); q.y = static_cast<float>(p.y()); q.z = static_cast<float>(p.z());
    turnNormal(q, back);
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

// R2 (R1 (x - c1) s1 - c2) s2 = R2 R1 (x - (c1 + R1ᵀ c2 / s1)) s1 s2
Normalization Normalization::then(const Normalization& next) const {
  Normalization n;
  n.center = center + rotation.transpose() * next.center / scale;
  n.scale = scale * next.scale;
  n.rotation = next.rotation * rotation;
  return n;
}

// x = Rᵀ x'/s + c = Rᵀ (x' - (-R c s)) / s
Normalization Normalization::inverse() const {
  Normalization n;
  n.center = -rotation * center * scale;
  n.scale = 1.0 / scale;
  n.rotation = rotation.transpose();
  return n;
}

template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointXYZ>&);
template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointNormal>&);
template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointXYZ>&, const Eigen::Matrix3d&);
template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointNormal>&, const Eigen::Matrix3d&);
template void Normalization::apply(pcl::PointCloud<pcl::PointXYZ>&) const;
template void Normalization::apply(pcl::PointCloud<pcl::PointNormal>&) const;
template void Normalization::applyInverse(pcl::PointCloud<pcl::PointXYZ>&) const;
template void Normalization::applyInverse(pcl::PointCloud<pcl::PointNormal>&) const;

}  // namespace paco
