#include <paco/segmentation/prepared_cloud.h>

#include <paco/common/error.h>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <utility>
#include <vector>

namespace paco::detail {

namespace {

// Two planes count as parallel when their normals are within about 8 degrees.
constexpr double kParallelCosine = 0.99;

}  // namespace

std::size_t recoverParallelPlanes(const PreparedCloud& prepared, std::vector<int>& labels, std::size_t min_points,
                                  std::size_t min_parallel_points, double distance, double min_abs_cosine) {
  const auto& points = *prepared.points;
  if (labels.size() != points.size()) throw Error("recoverParallelPlanes: one label per working point expected");
  min_parallel_points = std::max<std::size_t>(min_parallel_points, 3);
  const std::vector<std::vector<int>> groups = membersByLabel(labels);

  // The directions of the planes that stay, most supported first, each once. Points of segments
  // too small to stay are free again: they may belong to a small parallel plane.
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> supported;
  for (const auto& group : groups) {
    if (group.size() < min_points) {
      for (const int i : group) labels[static_cast<std::size_t>(i)] = -1;
      continue;
    }
    try {
      supported.emplace_back(group.size(), fitPlane(points, group).normal);
    } catch (const InvalidInputError&) {
      continue;  // collinear: no direction
    }
  }
  std::stable_sort(supported.begin(), supported.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Eigen::Vector3d> directions;
  for (const auto& [size, normal] : supported) {
    const bool known = std::any_of(directions.begin(), directions.end(),
                                   [&](const Eigen::Vector3d& d) { return std::abs(d.dot(normal)) > kParallelCosine; });
    if (!known) directions.push_back(normal);
  }

  // For each direction, the free points whose normals agree with it, by their offset along it:
  // the window of offsets 2 x `distance` wide that holds the most of them becomes a plane, while
  // it holds at least min_parallel_points.
  int next_label = static_cast<int>(groups.size());
  std::size_t added = 0;
  for (const Eigen::Vector3d& direction : directions) {
    std::vector<std::pair<double, int>> candidates;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (labels[i] >= 0) continue;
      const Eigen::Vector3d n = points[i].getNormalVector3fMap().cast<double>();
      if (!(std::abs(n.dot(direction)) >= min_abs_cosine)) continue;  // zero normals never agree
      candidates.emplace_back(direction.dot(points[i].getVector3fMap().cast<double>()), static_cast<int>(i));
    }
    std::sort(candidates.begin(), candidates.end());
    while (candidates.size() >= min_parallel_points) {
      std::size_t best_start = 0, best_count = 0;
      for (std::size_t start = 0, end = 0; start < candidates.size(); ++start) {
        end = std::max(end, start);
        while (end < candidates.size() && candidates[end].first - candidates[start].first <= 2.0 * distance) ++end;
        if (end - start > best_count) {
          best_count = end - start;
          best_start = start;
        }
      }
      if (best_count < min_parallel_points) break;
      std::vector<int> members;
      for (std::size_t k = best_start; k < best_start + best_count; ++k) members.push_back(candidates[k].second);
      candidates.erase(candidates.begin() + static_cast<std::ptrdiff_t>(best_start),
                       candidates.begin() + static_cast<std::ptrdiff_t>(best_start + best_count));
      // Points along a narrow strip fit a plane of any tilt about the strip: keep only windows
      // whose own plane is parallel to the direction.
      bool parallel = false;
      try {
        parallel = std::abs(fitPlane(points, members).normal.dot(direction)) > kParallelCosine;
      } catch (const InvalidInputError&) {
      }
      if (!parallel) continue;
      for (const int i : members) labels[static_cast<std::size_t>(i)] = next_label;
      ++next_label;
      ++added;
    }
  }
  return added;
}

}  // namespace paco::detail
