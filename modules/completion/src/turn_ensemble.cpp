#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/completion/parametric_completer.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/encoding/plane_proxy_encoder.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <string>

namespace paco {
namespace {


// One predicted primitive of one run.
struct Vote {
  const PlanarPrimitive* primitive;
  std::size_t run;
};

// The predictions taken as one face.
struct Group {
  Plane representative;                 // the most confident member's plane
  std::vector<Vote> members;
  std::vector<float> best_per_run;      // the best member confidence of each run, 0 if none
};

double meanDistance(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& plane) {
  if (points.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& p : points) sum += std::abs(plane.signedDistance(p.getVector3fMap().cast<double>()));
  return sum / static_cast<double>(points.size());
}

PlanarPrimitive mergeGroup(const Group& group, std::size_t runs) {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  double offset = 0.0, weight = 0.0;
  for (const Vote& v : group.members) {
    const double w = std::max(1e-6, static_cast<double>(v.primitive->confidence));
    normal += w * v.primitive->plane.normal;
    offset += w * v.primitive->plane.offset;
    weight += w;
  }
  PlanarPrimitive merged;
  // Members are within max_angle of the representative, so the weighted sum cannot vanish.
  merged.plane = Plane(normal / weight, offset / weight);
  merged.confidence = static_cast<float>(
      std::accumulate(group.best_per_run.begin(), group.best_per_run.end(), 0.0) / static_cast<double>(runs));

  std::size_t total = 0;
  for (const Vote& v : group.members) total += v.primitive->points.size();
  // The most confident member's count: the network's points per primitive, whatever the turns.
  const std::size_t keep = std::min(total, group.members.front().primitive->points.size());
  merged.points.reserve(keep);
  const Eigen::Vector3f n = merged.plane.normal.cast<float>();
  std::size_t index = 0, next = 0;
  for (const Vote& v : group.members) {
    for (const auto& p : v.primitive->points) {
      // Evenly spaced over the members' points, in member order.
      if (next < keep && index == next * total / keep) {
        pcl::PointNormal q = p;
        q.getVector3fMap() = merged.plane.project(p.getVector3fMap().cast<double>()).cast<float>();
        q.normal_x = n.x();
        q.normal_y = n.y();
        q.normal_z = n.z();
        merged.points.push_back(q);
        ++next;
      }
      ++index;
    }
  }
  merged.points.width = static_cast<std::uint32_t>(merged.points.size());
  merged.points.height = 1;
  merged.points.is_dense = true;
  return merged;
}

}  // namespace

std::vector<Eigen::Matrix3d> ensembleTurns(int count) {
  if (count < 1 || count > kMaxEnsembleTurns)
    throw InvalidInputError("ensembleTurns: " + std::to_string(count) + " turns; take 1 to " +
                            std::to_string(kMaxEnsembleTurns));
  // The signed permutation matrices of determinant +1: every rotation mapping axes to axes.
  std::vector<Eigen::Matrix3d> diagonal, others;
  int permutation[3] = {0, 1, 2};
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
      for (int row = 0; row < 3; ++row) r(row, permutation[row]) = (signs >> row) & 1 ? -1.0 : 1.0;
      if (r.determinant() < 0.0) continue;
      (r.cwiseAbs().isIdentity() ? diagonal : others).push_back(r);
    }
  } while (std::next_permutation(permutation, permutation + 3));
  // diagonal starts with the identity (no sign flipped), then the three half turns.
  std::vector<Eigen::Matrix3d> turns = diagonal;
  turns.insert(turns.end(), others.begin(), others.end());
  turns.resize(static_cast<std::size_t>(count));
  return turns;
}

std::vector<PlanarPrimitive> mergeTurnPredictions(const std::vector<std::vector<PlanarPrimitive>>& runs,
                                                  double diagonal, const TurnEnsembleOptions& options) {
  if (runs.empty()) throw InvalidInputError("mergeTurnPredictions: no run to merge");
  if (!(diagonal > 0.0) || !std::isfinite(diagonal))
    throw InvalidInputError("mergeTurnPredictions: the diagonal must be a positive number, got " +
                            std::to_string(diagonal));
  if (!(options.threshold >= 0.0 && options.threshold <= 1.0) || !(options.max_angle_degrees > 0.0) ||
      !(options.max_angle_degrees < 90.0) || !(options.max_distance > 0.0) || !std::isfinite(options.max_distance))
    throw InvalidInputError(
        "mergeTurnPredictions: threshold must be in [0, 1], max_angle_degrees in (0, 90) and max_distance > 0");

  std::vector<Vote> votes;
  for (std::size_t r = 0; r < runs.size(); ++r)
    for (const auto& p : runs[r]) votes.push_back({&p, r});
  std::stable_sort(votes.begin(), votes.end(),
                   [](const Vote& a, const Vote& b) { return a.primitive->confidence > b.primitive->confidence; });

  const double min_cos = std::cos(degreesToRadians(options.max_angle_degrees));
  const double max_distance = options.max_distance * diagonal;
  std::vector<Group> groups;
  for (const Vote& v : votes) {
    Group* home = nullptr;
    double best = max_distance;
    for (Group& g : groups) {
      if (g.representative.normal.dot(v.primitive->plane.normal) < min_cos) continue;
      const double d = meanDistance(v.primitive->points, g.representative);
      if (d <= best) {
        best = d;
        home = &g;
      }
    }
    if (!home) {
      groups.push_back({v.primitive->plane, {}, std::vector<float>(runs.size(), 0.0f)});
      home = &groups.back();
    }
    home->members.push_back(v);
    home->best_per_run[v.run] = std::max(home->best_per_run[v.run], v.primitive->confidence);
  }

  std::vector<PlanarPrimitive> merged;
  for (const Group& g : groups) {
    PlanarPrimitive p = mergeGroup(g, runs.size());
    if (p.confidence > options.threshold) merged.push_back(std::move(p));
  }
  std::stable_sort(merged.begin(), merged.end(),
                   [](const PlanarPrimitive& a, const PlanarPrimitive& b) { return a.confidence > b.confidence; });
  return merged;
}

std::vector<PlanarPrimitive> completeWithTurns(const CompletionModel::ConstPtr& model,
                                               const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                               const PlanarSegmentation& segmentation,
                                               const TurnEnsembleOptions& options, Normalization* frame) {
  if (!(options.candidate_threshold >= 0.0 && options.candidate_threshold <= 1.0))
    throw InvalidInputError("completeWithTurns: candidate_threshold must be in [0, 1], got " +
                            std::to_string(options.candidate_threshold));
  const std::vector<Eigen::Matrix3d> turns = ensembleTurns(options.turns);
  PlaneProxyEncoder encoder;
  encoder.setModel(model);
  encoder.setInputCloud(cloud);
  encoder.setSegmentation(segmentation);
  encoder.setNumPoints(options.num_points);
  ParametricCompleter completer;
  completer.setModel(model);
  if (turns.size() == 1) {  // no vote: exactly the completer's result
    PlaneProxies proxies;
    encoder.encode(proxies);
    if (frame) *frame = proxies.normalization;
    completer.setConfidenceThreshold(options.threshold);
    completer.setInputProxies(proxies);
    std::vector<PlanarPrimitive> primitives;
    completer.complete(primitives);
    return primitives;
  }
  completer.setConfidenceThreshold(std::min(options.candidate_threshold, options.threshold));
  std::vector<std::vector<PlanarPrimitive>> runs(turns.size());
  for (std::size_t t = 0; t < turns.size(); ++t) {
    encoder.setTurn(turns[t]);
    PlaneProxies proxies;
    encoder.encode(proxies);
    if (frame && t == 0) *frame = proxies.normalization;  // turns[0] is the identity
    completer.setInputProxies(proxies);
    completer.complete(runs[t]);
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : cloud->points) {
    lo = lo.cwiseMin(p.getVector3fMap().cast<double>());
    hi = hi.cwiseMax(p.getVector3fMap().cast<double>());
  }
  return mergeTurnPredictions(runs, (hi - lo).norm(), options);
}

}  // namespace paco
