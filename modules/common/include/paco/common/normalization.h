#pragma once
// Usage:
//   auto norm = paco::Normalization::fromBoundingBox(*cloud);   // centre at origin, unit diagonal
//   norm.apply(*cloud);                                          // into the normalised frame
//   ... work in the normalised frame ...
//   norm.applyInverse(mesh);                                     // back to the user's frame and units
#include <paco/common/plane.h>
#include <paco/common/primitive.h>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace paco {

struct SurfaceMesh;

/// A similarity x' = rotation * (x - center) * scale that moves a shape to the origin at unit
/// bounding-box diagonal, and its inverse. Normals turn with `rotation` (the scale is isotropic
/// and positive, so they keep their direction otherwise). The rotation is the identity unless
/// the input is also turned into a canonical orientation (see paco/common/orientation.h).
struct Normalization {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  ///< bounding-box centre in the user's frame
  double scale = 1.0;                                ///< 1 / bounding-box diagonal (user units⁻¹)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< user axes -> normalised axes (proper rotation)

  /// From the axis-aligned bounding box of the finite points. Throws InvalidInputError when there
  /// is no finite point or all points coincide (diagonal zero).
  template <typename PointT>
  static Normalization fromBoundingBox(const pcl::PointCloud<PointT>& cloud);
  static Normalization fromBoundingBox(const std::vector<Eigen::Vector3d>& points);
  static Normalization fromBoundingBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);
  /// The same in turned axes: the box of `rotation * x` over the finite points, so that the
  /// normalised shape is centred and of unit diagonal in the turned frame. `rotation` must be a
  /// proper rotation (orthonormal, determinant +1); throws InvalidInputError otherwise.
  template <typename PointT>
  static Normalization fromBoundingBox(const pcl::PointCloud<PointT>& cloud, const Eigen::Matrix3d& rotation);

  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return rotation * (x - center) * scale; }
  Eigen::Vector3d applyInverse(const Eigen::Vector3d& x) const { return rotation.transpose() * x / scale + center; }
  /// A direction (e.g. a normal): only turned.
  Eigen::Vector3d applyToDirection(const Eigen::Vector3d& d) const { return rotation * d; }

  Plane apply(const Plane& plane) const;
  Plane applyInverse(const Plane& plane) const;

  /// Points move; normals (point types that have them) turn.
  template <typename PointT>
  void apply(pcl::PointCloud<PointT>& cloud) const;
  template <typename PointT>
  void applyInverse(pcl::PointCloud<PointT>& cloud) const;
  void apply(PlanarPrimitive& primitive) const;
  void applyInverse(PlanarPrimitive& primitive) const;
  void apply(std::vector<PlanarPrimitive>& primitives) const;
  void applyInverse(std::vector<PlanarPrimitive>& primitives) const;
  void apply(SurfaceMesh& mesh) const;
  void applyInverse(SurfaceMesh& mesh) const;

  /// The composition "this, then `next`".
  Normalization then(const Normalization& next) const;
  /// The inverse similarity, as a Normalization.
  Normalization inverse() const;
};

extern template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointXYZ>&);
extern template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointNormal>&);
extern template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointXYZ>&,
                                                             const Eigen::Matrix3d&);
extern template Normalization Normalization::fromBoundingBox(const pcl::PointCloud<pcl::PointNormal>&,
                                                             const Eigen::Matrix3d&);
extern template void Normalization::apply(pcl::PointCloud<pcl::PointXYZ>&) const;
extern template void Normalization::apply(pcl::PointCloud<pcl::PointNormal>&) const;
extern template void Normalization::applyInverse(pcl::PointCloud<pcl::PointXYZ>&) const;
extern template void Normalization::applyInverse(pcl::PointCloud<pcl::PointNormal>&) const;

}  // namespace paco
