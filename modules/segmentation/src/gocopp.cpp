// Our implementation of GoCoPP (Yu & Lafarge, "Finding good configurations of planar primitives
// in unorganized point clouds", CVPR 2022). Differences from the authors' program: ε stays
// relative to the bounding-box diagonal (never rounded to absolute units), and a split is refused
// when its two planes coincide within ε (on noisy planes, two-plane clustering otherwise "splits"
// a plane into the points above and below it).
#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/segmentation/gocopp_segmenter.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <queue>
#include <string>
#include <utility>

namespace paco {

namespace {

constexpr double kEnergyTolerance = 1e-12;

Eigen::Vector3d positionOf(const pcl::PointNormal& p) { return p.getVector3fMap().cast<double>(); }
Eigen::Vector3d normalOf(const pcl::PointNormal& p) { return p.getNormalVector3fMap().cast<double>(); }
bool hasNormal(const pcl::PointNormal& p) { return p.getNormalVector3fMap().squaredNorm() > 0.5f; }

/// Running first and second moments of a point set, for O(1) plane refits while growing.
struct Moments {
  double count = 0.0;
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outer = Eigen::Matrix3d::Zero();
  void add(const Eigen::Vector3d& p) {
    count += 1.0;
    sum += p;
    outer.noalias() += p * p.transpose();
  }
  bool plane(Eigen::Vector3d& normal, double& offset) const {
    if (count < 3.0) return false;
    const Eigen::Vector3d mean = sum / count;
    const Eigen::Matrix3d covariance = outer / count - mean * mean.transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    if (!(solver.eigenvalues()(1) > 1e-14)) return false;
    normal = solver.eigenvectors().col(0).normalized();
    if (!normal.allFinite()) return false;
    offset = -normal.dot(mean);
    return true;
  }
};

}  // namespace

void GoCoPPParameters::validate() const {
  auto fail = [](const std::string& what) { throw InvalidInputError("GoCoPP: " + what); };
  if (!(epsilon > 0.0) || !std::isfinite(epsilon)) fail("epsilon must be > 0; got " + std::to_string(epsilon));
  if (!(normal_threshold >= 0.0 && normal_threshold <= 1.0))
    fail("normal_threshold is a |cosine| in [0, 1]; got " + std::to_string(normal_threshold));
  if (min_points < 3) fail("min_points must be >= 3; got " + std::to_string(min_points));
  if (neighbours < 3) fail("neighbours must be >= 3; got " + std::to_string(neighbours));
  if (!(lambda_simplicity >= 0.0 && lambda_completeness >= 0.0 && lambda_simplicity + lambda_completeness < 3.0))
    fail("lambda_simplicity and lambda_completeness must be >= 0 with a sum below 3; got " +
         std::to_string(lambda_simplicity) + " and " + std::to_string(lambda_completeness));
  if (max_rounds < 0) fail("max_rounds must be >= 0; got " + std::to_string(max_rounds));
}

GoCoPPOptimizer::GoCoPPOptimizer(const pcl::PointCloud<pcl::PointNormal>& points,
                                 const std::vector<std::vector<int>>& neighbours,
                                 const GoCoPPParameters& parameters)
    : points_(points), neighbours_(neighbours), parameters_(parameters) {
  parameters_.validate();
  if (neighbours_.size() != points_.size())
    throw InvalidInputError("GoCoPP: " + std::to_string(neighbours_.size()) + " neighbour lists for " +
                            std::to_string(points_.size()) + " points");
  label_.assign(points_.size(), -1);
}

// ---------------------------------------------------------------------------------------------
// Energy

double GoCoPPOptimizer::energyOf(double distance_sum, double assigned, double primitives) const {
  const double n = static_cast<double>(points_.size());
  if (n <= 0.0) return 0.0;
  const double ls = parameters_.lambda_simplicity, lc = parameters_.lambda_completeness;
  const double fidelity = assigned > 0.0 ? distance_sum / (assigned * parameters_.epsilon) : 0.0;
  const double simplicity = primitives * parameters_.min_points / n;
  const double completeness = (n - assigned) / n;
  return ((3.0 - ls - lc) * fidelity + ls * simplicity + lc * completeness) / 3.0;
}

double GoCoPPOptimizer::deltaEnergy(const Proposal& p) const {
  const double before = energyOf(total_distance_, static_cast<double>(assigned_), static_cast<double>(alive_));
  const double after = energyOf(total_distance_ + p.delta_distance, static_cast<double>(assigned_ + p.delta_assigned),
                                static_cast<double>(alive_ + p.delta_primitives));
  return after - before;
}

GoCoPPEnergy GoCoPPOptimizer::energy() const {
  GoCoPPEnergy e;
  const double n = static_cast<double>(points_.size());
  if (n <= 0.0) return e;
  e.fidelity = assigned_ > 0 ? total_distance_ / (static_cast<double>(assigned_) * parameters_.epsilon) : 0.0;
  e.simplicity = static_cast<double>(alive_) * parameters_.min_points / n;
  e.completeness = (n - static_cast<double>(assigned_)) / n;
  e.total = energyOf(total_distance_, static_cast<double>(assigned_), static_cast<double>(alive_));
  return e;
}

// ---------------------------------------------------------------------------------------------
// Primitive bookkeeping

bool GoCoPPOptimizer::fit(const std::vector<int>& members, Eigen::Vector3d& normal, double& offset) const {
  if (members.size() < 3) return false;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const int i : members) mean += positionOf(points_[static_cast<std::size_t>(i)]);
  mean /= static_cast<double>(members.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const int i : members) {
    const Eigen::Vector3d q = positionOf(points_[static_cast<std::size_t>(i)]) - mean;
    covariance.noalias() += q * q.transpose();
  }
  covariance /= static_cast<double>(members.size());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
  solver.computeDirect(covariance);
  if (!(solver.eigenvalues()(1) > 1e-14)) return false;
  normal = solver.eigenvectors().col(0).normalized();
  if (!normal.allFinite()) return false;
  offset = -normal.dot(mean);
  return true;
}

double GoCoPPOptimizer::distance(int point, const Eigen::Vector3d& normal, double offset) const {
  return std::abs(normal.dot(positionOf(points_[static_cast<std::size_t>(point)])) + offset);
}

double GoCoPPOptimizer::distanceSum(const std::vector<int>& members, const Eigen::Vector3d& normal,
                                    double offset) const {
  double sum = 0.0;
  for (const int i : members) sum += distance(i, normal, offset);
  return sum;
}

int GoCoPPOptimizer::addPrimitive(std::vector<int> members) {
  Primitive p;
  if (!fit(members, p.normal, p.offset)) return -1;
  p.distance_sum = distanceSum(members, p.normal, p.offset);
  p.members = std::move(members);
  p.alive = true;
  const int id = static_cast<int>(primitives_.size());
  for (const int i : p.members) label_[static_cast<std::size_t>(i)] = id;
  total_distance_ += p.distance_sum;
  assigned_ += static_cast<long>(p.members.size());
  ++alive_;
  primitives_.push_back(std::move(p));
  merged_into_.push_back(-1);
  return id;
}

int GoCoPPOptimizer::resolve(int id) const {
  while (id >= 0 && merged_into_[static_cast<std::size_t>(id)] >= 0) id = merged_into_[static_cast<std::size_t>(id)];
  return id;
}

int GoCoPPOptimizer::idOfCompact(int compact) const {
  int seen = 0;
  for (std::size_t id = 0; id < primitives_.size(); ++id) {
    if (!primitives_[id].alive) continue;
    if (seen == compact) return static_cast<int>(id);
    ++seen;
  }
  throw InvalidInputError("GoCoPP: no primitive " + std::to_string(compact) + "; there are " +
                          std::to_string(alive_));
}

std::vector<int> GoCoPPOptimizer::labels() const {
  std::vector<int> compact(primitives_.size(), -1);
  int next = 0;
  for (std::size_t id = 0; id < primitives_.size(); ++id)
    if (primitives_[id].alive) compact[id] = next++;
  std::vector<int> result(label_.size(), -1);
  for (std::size_t i = 0; i < label_.size(); ++i)
    if (label_[i] >= 0) result[i] = compact[static_cast<std::size_t>(label_[i])];
  return result;
}

std::size_t GoCoPPOptimizer::numPrimitives() const { return static_cast<std::size_t>(alive_); }

void GoCoPPOptimizer::setLabels(const std::vector<int>& labels) {
  if (labels.size() != points_.size())
    throw InvalidInputError("GoCoPP::setLabels: " + std::to_string(labels.size()) + " labels for " +
                            std::to_string(points_.size()) + " points");
  primitives_.clear();
  merged_into_.clear();
  label_.assign(points_.size(), -1);
  total_distance_ = 0.0;
  assigned_ = 0;
  alive_ = 0;
  int max_label = -1;
  for (const int l : labels) max_label = std::max(max_label, l);
  std::vector<std::vector<int>> groups(static_cast<std::size_t>(max_label + 1));
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] >= 0) groups[static_cast<std::size_t>(labels[i])].push_back(static_cast<int>(i));
  for (auto& g : groups)
    if (!g.empty()) addPrimitive(std::move(g));
}

// ---------------------------------------------------------------------------------------------
// Region growing

void GoCoPPOptimizer::growRegions() {
  setLabels(std::vector<int>(points_.size(), -1));
  const std::size_t n = points_.size();
  const double eps = parameters_.epsilon, tau = parameters_.normal_threshold;

  // Flattest points first: mean distance of the neighbours to the point's tangent plane.
  std::vector<double> flatness(n, std::numeric_limits<double>::infinity());
  for (std::size_t i = 0; i < n; ++i) {
    if (!hasNormal(points_[i]) || neighbours_[i].empty()) continue;
    const Eigen::Vector3d p = positionOf(points_[i]), normal = normalOf(points_[i]);
    double sum = 0.0;
    for (const int j : neighbours_[i]) sum += std::abs(normal.dot(positionOf(points_[static_cast<std::size_t>(j)]) - p));
    flatness[i] = sum / static_cast<double>(neighbours_[i].size());
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return flatness[static_cast<std::size_t>(a)] < flatness[static_cast<std::size_t>(b)];
  });

  constexpr int kGrowing = -2;
  std::vector<char> may_seed(n, 1);
  std::vector<int> region;
  for (const int seed : order) {
    const auto s = static_cast<std::size_t>(seed);
    if (label_[s] != -1 || !may_seed[s] || !std::isfinite(flatness[s])) continue;
    Eigen::Vector3d normal = normalOf(points_[s]);
    double offset = -normal.dot(positionOf(points_[s]));
    Moments moments;
    moments.add(positionOf(points_[s]));
    region.assign(1, seed);
    label_[s] = kGrowing;
    std::size_t next_fit = 8;
    for (std::size_t head = 0; head < region.size(); ++head) {
      for (const int j : neighbours_[static_cast<std::size_t>(region[head])]) {
        const auto& q = points_[static_cast<std::size_t>(j)];
        if (label_[static_cast<std::size_t>(j)] != -1) continue;
        const Eigen::Vector3d x = positionOf(q);
        if (std::abs(normal.dot(x) + offset) > eps) continue;
        if (hasNormal(q) && std::abs(normalOf(q).dot(normal)) < tau) continue;
        label_[static_cast<std::size_t>(j)] = kGrowing;
        region.push_back(j);
        moments.add(x);
        if (region.size() >= next_fit) {
          // Refit as the region doubles: the plane follows the data without O(n^2) work.
          Eigen::Vector3d fitted_normal;
          double fitted_offset;
          if (moments.plane(fitted_normal, fitted_offset)) {
            normal = fitted_normal;
            offset = fitted_offset;
          }
          next_fit = region.size() * 2;
        }
      }
    }
    if (static_cast<int>(region.size()) < parameters_.min_points) {
      for (const int i : region) {
        label_[static_cast<std::size_t>(i)] = -1;
        may_seed[static_cast<std::size_t>(i)] = 0;
      }
      continue;
    }
    if (addPrimitive(region) < 0)
      for (const int i : region) label_[static_cast<std::size_t>(i)] = -1;
  }
}

// ---------------------------------------------------------------------------------------------
// Operators: proposals

bool GoCoPPOptimizer::proposeMerge(int a, int b, Proposal& p) const {
  const auto& pa = primitives_[static_cast<std::size_t>(a)];
  const auto& pb = primitives_[static_cast<std::size_t>(b)];
  if (!pa.alive || !pb.alive || a == b) return false;
  std::vector<int> merged;
  merged.reserve(pa.members.size() + pb.members.size());
  merged.insert(merged.end(), pa.members.begin(), pa.members.end());
  merged.insert(merged.end(), pb.members.begin(), pb.members.end());
  Eigen::Vector3d normal;
  double offset;
  if (!fit(merged, normal, offset)) return false;
  std::vector<int> kept;
  kept.reserve(merged.size());
  for (int pass = 0; pass < 2; ++pass) {
    kept.clear();
    for (const int i : merged)
      if (distance(i, normal, offset) <= parameters_.epsilon) kept.push_back(i);
    if (static_cast<int>(kept.size()) < parameters_.min_points) return false;
    if (pass == 0 && kept.size() < merged.size() && !fit(kept, normal, offset)) return false;
    if (kept.size() == merged.size()) break;
  }
  p = Proposal{};
  p.kind = Proposal::Kind::Merge;
  p.a = a;
  p.b = b;
  const double sum = distanceSum(kept, normal, offset);
  p.delta_distance = sum - pa.distance_sum - pb.distance_sum;
  p.delta_assigned = static_cast<long>(kept.size()) - static_cast<long>(merged.size());
  p.delta_primitives = -1;
  p.addGroup(std::move(kept), normal, offset, sum);
  return true;
}

bool GoCoPPOptimizer::proposeSplit(int a, Proposal& p) const {
  const auto& pa = primitives_[static_cast<std::size_t>(a)];
  const auto& members = pa.members;
  const std::size_t m = members.size();
  if (!pa.alive || static_cast<int>(m) < 2 * parameters_.min_points) return false;

  // Two initial partitions: by the tilt of the point normals against the plane (a ridge), and
  // by position along the main in-plane axis. Each is refined by two-plane clustering.
  std::vector<std::vector<char>> starts;
  {
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    std::vector<Eigen::Vector3d> tilts(m, Eigen::Vector3d::Zero());
    for (std::size_t k = 0; k < m; ++k) {
      const auto& q = points_[static_cast<std::size_t>(members[k])];
      if (!hasNormal(q)) continue;
      Eigen::Vector3d n = normalOf(q);
      if (n.dot(pa.normal) < 0) n = -n;
      tilts[k] = n - n.dot(pa.normal) * pa.normal;
      covariance.noalias() += tilts[k] * tilts[k].transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    if (solver.eigenvalues()(2) > 1e-12) {
      const Eigen::Vector3d axis = solver.eigenvectors().col(2);
      std::vector<char> side(m);
      for (std::size_t k = 0; k < m; ++k) side[k] = tilts[k].dot(axis) > 0 ? 1 : 0;
      starts.push_back(std::move(side));
    }
  }
  {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const int i : members) mean += positionOf(points_[static_cast<std::size_t>(i)]);
    mean /= static_cast<double>(m);
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const int i : members) {
      const Eigen::Vector3d q = positionOf(points_[static_cast<std::size_t>(i)]) - mean;
      covariance.noalias() += q * q.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver;
    solver.computeDirect(covariance);
    const Eigen::Vector3d axis = solver.eigenvectors().col(2);
    std::vector<char> side(m);
    for (std::size_t k = 0; k < m; ++k)
      side[k] = axis.dot(positionOf(points_[static_cast<std::size_t>(members[k])]) - mean) > 0 ? 1 : 0;
    starts.push_back(std::move(side));
  }

  bool found = false;
  double best_sum = pa.distance_sum;
  std::vector<int> group[2];
  Eigen::Vector3d normal[2];
  double offset[2];
  for (auto& side : starts) {
    std::vector<int> g[2];
    Eigen::Vector3d n[2];
    double d[2];
    bool ok = true;
    for (int iteration = 0; iteration < 10; ++iteration) {
      g[0].clear();
      g[1].clear();
      for (std::size_t k = 0; k < m; ++k) g[side[k] ? 1 : 0].push_back(members[k]);
      if (static_cast<int>(g[0].size()) < parameters_.min_points || static_cast<int>(g[1].size()) < parameters_.min_points ||
          !fit(g[0], n[0], d[0]) || !fit(g[1], n[1], d[1])) {
        ok = false;
        break;
      }
      std::size_t moved = 0;
      for (std::size_t k = 0; k < m; ++k) {
        const char nearer = distance(members[k], n[1], d[1]) < distance(members[k], n[0], d[0]) ? 1 : 0;
        if (nearer != side[k]) {
          side[k] = nearer;
          ++moved;
        }
      }
      if (moved == 0) break;
      if (iteration == 9) {  // not converged: use the last consistent partition
        g[0].clear();
        g[1].clear();
        for (std::size_t k = 0; k < m; ++k) g[side[k] ? 1 : 0].push_back(members[k]);
        ok = static_cast<int>(g[0].size()) >= parameters_.min_points &&
             static_cast<int>(g[1].size()) >= parameters_.min_points && fit(g[0], n[0], d[0]) && fit(g[1], n[1], d[1]);
      }
    }
    if (!ok) continue;
    // Two planes that coincide within ε are one plane split into its points above and below.
    Eigen::Vector3d centroid[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
    for (int s = 0; s < 2; ++s) {
      for (const int i : g[s]) centroid[s] += positionOf(points_[static_cast<std::size_t>(i)]);
      centroid[s] /= static_cast<double>(g[s].size());
    }
    if (std::abs(n[0].dot(centroid[1]) + d[0]) <= parameters_.epsilon &&
        std::abs(n[1].dot(centroid[0]) + d[1]) <= parameters_.epsilon)
      continue;
    const double sum = distanceSum(g[0], n[0], d[0]) + distanceSum(g[1], n[1], d[1]);
    if (!found || sum < best_sum) {
      found = true;
      best_sum = sum;
      for (int s = 0; s < 2; ++s) {
        group[s] = g[s];
        normal[s] = n[s];
        offset[s] = d[s];
      }
    }
  }
  if (!found) return false;
  p = Proposal{};
  p.kind = Proposal::Kind::Split;
  p.a = a;
  for (int s = 0; s < 2; ++s) {
    const double sum = distanceSum(group[s], normal[s], offset[s]);
    p.addGroup(std::move(group[s]), normal[s], offset[s], sum);
  }
  p.delta_distance = best_sum - pa.distance_sum;
  p.delta_assigned = 0;
  p.delta_primitives = 1;
  return true;
}

bool GoCoPPOptimizer::proposeInsert(int a, Proposal& p) const {
  const auto& pa = primitives_[static_cast<std::size_t>(a)];
  if (!pa.alive) return false;
  std::vector<int> candidates;
  for (const int i : pa.members)
    for (const int j : neighbours_[static_cast<std::size_t>(i)]) {
      if (label_[static_cast<std::size_t>(j)] != -1) continue;
      const auto& q = points_[static_cast<std::size_t>(j)];
      if (distance(j, pa.normal, pa.offset) > parameters_.epsilon) continue;
      if (hasNormal(q) && std::abs(normalOf(q).dot(pa.normal)) < parameters_.normal_threshold) continue;
      candidates.push_back(j);
    }
  if (candidates.empty()) return false;
  std::sort(candidates.begin(), candidates.end());
  candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
  std::vector<int> grown = pa.members;
  grown.insert(grown.end(), candidates.begin(), candidates.end());
  Eigen::Vector3d normal;
  double offset;
  if (!fit(grown, normal, offset)) return false;
  p = Proposal{};
  p.kind = Proposal::Kind::Insert;
  p.a = a;
  const double sum = distanceSum(grown, normal, offset);
  p.delta_distance = sum - pa.distance_sum;
  p.delta_assigned = static_cast<long>(candidates.size());
  p.delta_primitives = 0;
  p.addGroup(std::move(grown), normal, offset, sum);
  return true;
}

bool GoCoPPOptimizer::proposeExclude(int a, Proposal& p) const {
  const auto& pa = primitives_[static_cast<std::size_t>(a)];
  if (!pa.alive) return false;
  std::vector<int> kept;
  kept.reserve(pa.members.size());
  for (const int i : pa.members)
    if (distance(i, pa.normal, pa.offset) <= parameters_.epsilon) kept.push_back(i);
  if (kept.size() == pa.members.size() && static_cast<int>(kept.size()) >= parameters_.min_points) return false;
  p = Proposal{};
  p.kind = Proposal::Kind::Exclude;
  p.a = a;
  Eigen::Vector3d normal;
  double offset;
  if (static_cast<int>(kept.size()) < parameters_.min_points || !fit(kept, normal, offset)) {
    p.delta_distance = -pa.distance_sum;  // too few left: the primitive goes
    p.delta_assigned = -static_cast<long>(pa.members.size());
    p.delta_primitives = -1;
    return true;
  }
  const double sum = distanceSum(kept, normal, offset);
  p.delta_distance = sum - pa.distance_sum;
  p.delta_assigned = static_cast<long>(kept.size()) - static_cast<long>(pa.members.size());
  p.delta_primitives = 0;
  p.addGroup(std::move(kept), normal, offset, sum);
  return true;
}

bool GoCoPPOptimizer::propose(Proposal::Kind kind, int a, int b, Proposal& p) const {
  switch (kind) {
    case Proposal::Kind::Merge: return proposeMerge(a, b, p);
    case Proposal::Kind::Split: return proposeSplit(a, p);
    case Proposal::Kind::Insert: return proposeInsert(a, p);
    case Proposal::Kind::Exclude: return proposeExclude(a, p);
  }
  return false;
}

void GoCoPPOptimizer::apply(const Proposal& p) {
  // Release the old members of every primitive involved, then assign the new groups.
  std::vector<int> involved{p.a};
  if (p.kind == Proposal::Kind::Merge) involved.push_back(p.b);
  for (const int id : involved) {
    auto& prim = primitives_[static_cast<std::size_t>(id)];
    for (const int i : prim.members) label_[static_cast<std::size_t>(i)] = -1;
    total_distance_ -= prim.distance_sum;
    assigned_ -= static_cast<long>(prim.members.size());
    --alive_;
    prim.members.clear();
    prim.alive = false;
    ++prim.version;
  }
  if (p.kind == Proposal::Kind::Merge) merged_into_[static_cast<std::size_t>(p.b)] = p.a;
  for (std::size_t g = 0; g < p.groups.size(); ++g) {
    int id = p.a;
    if (g == 1) {
      id = static_cast<int>(primitives_.size());
      primitives_.emplace_back();
      merged_into_.push_back(-1);
    }
    auto& prim = primitives_[static_cast<std::size_t>(id)];
    prim.members = p.groups[g];
    prim.normal = p.normals[g];
    prim.offset = p.offsets[g];
    prim.distance_sum = p.distance_sums[g];
    prim.alive = true;
    ++prim.version;
    for (const int i : prim.members) label_[static_cast<std::size_t>(i)] = id;
    total_distance_ += prim.distance_sum;
    assigned_ += static_cast<long>(prim.members.size());
    ++alive_;
  }
}

bool GoCoPPOptimizer::tryOperator(Proposal::Kind kind, int a, int b) {
  Proposal p;
  if (!propose(kind, a, b, p)) return false;
  if (!(deltaEnergy(p) < -kEnergyTolerance)) return false;
  apply(p);
  return true;
}

bool GoCoPPOptimizer::tryMerge(int a, int b) {
  return tryOperator(Proposal::Kind::Merge, idOfCompact(a), idOfCompact(b));
}
bool GoCoPPOptimizer::trySplit(int a) { return tryOperator(Proposal::Kind::Split, idOfCompact(a), -1); }
bool GoCoPPOptimizer::tryInsert(int a) { return tryOperator(Proposal::Kind::Insert, idOfCompact(a), -1); }
bool GoCoPPOptimizer::tryExclude(int a) { return tryOperator(Proposal::Kind::Exclude, idOfCompact(a), -1); }

// ---------------------------------------------------------------------------------------------
// Transfer

bool GoCoPPOptimizer::transfer() {
  bool improved_any = false;
  for (int pass = 0; pass < 3; ++pass) {
    std::vector<int> new_label = label_;
    std::vector<long> size(primitives_.size(), 0);
    for (std::size_t id = 0; id < primitives_.size(); ++id)
      size[id] = static_cast<long>(primitives_[id].members.size());
    std::vector<char> touched(primitives_.size(), 0);
    std::size_t moved = 0;
    for (std::size_t i = 0; i < points_.size(); ++i) {
      const int a = label_[i];
      if (a < 0 || size[static_cast<std::size_t>(a)] <= parameters_.min_points || !hasNormal(points_[i])) continue;
      const Eigen::Vector3d n = normalOf(points_[i]);
      double best_cos = std::abs(n.dot(primitives_[static_cast<std::size_t>(a)].normal));
      int best = -1;
      for (const int j : neighbours_[i]) {
        const int b = label_[static_cast<std::size_t>(j)];
        if (b < 0 || b == a) continue;
        const auto& pb = primitives_[static_cast<std::size_t>(b)];
        const double c = std::abs(n.dot(pb.normal));
        if (c > best_cos + 1e-9 && distance(static_cast<int>(i), pb.normal, pb.offset) <= parameters_.epsilon) {
          best_cos = c;
          best = b;
        }
      }
      if (best < 0) continue;
      new_label[i] = best;
      --size[static_cast<std::size_t>(a)];
      ++size[static_cast<std::size_t>(best)];
      touched[static_cast<std::size_t>(a)] = touched[static_cast<std::size_t>(best)] = 1;
      ++moved;
    }
    if (moved == 0) break;

    // Rebuild the touched primitives and keep the move only if the energy drops.
    std::vector<std::vector<int>> members(primitives_.size());
    for (std::size_t i = 0; i < points_.size(); ++i)
      if (new_label[i] >= 0 && touched[static_cast<std::size_t>(new_label[i])]) members[static_cast<std::size_t>(new_label[i])].push_back(static_cast<int>(i));
    std::vector<Primitive> updated;
    std::vector<int> updated_ids;
    double new_total = total_distance_;
    bool ok = true;
    for (std::size_t id = 0; id < primitives_.size() && ok; ++id) {
      if (!touched[id]) continue;
      Primitive prim = primitives_[id];
      prim.members = std::move(members[id]);
      if (!fit(prim.members, prim.normal, prim.offset)) {
        ok = false;
        break;
      }
      prim.distance_sum = distanceSum(prim.members, prim.normal, prim.offset);
      new_total += prim.distance_sum - primitives_[id].distance_sum;
      ++prim.version;
      updated.push_back(std::move(prim));
      updated_ids.push_back(static_cast<int>(id));
    }
    if (!ok) break;
    const double before = energyOf(total_distance_, static_cast<double>(assigned_), static_cast<double>(alive_));
    const double after = energyOf(new_total, static_cast<double>(assigned_), static_cast<double>(alive_));
    if (!(after < before - kEnergyTolerance)) break;
    label_ = std::move(new_label);
    for (std::size_t k = 0; k < updated.size(); ++k)
      primitives_[static_cast<std::size_t>(updated_ids[k])] = std::move(updated[k]);
    total_distance_ = new_total;
    improved_any = true;
  }
  return improved_any;
}

// ---------------------------------------------------------------------------------------------
// Rounds

bool GoCoPPOptimizer::runRound() {
  struct Entry {
    double delta;
    Proposal::Kind kind;
    int a, b;
    int version_a, version_b;
    std::size_t proposal;  ///< index into `proposals`
  };
  auto later = [](const Entry& x, const Entry& y) {
    if (x.delta != y.delta) return x.delta > y.delta;
    if (x.kind != y.kind) return x.kind > y.kind;
    if (x.a != y.a) return x.a > y.a;
    return x.b > y.b;
  };
  std::priority_queue<Entry, std::vector<Entry>, decltype(later)> queue(later);
  std::vector<Proposal> proposals;
  auto versionOf = [&](int id) { return id < 0 ? 0 : primitives_[static_cast<std::size_t>(id)].version; };
  auto consider = [&](Proposal::Kind kind, int a, int b) {
    Proposal p;
    if (!propose(kind, a, b, p)) return;
    const double delta = deltaEnergy(p);
    if (!(delta < -kEnergyTolerance)) return;
    proposals.push_back(std::move(p));
    queue.push({delta, kind, a, b, versionOf(a), versionOf(b), proposals.size() - 1});
  };

  // Neighbouring primitives: those sharing an edge of the k-nearest-neighbour graph.
  std::vector<std::pair<int, int>> pairs;
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const int a = label_[i];
    if (a < 0) continue;
    for (const int j : neighbours_[i]) {
      const int b = label_[static_cast<std::size_t>(j)];
      if (b >= 0 && b != a) pairs.emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  for (const auto& [a, b] : pairs) consider(Proposal::Kind::Merge, a, b);
  const int count = static_cast<int>(primitives_.size());
  for (int a = 0; a < count; ++a) {
    if (!primitives_[static_cast<std::size_t>(a)].alive) continue;
    consider(Proposal::Kind::Split, a, -1);
    consider(Proposal::Kind::Insert, a, -1);
    consider(Proposal::Kind::Exclude, a, -1);
  }

  bool changed = false;
  while (!queue.empty()) {
    if (interruptRequested()) break;
    const Entry e = queue.top();
    queue.pop();
    const int a = resolve(e.a);
    const int b = e.kind == Proposal::Kind::Merge ? resolve(e.b) : -1;
    if (a < 0 || !primitives_[static_cast<std::size_t>(a)].alive) continue;
    if (e.kind == Proposal::Kind::Merge && (a == b || b < 0 || !primitives_[static_cast<std::size_t>(b)].alive)) continue;
    const bool stale = a != e.a || b != e.b || versionOf(a) != e.version_a || versionOf(b) != e.version_b;
    if (stale) {
      // Re-evaluate against the current configuration and queue it again if still good.
      consider(e.kind, std::min(a, b < 0 ? a : b), b < 0 ? -1 : std::max(a, b));
      continue;
    }
    const Proposal& p = proposals[e.proposal];
    // Unassigned points may have been taken since an insertion was proposed: re-check.
    if (e.kind == Proposal::Kind::Insert) {
      bool free = true;
      for (const int i : p.groups[0])
        if (label_[static_cast<std::size_t>(i)] != -1 && label_[static_cast<std::size_t>(i)] != a) {
          free = false;
          break;
        }
      if (!free) {
        consider(e.kind, a, -1);
        continue;
      }
    }
    if (!(deltaEnergy(p) < -kEnergyTolerance)) continue;
    apply(p);
    changed = true;
  }
  if (transfer()) changed = true;
  return changed;
}

int GoCoPPOptimizer::optimize() {
  int rounds = 0;
  while (rounds < parameters_.max_rounds && !interruptRequested()) {
    ++rounds;
    if (!runRound()) break;
  }
  return rounds;
}

}  // namespace paco
