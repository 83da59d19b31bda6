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

// Ray parity: a ray leaving a closed surface outwards crosses it an even number of times before
// it leaves the object, one leaving inwards an odd number. Rays per segment (its points evenly
// spread), fewer when there are so many segments that the plane tests (each ray tests every
// plane) would exceed a budget of about a second ...
constexpr std::size_t kParityRaysPerSegment = 24;
constexpr double kMaxPlaneTests = 1e8;
// ... a crossing counts where another segment has this many points within this many point
// spacings of it: inside a face sampled at that spacing there are about 12, along its rim about
// half as many, at a corner a quarter (with 1.5 spacings and 4 points, most rays across a
// sheet-metal channel 0.05 thick missed a wall, and its inner faces stayed turned) ...
constexpr double kCrossingRadiusSpacings = 2.0;
constexpr std::size_t kMinCrossingPoints = 3;
// ... planes the ray meets at a grazing angle (cosine below this) are not counted: where it
// crosses them is too uncertain ...
constexpr double kMinCrossingCosine = 0.2;
// ... and a group follows the rays when this share of the rays cast tell (on a partial scan most
// leave through its holes and say nothing, and a few that tell are too few to trust), and this
// share of those agree. Shares of 0.1, 0.3 and 0.5 orient the same number of validation
// segments within one (paco_orientation_check, doc/segmentation.md).
constexpr double kMinTellingShare = 0.3;
constexpr double kMinParityShare = 0.7;
// A group whose rays disagree is split in two only when each part has at least this many rays
// that tell, two segments' worth: a part of one small segment, whose far side a partial scan
// often lacks, would follow its own few rays.
constexpr std::size_t kMinSplitPartRays = 2 * kParityRaysPerSegment;

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

// What the rays of one segment, or of a group, say about its normal.
struct RayVerdict {
  long vote = 0;            // +1 per ray saying the normal faces out, -1 per ray saying in
  std::size_t cast = 0;     // rays cast
  std::size_t telling = 0;  // rays that said either

  bool tellsEnough() const {
    return telling > 0 && static_cast<double>(telling) >= kMinTellingShare * static_cast<double>(cast);
  }
  bool agrees() const { return static_cast<double>(std::abs(vote)) >= kMinParityShare * static_cast<double>(telling); }
  bool decisive() const { return tellsEnough() && agrees(); }
  // Adds another segment's verdict, whose normal is turned against this one's when `turned`.
  void add(const RayVerdict& other, bool turned) {
    vote += turned ? -other.vote : other.vote;
    cast += other.cast;
    telling += other.telling;
  }
};

// What a ray can cross: the segments, with a bounding sphere each so that most planes are ruled
// out before a neighbour search. Without the spheres, the milk-carton scan segmented into 428
// planes took 1.6 s instead of 0.23 s without rays; with them, 0.27 s.
struct RayScene {
  const PreparedCloud& prepared;
  const std::vector<int>& segment_of;
  const std::vector<Plane>& planes;
  std::vector<Eigen::Vector3d> centres;
  std::vector<double> extents;  // largest distance of a segment's point from its centre
  double spacing = 0.0;
  double radius = 0.0;  // of the search for a crossed segment's points
  std::size_t rays_per_segment = kParityRaysPerSegment;

  RayScene(const PreparedCloud& cloud, const std::vector<int>& labels, const std::vector<Plane>& segment_planes,
           const std::vector<std::vector<int>>& members, double point_spacing)
      : prepared(cloud), segment_of(labels), planes(segment_planes), centres(members.size(), Eigen::Vector3d::Zero()),
        extents(members.size(), 0.0), spacing(point_spacing), radius(kCrossingRadiusSpacings * point_spacing) {
    const double segments = static_cast<double>(members.size());
    const double affordable = kMaxPlaneTests / std::max(1.0, 2.0 * segments * segments);
    if (affordable < static_cast<double>(kParityRaysPerSegment))
      rays_per_segment = std::max<std::size_t>(1, static_cast<std::size_t>(affordable));
    for (std::size_t s = 0; s < members.size(); ++s) {
      for (const int i : members[s]) centres[s] += position(i);
      if (!members[s].empty()) centres[s] /= static_cast<double>(members[s].size());
      for (const int i : members[s]) extents[s] = std::max(extents[s], (position(i) - centres[s]).norm());
    }
  }
  Eigen::Vector3d position(int i) const { return (*prepared.points)[static_cast<std::size_t>(i)].getVector3fMap().cast<double>(); }

  // How many times a ray from `origin` along `direction` crosses the surface of segments other
  // than `own`. A segment is crossed where kMinCrossingPoints of its points lie within `radius`
  // of the ray's hit on its plane. Hits closer than a point spacing to the origin or to each
  // other are layers of one surface, not two (a face split into parallel segments by noise or
  // by two passes of a scanner that do not quite agree); a wall that thin cannot be resolved at
  // that spacing anyway.
  std::size_t crossings(std::size_t own, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction) const {
    std::vector<double> hits;
    pcl::Indices found;
    std::vector<float> sq_distances;
    for (std::size_t t = 0; t < planes.size(); ++t) {
      if (t == own) continue;
      const double along = planes[t].normal.dot(direction);
      if (std::abs(along) < kMinCrossingCosine) continue;
      const double distance = -planes[t].signedDistance(origin) / along;
      if (distance < spacing) continue;
      const Eigen::Vector3d at = origin + distance * direction;
      if ((at - centres[t]).norm() > extents[t] + radius) continue;
      pcl::PointNormal query;
      query.getVector3fMap() = at.cast<float>();
      if (prepared.tree->radiusSearch(query, radius, found, sq_distances) < static_cast<int>(kMinCrossingPoints)) continue;
      const auto on_t = std::count_if(found.begin(), found.end(), [&](const auto j) {
        return segment_of[static_cast<std::size_t>(j)] == static_cast<int>(t);
      });
      if (static_cast<std::size_t>(on_t) >= kMinCrossingPoints) hits.push_back(distance);
    }
    std::sort(hits.begin(), hits.end());
    std::size_t count = 0;
    for (std::size_t h = 0; h < hits.size(); ++h)
      if (h == 0 || hits[h] - hits[h - 1] > spacing) ++count;
    return count;
  }

  // +1 for each ray of segment `s` (`members`) that says `normal` faces out (an even number of
  // crossings ahead of it and an odd number behind), -1 for each that says it faces in; rays that
  // cross both ways evenly (they leave through a hole in the scan) or both oddly say nothing.
  long vote(std::size_t s, const std::vector<int>& members, const Eigen::Vector3d& normal, std::size_t& rays_cast,
            std::size_t& rays_that_tell) const {
    long total = 0;
    const std::size_t step = std::max<std::size_t>(1, members.size() / rays_per_segment);
    for (std::size_t k = 0; k < members.size(); k += step) {
      const Eigen::Vector3d origin = position(members[k]);
      ++rays_cast;
      const bool ahead_odd = crossings(s, origin, normal) % 2 == 1;
      const bool behind_odd = crossings(s, origin, -normal) % 2 == 1;
      if (ahead_odd == behind_odd) continue;
      ++rays_that_tell;
      total += behind_odd ? 1 : -1;
    }
    return total;
  }
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
  // Which segments mostly had given normals: they keep their orientation, and vote for their
  // group's.
  std::vector<bool> mostly_given(segments, false);
  for (std::size_t s = 0; s < segments; ++s) {
    const auto given = std::count_if(members[s].begin(), members[s].end(), [&](const int i) {
      return !prepared.estimated_normal[static_cast<std::size_t>(i)];
    });
    mostly_given[s] = 2 * static_cast<std::size_t>(given) > members[s].size();
  }
  // What each segment's rays say, in its own plane's orientation.
  const RayScene scene(prepared, segment_of, planes, members, spacing);
  std::vector<RayVerdict> rays(segments);
  for (std::size_t s = 0; s < segments; ++s)
    if (!mostly_given[s]) rays[s].vote = scene.vote(s, members[s], planes[s].normal, rays[s].cast, rays[s].telling);

  // The spanning forest over the relations not dropped; `joined` marks the relations it used.
  std::vector<bool> dropped(relations.size(), false);
  const auto forest = [&](std::vector<bool>& joined) {
    ParityUnionFind groups(segments);
    joined.assign(relations.size(), false);
    for (std::size_t k = 0; k < relations.size(); ++k)
      if (!dropped[k]) joined[k] = groups.join(relations[k].a, relations[k].b, relations[k].flip);
    return groups;
  };
  // The rays of each group (indexed by its root), in the root's orientation.
  const auto group_rays = [&](ParityUnionFind& groups) {
    std::vector<RayVerdict> verdicts(segments);
    for (std::size_t s = 0; s < segments; ++s) {
      const auto [root, parity] = groups.find(s);
      verdicts[root].add(rays[s], parity != 0);
    }
    return verdicts;
  };
  std::vector<bool> joined;
  ParityUnionFind groups = forest(joined);

  // A group whose rays tell but disagree may hold a false relation: points seen through a thin
  // wall make an edge between its two sides (3 points each side in PCL RANSAC's segments of a U
  // channel, 27 in CGAL's). The relation whose removal leaves two parts whose rays each agree,
  // with kMinSplitPartRays that tell in each, is dropped (the one with the most rays behind its
  // parts, if several). One split per group.
  {
    const std::vector<RayVerdict> verdicts = group_rays(groups);
    bool any = false;
    for (std::size_t g = 0; g < segments; ++g) {
      if (!verdicts[g].tellsEnough() || verdicts[g].agrees() || groups.find(g).first != g) continue;
      std::size_t best = relations.size();
      long best_votes = 0;
      for (std::size_t k = 0; k < relations.size(); ++k) {
        if (!joined[k] || groups.find(relations[k].a).first != g) continue;
        dropped[k] = true;
        std::vector<bool> split_joined;
        ParityUnionFind split = forest(split_joined);
        const std::vector<RayVerdict> parts = group_rays(split);
        const RayVerdict& a = parts[split.find(relations[k].a).first];
        const RayVerdict& b = parts[split.find(relations[k].b).first];
        const long votes = std::abs(a.vote) + std::abs(b.vote);
        const bool substantial = a.telling >= kMinSplitPartRays && b.telling >= kMinSplitPartRays;
        if (substantial && a.decisive() && b.decisive() && votes > best_votes) {
          best = k;
          best_votes = votes;
        }
        dropped[k] = false;
      }
      if (best < relations.size()) {
        dropped[best] = true;
        any = true;
      }
    }
    if (any) groups = forest(joined);
  }

  // Each group's orientation as a whole: given normals vote first, then rays (when enough of them
  // tell and agree), else away from the centre. Away from the centre is right for the outer hull
  // but wrong for every face of a cavity that no edge relation ties to the hull: the inner faces
  // of a sheet-metal channel, whose rims are too thin to segment, face the centre. Rays tell them.
  const std::vector<RayVerdict> final_rays = group_rays(groups);
  std::vector<long> given_votes(segments, 0), outward_votes(segments, 0);
  std::vector<int> parity(segments, 0);
  std::vector<std::size_t> root(segments, 0);
  for (std::size_t s = 0; s < segments; ++s) {
    std::tie(root[s], parity[s]) = groups.find(s);
    const double sign = parity[s] ? -1.0 : 1.0;  // this segment's normal in its root's orientation
    const Eigen::Vector3d n = sign * planes[s].normal;
    for (const int i : members[s]) {
      const auto& p = points[static_cast<std::size_t>(i)];
      const Eigen::Vector3d position = p.getVector3fMap().cast<double>();
      const double outward = n.dot(position);  // the box centre is the origin of the working frame
      outward_votes[root[s]] += outward > 0.0 ? 1 : (outward < 0.0 ? -1 : 0);
      if (prepared.estimated_normal[static_cast<std::size_t>(i)]) continue;
      const double agreement = n.dot(p.getNormalVector3fMap().cast<double>());
      given_votes[root[s]] += agreement > 0.0 ? 1 : (agreement < 0.0 ? -1 : 0);
    }
  }
  for (std::size_t s = 0; s < segments; ++s) {
    if (mostly_given[s]) continue;
    const std::size_t group = root[s];
    const long vote = given_votes[group] != 0      ? given_votes[group]
                      : final_rays[group].decisive() ? final_rays[group].vote
                                                     : outward_votes[group];
    const bool turn_group = vote < 0;
    if (static_cast<bool>(parity[s]) != turn_group) planes[s] = planes[s].flipped();
  }
}

}  // namespace detail
}  // namespace paco
