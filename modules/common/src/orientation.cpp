#include <paco/common/error.h>
#include <paco/common/orientation.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace paco {

std::optional<Eigen::Matrix3d> dominantPlaneAxes(const std::vector<Eigen::Vector3d>& normals,
                                                 const std::vector<double>& weights, double tolerance_degrees) {
  if (normals.size() != weights.size())
    throw InvalidInputError("dominantPlaneAxes: " + std::to_string(normals.size()) + " normals but " +
                            std::to_string(weights.size()) + " weights");
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < normals.size(); ++i)
    if (normals[i].allFinite() && normals[i].norm() > 0.0 && weights[i] > 0.0) order.push_back(i);
  if (order.empty()) return std::nullopt;
  // Stable: equal weights keep the given order, so the result is reproducible.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return weights[a] > weights[b]; });
  const Eigen::Vector3d first = normals[order[0]].normalized();
  const double max_cosine = std::sin(tolerance_degrees * 3.14159265358979323846 / 180.0);
  std::optional<Eigen::Vector3d> second;
  for (std::size_t k = 1; k < order.size() && !second; ++k) {
    const Eigen::Vector3d n = normals[order[k]].normalized();
    if (std::abs(n.dot(first)) <= max_cosine) second = (n - n.dot(first) * first).normalized();
  }
  if (!second) {
    Eigen::Index least = 0;
    first.cwiseAbs().minCoeff(&least);
    const Eigen::Vector3d axis = Eigen::Vector3d::Unit(least);
    second = (axis - axis.dot(first) * first).normalized();
  }
  Eigen::Matrix3d axes;
  axes.col(0) = first;
  axes.col(1) = *second;
  axes.col(2) = first.cross(*second);
  return axes;
}

Eigen::Matrix3d rotationOntoAxesClosestToIdentity(const Eigen::Matrix3d& axes) {
  // R = P Aᵀ maps column j of A onto column j of the signed permutation P; det R = det P.
  std::array<int, 3> permutation = {0, 1, 2};
  Eigen::Matrix3d best = Eigen::Matrix3d::Identity();
  double best_trace = -std::numeric_limits<double>::infinity();
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
      for (int j = 0; j < 3; ++j) P(permutation[j], j) = (signs >> j) & 1 ? -1.0 : 1.0;
      if (P.determinant() * axes.determinant() < 0.0) continue;
      const Eigen::Matrix3d R = P * axes.transpose();
      if (R.trace() > best_trace + 1e-12) {
        best_trace = R.trace();
        best = R;
      }
    }
  } while (std::next_permutation(permutation.begin(), permutation.end()));
  return best;
}

Eigen::Matrix3d seenPlanesRotation(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights) {
  const auto axes = dominantPlaneAxes(normals, weights);
  return axes ? rotationOntoAxesClosestToIdentity(*axes) : Eigen::Matrix3d::Identity();
}

}  // namespace paco
