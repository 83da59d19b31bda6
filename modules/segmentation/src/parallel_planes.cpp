#include <paco/segmentation/prepared_cloud.h>

#include <paco/common/error.h>
#include <paco/common/primitive.h>

#include <Eigen/Core>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

namespace paco::detail {

namespace {

// Two planes count as parallel when their normals are within about 8 degrees.
constexpr double kParallelCosine = 0.99;

// A face's points scatter about its plane. On a noisy scan the widened inlier distance still cuts
// off the tails of that scatter, and the points cut off on either side lie on planes parallel to
// the face, about a noise's width off it; the cell complex then closed thin slabs between them
// (forty-seventh session: noise of 1 % of the diagonal, CD 5.57 -> 5.35 at 75 % missing). A
// window within this many RMS distances of a kept face's points to its plane is such a tail when
// it lies over the face. Only on a noisy scan: on a real carton scan without noise adaptation the
// band held a bend of its top, and the cell complex grew a fin without it.
constexpr double kNoiseTailWidths = 4.0;
// ...and it lies over the face when at least this share of its points do: within two point
// spacings of one of the face's points, both projected onto the face's plane. A pocket's floor a
// little below a face lies inside the face's outline, but not over its points.
constexpr double kNoiseTailOver = 0.9;

// A kept segment that a window of free points may be the noise tail of.
class KeptFace {
 public:
  KeptFace(const pcl::PointCloud<pcl::PointNormal>& points, const std::vector<int>& members, const Plane& plane)
      : points_(&points), members_(&members), plane_(plane), rms_(rmsDistance(points, members, plane)) {}

  const Plane& plane() const { return plane_; }

  // True when the window's points lie within kNoiseTailWidths RMS distances of the plane, on average.
  bool withinScatter(const std::vector<int>& window) const {
    double offset = 0.0;
    for (const int i : window) offset += plane_.signedDistance(at(i));
    return std::abs(offset / static_cast<double>(window.size())) <= kNoiseTailWidths * rms_;
  }

  // True when kNoiseTailOver of the window's points lie within `radius` of one of the face's
  // points, both projected onto its plane.
  bool liesOver(const std::vector<int>& window, double radius) {
    if (!flat_tree_) {
      // The face's points on its plane, searched in the plane (built only for a window this close).
      auto flat = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
      for (const int i : *members_) {
        const Eigen::Vector3d q = plane_.project(at(i));
        flat->push_back(pcl::PointXYZ(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z())));
      }
      flat_tree_ = std::make_shared<pcl::search::KdTree<pcl::PointXYZ>>(false);
      flat_tree_->setInputCloud(flat);
    }
    std::vector<int> nearest(1);
    std::vector<float> squared(1);
    std::size_t over = 0;
    for (const int i : window) {
      const Eigen::Vector3d q = plane_.project(at(i));
      const pcl::PointXYZ query(static_cast<float>(q.x()), static_cast<float>(q.y()), static_cast<float>(q.z()));
      if (flat_tree_->nearestKSearch(query, 1, nearest, squared) == 1 && squared[0] <= radius * radius) ++over;
    }
    return static_cast<double>(over) >= kNoiseTailOver * static_cast<double>(window.size());
  }

 private:
  Eigen::Vector3d at(int i) const { return (*points_)[static_cast<std::size_t>(i)].getVector3fMap().cast<double>(); }

  const pcl::PointCloud<pcl::PointNormal>* points_;
  const std::vector<int>* members_;
  Plane plane_;
  double rms_;
  std::shared_ptr<pcl::search::KdTree<pcl::PointXYZ>> flat_tree_;
};

}  // namespace

std::size_t recoverParallelPlanes(const PreparedCloud& prepared, std::vector<int>& labels, std::size_t min_points,
                                  std::size_t min_parallel_points, double distance, double min_abs_cosine,
                                  bool noisy_scan) {
  const auto& points = *prepared.points;
  if (labels.size() != points.size()) throw Error("recoverParallelPlanes: one label per working point expected");
  min_parallel_points = std::max<std::size_t>(min_parallel_points, 3);
  const std::vector<std::vector<int>> groups = membersByLabel(labels);

  // The directions of the planes that stay, most supported first, each once. Points of segments
  // too small to stay are free again: they may belong to a small parallel plane.
  std::vector<std::pair<std::size_t, Eigen::Vector3d>> supported;
  std::vector<KeptFace> kept;  // on a noisy scan only: the faces whose noise tails stay free
  for (const auto& group : groups) {
    if (group.size() < min_points) {
      for (const int i : group) labels[static_cast<std::size_t>(i)] = -1;
      continue;
    }
    try {
      const Plane plane = fitPlane(points, group);
      supported.emplace_back(group.size(), plane.normal);
      if (noisy_scan) kept.emplace_back(points, group, plane);
    } catch (const InvalidInputError&) {
      continue;  // collinear: no direction
    }
  }
  double tail_radius = -1.0;  // two point spacings, measured when first needed (noisy scans only)
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
      // The scatter of a kept face cut off by the inlier distance is that face, not a new one:
      // its points stay free (`kept` is empty unless the scan is noisy).
      if (std::any_of(kept.begin(), kept.end(), [&](KeptFace& face) {
            if (std::abs(face.plane().normal.dot(direction)) <= kParallelCosine || !face.withinScatter(members))
              return false;
            if (tail_radius < 0.0) tail_radius = 2.0 * prepared.averageSpacing();
            return face.liesOver(members, tail_radius);
          }))
        continue;
      for (const int i : members) labels[static_cast<std::size_t>(i)] = next_label;
      ++next_label;
      ++added;
    }
  }
  return added;
}

}  // namespace paco::detail
