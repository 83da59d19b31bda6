// Orienting segments whose normals were estimated: consistently across shared edges, then each
// connected group as a whole (see orientEstimatedSegments in prepared_cloud.h).
#include <paco/segmentation/prepared_cloud.h>
#include <paco/common/angles.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <tuple>
#include <utility>

namespace paco {
namespace detail {
namespace {

// Neighbours per point for the edge evidence. They reach about three point spacings across an
// edge: far enough that the other face's points stand off this plane by more than scanner noise
// (with 10, a scan with noise of 1 % of its diagonal got more segments wrong than turning each
// normal away from the centre).
constexpr int kEdgeNeighbours = 30;
// Below this angle two adjacent planes count as near-parallel: the side their points lie on then
// says nothing about convexity.
constexpr double kNearParallelDegrees = 30.0;
// An edge needs this many points of each segment clearly off the other's plane ...
constexpr std::size_t kMinEdgePoints = 3;
// ... and this share of them on one side.
constexpr double kMinSideShare = 0.7;
// Points closer to the other plane than this many times the larger of the two segments' scatter
// about their own planes, or this fraction of the point spacing, are on neither side.
constexpr double kBandScatters = 3.0;
constexpr double kBandSpacingFraction = 0.25;
// Near-parallel neighbours count as near-coplanar, and face alike, when the points of each lie
// within this fraction of the point spacing of the other's plane on average. Noise splits a face
// into parallel layers this close.
constexpr double kCoplanarSpacingFraction = 0.5;

// Union-find over segments that also keeps each segment's orientation relative to its root
// (parity 1: opposite), so that joining two groups by a relation between two of their members
// fixes every member's orientation relative to the new root.
class ParityUnionFind {
 public:
  explicit ParityUnionFind(std::size_t n) : parent_(n), parity_(n, 0) { std::iota(parent_.begin(), parent_.end(), 0); }

  /// The root of x's group and x's parity relative to it.
  std::pair<std::size_t, int> find(std::size_t x) {
    std::size_t root = x;
    int parity = 0;
    while (parent_[root] != root) {
      parity ^= parity_[root];
      root = parent_[root];
    }
    // Path compression: point every visited node at the root with its parity relative to it.
    std::size_t node = x;
    int node_parity = parity;
    while (parent_[node] != node) {
      const std::size_t next = parent_[node];
      const int next_parity = node_parity ^ parity_[node];
      parent_[node] = root;
      parity_[node] = node_parity;
      node = next;
      node_parity = next_parity;
    }
    return {root, parity};
  }

  /// Joins the groups of a and b so that parity(a) ^ parity(b) == relation; false (and nothing
  /// changes) when they are already in one group.
  bool join(std::size_t a, std::size_t b, int relation) {
    const auto [root_a, parity_a] = find(a);
    const auto [root_b, parity_b] = find(b);
    if (root_a == root_b) return false;
    parent_[root_b] = root_a;
    parity_[root_b] = parity_a ^ parity_b ^ relation;
    return true;
  }

 private:
  std::vector<std::size_t> parent_;
  std::vector<int> parity_;
};

// Where the points of one segment near a shared edge lie relative to the other's plane. Points
// within `band` of that plane say nothing: near an edge the two planes meet, and noisy points of
// one face fall within the other's inlier band. Each point counts once, however many neighbours
// it has across the edge.
struct SideEvidence {
  std::vector<int> points;  // working indices, with repeats until classify()
  std::size_t in_front = 0, behind = 0;
  double mean_distance = 0.0;  // mean absolute distance to the other plane

  void classify(const pcl::PointCloud<pcl::PointNormal>& cloud, const Plane& other_plane, double band) {
    std::sort(points.begin(), points.end());
    points.erase(std::unique(points.begin(), points.end()), points.end());
    for (const int i : points) {
      const double d = other_plane.signedDistance(cloud[static_cast<std::size_t>(i)].getVector3fMap().cast<double>());
      mean_distance += std::abs(d) / static_cast<double>(points.size());
      if (d > band) ++in_front;
      else if (d < -band) ++behind;
    }
  }
  std::size_t clear() const { return in_front + behind; }
  // Enough points off the plane, and nearly all of them on one side.
  bool decisive() const {
    return clear() >= kMinEdgePoints && std::max(in_front, behind) >= kMinSideShare * static_cast<double>(clear());
  }
  bool inFront() const { return in_front > behind; }
};

struct EdgeEvidence {
  SideEvidence second_to_first_plane;  // points of the higher-numbered segment, plane of the lower
  SideEvidence first_to_second_plane;  // points of the lower-numbered segment, plane of the higher
};

struct Relation {
  std::size_t a = 0, b = 0;
  int flip = 0;            // 1: one of the two must turn for them to agree
  std::size_t weight = 0;  // points supporting it
};

}  // namespace

void orientEstimatedSegments(const PreparedCloud& prepared, const std::vector<std::vector<int>>& members,
                             std::vector<Plane>& planes) {
  const std::size_t segments = planes.size();
  if (segments == 0 || prepared.estimated_normal.size() != prepared.size()) return;
  const auto& points = *prepared.points;
  std::vector<int> segment_of(points.size(), -1);
  for (std::size_t s = 0; s < segments; ++s)
    for (const int i : members[s]) segment_of[static_cast<std::size_t>(i)] = static_cast<int>(s);

  std::map<std::pair<std::size_t, std::size_t>, EdgeEvidence> edges;
  const auto& neighbours = prepared.neighbours(kEdgeNeighbours);
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (segment_of[i] < 0) continue;
    const auto a = static_cast<std::size_t>(segment_of[i]);
    for (const int j : neighbours[i]) {
      const int sj = segment_of[static_cast<std::size_t>(j)];
      if (sj < 0 || static_cast<std::size_t>(sj) == a) continue;
      const auto b = static_cast<std::size_t>(sj);
      auto& edge = edges[{std::min(a, b), std::max(a, b)}];
      (a < b ? edge.first_to_second_plane : edge.second_to_first_plane).points.push_back(static_cast<int>(i));
      (a < b ? edge.second_to_first_plane : edge.first_to_second_plane).points.push_back(j);
    }
  }
  // Root-mean-square distance of each segment's points to its plane: the noise an edge's
  // evidence must rise above.
  std::vector<double> scatter_of(segments, 0.0);
  for (std::size_t s = 0; s < segments; ++s) {
    double sum_squares = 0.0;
    for (const int i : members[s]) {
      const double d = planes[s].signedDistance(points[static_cast<std::size_t>(i)].getVector3fMap().cast<double>());
      sum_squares += d * d;
    }
    scatter_of[s] = members[s].empty() ? 0.0 : std::sqrt(sum_squares / static_cast<double>(members[s].size()));
  }

  const double spacing = prepared.averageSpacing();
  for (auto& [key, edge] : edges) {
    const double band =
        std::max(kBandScatters * std::max(scatter_of[key.first], scatter_of[key.second]), kBandSpacingFraction * spacing);
    edge.second_to_first_plane.classify(points, planes[key.first], band);
    edge.first_to_second_plane.classify(points, planes[key.second], band);
  }

  const double near_parallel = std::cos(degreesToRadians(kNearParallelDegrees));
  std::vector<Relation> relations;
  for (const auto& [key, edge] : edges) {
    const auto& [a, b] = key;
    const SideEvidence& b_to_a = edge.second_to_first_plane;
    const SideEvidence& a_to_b = edge.first_to_second_plane;
    if (b_to_a.points.size() < kMinEdgePoints || a_to_b.points.size() < kMinEdgePoints) continue;
    const double cosine = planes[a].normal.dot(planes[b].normal);
    if (std::abs(cosine) >= near_parallel) {
      // Near-parallel: near-coplanar neighbours face alike; with an offset (a step, or the two
      // sides of a thin wall) nothing is known.
      const auto on_plane = [&](const SideEvidence& e) { return e.mean_distance < kCoplanarSpacingFraction * spacing; };
      if (on_plane(b_to_a) && on_plane(a_to_b))
        relations.push_back({a, b, cosine < 0.0 ? 1 : 0, std::min(b_to_a.points.size(), a_to_b.points.size())});
      continue;
    }
    // With outward normals, a convex edge has each segment behind the other's plane and a
    // concave edge in front of it: the two sides agree. If they disagree, one plane is turned.
    if (!b_to_a.decisive() || !a_to_b.decisive()) continue;
    relations.push_back({a, b, b_to_a.inFront() == a_to_b.inFront() ? 0 : 1, std::min(b_to_a.clear(), a_to_b.clear())});
  }
  // Best-supported relations first; a relation that closes a loop is left out, so a wrong one
  // on a weak edge cannot overrule the strong ones (a maximum spanning forest).
  std::stable_sort(relations.begin(), relations.end(),
                   [](const Relation& x, const Relation& y) { return x.weight > y.weight; });
  ParityUnionFind groups(segments);
  for (const auto& r : relations) groups.join(r.a, r.b, r.flip);

  // Each group's orientation as a whole: given normals vote first, else away from the centre.
  std::vector<long> given_votes(segments, 0), outward_votes(segments, 0);
  std::vector<int> parity(segments, 0);
  std::vector<std::size_t> root(segments, 0);
  std::vector<bool> mostly_given(segments, false);
  for (std::size_t s = 0; s < segments; ++s) {
    std::tie(root[s], parity[s]) = groups.find(s);
    const double sign = parity[s] ? -1.0 : 1.0;  // this segment's normal in its root's orientation
    const Eigen::Vector3d n = sign * planes[s].normal;
    std::size_t given = 0;
    for (const int i : members[s]) {
      const auto& p = points[static_cast<std::size_t>(i)];
      const Eigen::Vector3d position = p.getVector3fMap().cast<double>();
      const double outward = n.dot(position);  // the box centre is the origin of the working frame
      outward_votes[root[s]] += outward > 0.0 ? 1 : (outward < 0.0 ? -1 : 0);
      if (prepared.estimated_normal[static_cast<std::size_t>(i)]) continue;
      ++given;
      const double agreement = n.dot(p.getNormalVector3fMap().cast<double>());
      given_votes[root[s]] += agreement > 0.0 ? 1 : (agreement < 0.0 ? -1 : 0);
    }
    mostly_given[s] = 2 * given > members[s].size();
  }
  for (std::size_t s = 0; s < segments; ++s) {
    if (mostly_given[s]) continue;
    const long vote = given_votes[root[s]] != 0 ? given_votes[root[s]] : outward_votes[root[s]];
    const bool turn_group = vote < 0;
    if (static_cast<bool>(parity[s]) != turn_group) planes[s] = planes[s].flipped();
  }
}

}  // namespace detail
}  // namespace paco
