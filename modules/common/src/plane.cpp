#include <paco/common/error.h>
#include <paco/common/plane.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <string>

namespace paco {

Plane::Plane(const Eigen::Vector3d& n, double d) {
  const double length = n.norm();
  if (!(length > 1e-12) || !std::isfinite(length) || !std::isfinite(d))
    throw InvalidInputError("Plane: the normal must be finite and non-zero (got length " +
                            std::to_string(length) + ")");
  normal = n / length;
  offset = d / length;
}

Plane Plane::fromPointAndNormal(const Eigen::Vector3d& point, const Eigen::Vector3d& n) {
  Plane p(n, 0.0);
  p.offset = -p.normal.dot(point);
  return p;
}

Plane Plane::fit(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& orientation_hint) {
  if (points.size() < 3)
    throw InvalidInputError("Plane::fit: needs at least 3 points, got " + std::to_string(points.size()));
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : points) {
    const Eigen::Vector3d q = p - centroid;
    covariance += q * q.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(covariance);
  const Eigen::Vector3d eigenvalues = solver.eigenvalues();  // ascending
  // Collinear or coincident points leave two (near-)zero eigenvalues: no unique plane.
  if (!(eigenvalues(1) > 1e-12 * std::max(1.0, eigenvalues(2))) )
    throw InvalidInputError("Plane::fit: the " + std::to_string(points.size()) +
                            " points are collinear or coincident; no unique plane");
  Eigen::Vector3d n = solver.eigenvectors().col(0);
  if (orientation_hint.squaredNorm() > 0 && n.dot(orientation_hint) < 0) n = -n;
  return fromPointAndNormal(centroid, n);
}

Plane Plane::flipped() const {
  Plane p;
  p.normal = -normal;
  p.offset = -offset;
  return p;
}

double Plane::unorientedAngleTo(const Plane& other) const {
  const double c = std::min(1.0, std::abs(normal.dot(other.normal)));
  return std::acos(c);
}

pcl::ModelCoefficients toModelCoefficients(const Plane& plane) {
  pcl::ModelCoefficients c;
  c.values = {static_cast<float>(plane.normal.x()), static_cast<float>(plane.normal.y()),
              static_cast<float>(plane.normal.z()), static_cast<float>(plane.offset)};
  return c;
}

Plane fromModelCoefficients(const pcl::ModelCoefficients& c) {
  if (c.values.size() != 4)
    throw InvalidInputError("fromModelCoefficients: a plane needs 4 values {a, b, c, d}, got " +
                            std::to_string(c.values.size()));
  return Plane(Eigen::Vector3d(c.values[0], c.values[1], c.values[2]), c.values[3]);
}

}  // namespace paco
