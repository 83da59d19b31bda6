#include <paco/data/partial.h>

#include "random.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace paco::data {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point3 = Kernel::Point_3;
using Triangle3 = Kernel::Triangle_3;
using Segment3 = Kernel::Segment_3;
using TriangleIterator = std::vector<Triangle3>::const_iterator;
using Primitive = CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;

Point3 toCgal(const Eigen::Vector3d& p) { return Point3(p.x(), p.y(), p.z()); }

const Eigen::Vector3d kCubeCorners[8] = {
    {1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}, {-1, -1, 1}, {-1, 1, -1}, {1, -1, -1}, {-1, -1, -1}};

}  // namespace

std::string toString(RemovalMode mode) { return mode == RemovalMode::Nearest ? "nearest" : "visibility"; }

RemovalMode removalModeFromString(const std::string& name) {
  if (name == "nearest") return RemovalMode::Nearest;
  if (name == "visibility") return RemovalMode::Visibility;
  throw InvalidInputError("unknown removal mode '" + name + "': use 'nearest' or 'visibility'");
}

Eigen::Vector3d viewpointDirection(int view, int views) {
  if (views <= 0 || view < 0 || view >= views)
    throw InvalidInputError("viewpointDirection: view " + std::to_string(view) + " out of 0.." +
                            std::to_string(views - 1));
  if (views <= 8) return kCubeCorners[view].normalized();
  // Fibonacci sphere: near-uniform directions for any count.
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  const double z = 1.0 - 2.0 * (view + 0.5) / views;
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Eigen::Vector3d(r * std::cos(golden * view), r * std::sin(golden * view), z);
}

std::vector<bool> visibleFrom(const SurfaceMesh& triangles, const std::vector<Eigen::Vector3d>& points,
                              const std::vector<Eigen::Vector3d>& normals, const Eigen::Vector3d& eye,
                              double epsilon) {
  std::vector<Triangle3> soup;
  soup.reserve(triangles.faces.size());
  for (const auto& f : triangles.faces)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      soup.emplace_back(toCgal(triangles.vertices[f[0]]), toCgal(triangles.vertices[f[k]]),
                        toCgal(triangles.vertices[f[k + 1]]));
  std::vector<bool> visible(points.size(), false);
  if (soup.empty()) return visible;
  Tree tree(soup.begin(), soup.end());
  tree.accelerate_distance_queries();
  const Point3 target = toCgal(eye);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (normals[i].dot(eye - points[i]) <= 0.0) continue;  // back-facing
    const Point3 source = toCgal(points[i] + epsilon * normals[i]);
    visible[i] = !tree.do_intersect(Segment3(source, target));
  }
  return visible;
}

PartialScanner::PartialScanner(const GroundTruth& gt, const PartialOptions& options, std::uint64_t seed)
    : options_(options) {
  if (options.output_points == 0) throw InvalidInputError("PartialScanner: output_points must be > 0");
  if (options.dense_points < options.output_points)
    throw InvalidInputError("PartialScanner: dense_points must be >= output_points");
  if (!(options.viewpoint_distance > 0.0)) throw InvalidInputError("PartialScanner: viewpoint_distance must be > 0");
  if (!(options.noise_percent >= 0.0)) throw InvalidInputError("PartialScanner: noise_percent must be >= 0");
  if (gt.faces.empty()) throw InvalidInputError("PartialScanner: the ground truth has no faces");
  const GtPoints dense = sampleGroundTruth(gt, options.dense_points, seed);
  dense_points_ = dense.points;
  dense_normals_ = dense.normals;
  dense_labels_ = dense.labels;
  diagonal_ = gt.diagonal;
  if (options.mode == RemovalMode::Visibility) {
    mesh_ = gt.mesh;
    const int count = options.single_scanner ? 0 : std::clamp(options.visibility_stations, 1, 8);
    for (int s = 0; s < count; ++s) {
      stations_.push_back(viewpointDirection(s, 8) * options.viewpoint_distance);
      visible_.push_back(visibleFrom(mesh_, dense_points_, dense_normals_, stations_.back(), 1e-7 * diagonal_));
    }
  }
}

PartialScanner::~PartialScanner() = default;

PartialScan PartialScanner::scan(const Eigen::Vector3d& direction, double missing_ratio, std::uint64_t seed) const {
  if (!(missing_ratio >= 0.0 && missing_ratio < 1.0))
    throw InvalidInputError("PartialScanner: missing ratio must be in [0, 1)");
  const std::size_t n = dense_points_.size();
  const Eigen::Vector3d eye = direction.normalized() * options_.viewpoint_distance;
  const std::size_t keep_target =
      n - std::min(n - 1, static_cast<std::size_t>(std::llround(missing_ratio * static_cast<double>(n))));

  std::vector<double> distance(n);
  for (std::size_t i = 0; i < n; ++i) distance[i] = (dense_points_[i] - eye).norm();
  auto nearer = [&](std::uint32_t a, std::uint32_t b) {
    return distance[a] < distance[b] || (distance[a] == distance[b] && a < b);
  };

  std::vector<std::uint32_t> kept;
  if (options_.mode == RemovalMode::Nearest) {
    // AdaPoinTr: drop the points nearest to the viewpoint.
    std::vector<std::uint32_t> order(n);
    std::iota(order.begin(), order.end(), 0u);
    const std::size_t drop = n - keep_target;
    std::nth_element(order.begin(), order.begin() + drop, order.end(), nearer);
    kept.assign(order.begin() + drop, order.end());
  } else {
    // A scanner at the viewpoint sees the visible points. When they are more than the level keeps,
    // the scanner's range is limited (keep the visible points nearest to it); when fewer, further
    // stations (the other cube corners, nearest in angle first) add what they see, unless the
    // scanner is the only one (options_.single_scanner: no station was set up).
    std::vector<bool> seen(n, false);
    std::size_t seen_count = 0;
    auto add = [&](const std::vector<bool>& visible) {
      for (std::size_t i = 0; i < n; ++i)
        if (visible[i] && !seen[i]) seen[i] = true, ++seen_count;
    };
    std::vector<std::size_t> station_order(stations_.size());
    std::iota(station_order.begin(), station_order.end(), 0);
    std::stable_sort(station_order.begin(), station_order.end(), [&](std::size_t a, std::size_t b) {
      return stations_[a].dot(eye) > stations_[b].dot(eye);
    });
    std::size_t next = 0;
    const bool eye_is_station =
        !stations_.empty() && (stations_[station_order[0]] - eye).norm() < 1e-9 * options_.viewpoint_distance;
    if (eye_is_station) {
      add(visible_[station_order[0]]);
      next = 1;
    } else {
      add(visibleFrom(mesh_, dense_points_, dense_normals_, eye, 1e-7 * diagonal_));
    }
    while (seen_count < keep_target && next < station_order.size()) add(visible_[station_order[next++]]);
    for (std::size_t i = 0; i < n; ++i)
      if (seen[i]) kept.push_back(static_cast<std::uint32_t>(i));
    if (kept.size() > keep_target) {
      std::nth_element(kept.begin(), kept.begin() + keep_target, kept.end(), nearer);
      kept.resize(keep_target);
    }
    if (kept.empty()) throw InvalidInputError("PartialScanner: no point of the surface is visible from the viewpoint");
  }
  std::sort(kept.begin(), kept.end());

  PartialScan scan;
  scan.missing_ratio = 1.0 - static_cast<double>(kept.size()) / static_cast<double>(n);
  scan.cut_distance = std::numeric_limits<double>::infinity();
  for (std::uint32_t i : kept) scan.cut_distance = std::min(scan.cut_distance, distance[i]);

  // Resample to output_points: a random subset, or every point plus random repeats when too few.
  detail::Rng rng(seed);
  std::vector<std::uint32_t> chosen;
  const std::size_t m = options_.output_points;
  if (kept.size() >= m) {
    for (std::size_t k = 0; k < m; ++k) {  // partial Fisher-Yates
      const std::size_t j = k + rng.index(kept.size() - k);
      std::swap(kept[k], kept[j]);
    }
    chosen.assign(kept.begin(), kept.begin() + m);
  } else {
    chosen = kept;
    while (chosen.size() < m) chosen.push_back(kept[rng.index(kept.size())]);
  }
  const double sigma = options_.noise_percent / 100.0 * diagonal_;
  scan.points.reserve(m);
  scan.normals.reserve(m);
  scan.labels.reserve(m);
  for (std::uint32_t i : chosen) {
    Eigen::Vector3d p = dense_points_[i];
    if (sigma > 0.0) p += sigma * Eigen::Vector3d(rng.normal(), rng.normal(), rng.normal());
    scan.points.push_back(p);
    scan.normals.push_back(dense_normals_[i]);
    scan.labels.push_back(dense_labels_[i]);
  }
  return scan;
}

}  // namespace paco::data
