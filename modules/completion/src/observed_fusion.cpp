#include <paco/completion/observed_fusion.h>

#include <paco/common/error.h>
#include <paco/common/orientation.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace paco {
namespace {

constexpr double kPi = 3.14159265358979323846;

Eigen::Vector3d position(const pcl::PointNormal& p) { return {p.x, p.y, p.z}; }

// Mean |distance| of (at most 256 evenly spaced) points to a plane: enough to rank planes.
double meanDistance(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& plane) {
  const std::size_t n = points.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 256);
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; i += stride, ++count) sum += std::abs(plane.signedDistance(position(points[i])));
  return count == 0 ? std::numeric_limits<double>::infinity() : sum / static_cast<double>(count);
}

// Moves the points onto the plane and gives them its normal.
void projectOnto(const Plane& plane, pcl::PointCloud<pcl::PointNormal>& points) {
  for (auto& p : points) {
    const Eigen::Vector3d q = plane.project(position(p));
    p.x = static_cast<float>(q.x());
    p.y = static_cast<float>(q.y());
    p.z = static_cast<float>(q.z());
    p.normal_x = static_cast<float>(plane.normal.x());
    p.normal_y = static_cast<float>(plane.normal.y());
    p.normal_z = static_cast<float>(plane.normal.z());
  }
}

double diagonalOf(const std::vector<PlanarPrimitive>& primitives) {
  Eigen::AlignedBox3d box;
  for (const auto& primitive : primitives)
    for (const auto& p : primitive.points) box.extend(position(p));
  return box.isEmpty() ? 0.0 : box.diagonal().norm();
}

// The seen directions: every trusted observed segment's normal and the dominant axes.
std::vector<Eigen::Vector3d> seenDirections(const std::vector<PlanarPrimitive>& observed, std::size_t min_points) {
  std::vector<Eigen::Vector3d> directions;
  std::vector<double> sizes;
  for (const auto& seen : observed) {
    if (seen.points.size() < min_points || !(seen.plane.normal.norm() > 0.0)) continue;
    directions.push_back(seen.plane.normal.normalized());
    sizes.push_back(static_cast<double>(seen.points.size()));
  }
  if (const auto axes = dominantPlaneAxes(directions, sizes))
    for (int k = 0; k < 3; ++k) directions.push_back(axes->col(k));
  return directions;
}

// Turns the primitive's plane onto the nearest direction within max_angle (keeping its outward
// side), through its points' centroid; true when it turned.
bool alignWithNearest(PlanarPrimitive& primitive, const std::vector<Eigen::Vector3d>& directions, double max_angle) {
  const Eigen::Vector3d normal = primitive.plane.normal.normalized();
  const Eigen::Vector3d* nearest = nullptr;
  double best = -1.0;
  for (const auto& d : directions) {
    const double c = std::abs(normal.dot(d));
    if (c > best) {
      best = c;
      nearest = &d;
    }
  }
  if (!nearest || std::acos(std::min(1.0, best)) > max_angle) return false;
  const Eigen::Vector3d turned = normal.dot(*nearest) < 0.0 ? -*nearest : *nearest;
  Eigen::Vector3d pivot = primitive.plane.foot();
  if (!primitive.points.empty()) {
    pivot.setZero();
    for (const auto& p : primitive.points) pivot += position(p);
    pivot /= static_cast<double>(primitive.points.size());
  }
  primitive.plane = Plane::fromPointAndNormal(pivot, turned);
  projectOnto(primitive.plane, primitive.points);
  return true;
}

}  // namespace

std::string describe(const ObservedFusionReport& report) {
  return std::to_string(report.snapped) + " primitives took a seen plane, " + std::to_string(report.absorbed) +
         " duplicates absorbed, " + std::to_string(report.added) + " seen faces added" +
         (report.aligned ? ", " + std::to_string(report.aligned) + " unseen aligned with seen directions" : "");
}

std::vector<PlanarPrimitive> fuseWithObserved(std::vector<PlanarPrimitive> completed,
                                              const std::vector<PlanarPrimitive>& observed,
                                              const ObservedFusionOptions& options, ObservedFusionReport* report) {
  if (!std::isfinite(options.max_angle_degrees) || options.max_angle_degrees < 0.0 ||
      !std::isfinite(options.max_distance) || options.max_distance < 0.0 ||
      !std::isfinite(options.align_unseen_degrees) || options.align_unseen_degrees < 0.0)
    throw InvalidInputError(
        "fuseWithObserved: max_angle_degrees, max_distance and align_unseen_degrees must be finite and >= 0");
  ObservedFusionReport counts;
  const double max_angle = options.max_angle_degrees * kPi / 180.0;
  const double max_distance = options.max_distance * diagonalOf(observed);

  std::vector<std::size_t> order(observed.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return observed[a].points.size() > observed[b].points.size(); });

  std::vector<bool> snapped(completed.size(), false), absorbed(completed.size(), false);
  std::vector<PlanarPrimitive> unmatched;
  std::vector<std::size_t> matches;
  for (std::size_t o : order) {
    const PlanarPrimitive& seen = observed[o];
    if (seen.points.size() < options.min_observed_points) {
      ++counts.ignored;
      continue;
    }
    matches.clear();
    std::size_t best = completed.size();
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < completed.size(); ++c) {
      if (absorbed[c] || completed[c].plane.unorientedAngleTo(seen.plane) > max_angle) continue;
      const double d = meanDistance(seen.points, completed[c].plane);
      if (d > max_distance) continue;
      matches.push_back(c);
      if (d < best_distance) {
        best = c;
        best_distance = d;
      }
    }
    if (best == completed.size()) {
      unmatched.push_back(seen);
      unmatched.back().confidence = 1.0f;
      ++counts.added;
      continue;
    }
    PlanarPrimitive& target = completed[best];
    if (!snapped[best]) {
      // Keep the predicted orientation (outward), take the observed position and tilt.
      target.plane = seen.plane.normal.dot(target.plane.normal) < 0.0 ? seen.plane.flipped() : seen.plane;
      projectOnto(target.plane, target.points);
      // A seen face is certain, whatever the network's score: confidence 1, like the unmatched
      // observed segments (the assembler's candidate-face budget never drops those).
      target.confidence = 1.0f;
      snapped[best] = true;
      ++counts.snapped;
    } else {
      ++counts.joined;
    }
    target.points += seen.points;
    // Other predictions of the same seen face are duplicates: their points (which may reach into
    // the unseen part of the face) join the chosen one.
    for (std::size_t c : matches) {
      if (c == best || snapped[c]) continue;
      projectOnto(target.plane, completed[c].points);
      target.points += completed[c].points;
      absorbed[c] = true;
      ++counts.absorbed;
    }
  }
  if (options.align_unseen_degrees > 0.0) {
    const auto directions = seenDirections(observed, options.min_observed_points);
    const double max_align = options.align_unseen_degrees * kPi / 180.0;
    for (std::size_t c = 0; c < completed.size(); ++c)
      if (!snapped[c] && !absorbed[c] && alignWithNearest(completed[c], directions, max_align)) ++counts.aligned;
  }
  std::vector<PlanarPrimitive> fused;
  fused.reserve(completed.size() + unmatched.size());
  for (std::size_t c = 0; c < completed.size(); ++c)
    if (!absorbed[c]) fused.push_back(std::move(completed[c]));
  for (auto& primitive : unmatched) fused.push_back(std::move(primitive));
  if (report) *report = counts;
  return fused;
}

}  // namespace paco
