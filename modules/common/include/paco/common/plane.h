#pragma once
// Usage:
//   paco::Plane p = paco::Plane::fromPointAndNormal({0, 0, 1}, {0, 0, 1});  // z = 1
//   double d = p.signedDistance(Eigen::Vector3d(0, 0, 3));                 // 2
//   pcl::ModelCoefficients c = paco::toModelCoefficients(p);
#include <Eigen/Core>
#include <pcl/ModelCoefficients.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace paco {

/// An oriented plane n·x + d = 0 with a unit normal n. One plane type is used everywhere.
struct Plane {
  Eigen::Vector3d normal{0.0, 0.0, 1.0};  ///< unit normal n
  double offset = 0.0;                     ///< d in n·x + d = 0 (the distance of the origin is -d)

  Plane() = default;
  /// Normalises (normal, offset) so that the normal has unit length; throws if it is ~zero.
  Plane(const Eigen::Vector3d& normal, double offset);

  static Plane fromPointAndNormal(const Eigen::Vector3d& point, const Eigen::Vector3d& normal);

  /// Least-squares plane through at least 3 non-collinear points (smallest eigenvector of the
  /// covariance). The normal is flipped to agree with `orientation_hint` when it is non-zero.
  static Plane fit(const std::vector<Eigen::Vector3d>& points,
                   const Eigen::Vector3d& orientation_hint = Eigen::Vector3d::Zero());

  double signedDistance(const Eigen::Vector3d& x) const { return normal.dot(x) + offset; }
  Eigen::Vector3d project(const Eigen::Vector3d& x) const { return x - signedDistance(x) * normal; }
  /// The point of the plane nearest to the origin.
  Eigen::Vector3d foot() const { return -offset * normal; }
  /// Same plane with the opposite orientation.
  Plane flipped() const;
  /// Angle between the two normals in radians, ignoring orientation (in [0, pi/2]).
  double unorientedAngleTo(const Plane& other) const;
};

/// pcl::ModelCoefficients of a plane: values {a, b, c, d} with a x + b y + c z + d = 0.
pcl::ModelCoefficients toModelCoefficients(const Plane& plane);
/// Reads a pcl::ModelCoefficients plane; throws InvalidInputError unless it has 4 finite values
/// and a non-zero normal.
Plane fromModelCoefficients(const pcl::ModelCoefficients& coefficients);

}  // namespace paco
