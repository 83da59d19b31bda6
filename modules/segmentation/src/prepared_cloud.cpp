#include <paco/common/error.h>
#include <paco/segmentation/prepared_cloud.h>
#include <paco/segmentation/thinning.h>

#include <pcl/console/print.h>
#include <pcl/features/normal_3d_omp.h>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <string>

namespace paco {

namespace {

// Ascending eigenvalues of the covariance (about the mean, divided by the count) of the points
// of `cloud` that `indices` names, or of all of them when it is null: the variances along the
// principal axes; the smallest is the mean squared distance to the best plane.
Eigen::Vector3d principalVariances(const pcl::PointCloud<pcl::PointNormal>& cloud, const pcl::Indices* indices) {
  const std::size_t n = indices ? indices->size() : cloud.size();
  const auto position = [&](std::size_t i) -> Eigen::Vector3d {
    return cloud[indices ? static_cast<std::size_t>((*indices)[i]) : i].getVector3fMap().cast<double>();
  };
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) mean += position(i);
  mean /= static_cast<double>(n);
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = position(i) - mean;
    covariance += d * d.transpose();
  }
  covariance /= static_cast<double>(n);
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance, Eigen::EigenvaluesOnly).eigenvalues();
}

// Residuals split at their widest gap count as two layers, not as scatter, when the gap is this
// many times the layers' own spread: the two sides of a wall a few point spacings thin, or of a
// shallow step, both in one neighbourhood. Noise on one surface has no such gap.
constexpr double kLayerGapRatio = 4.0;
// Each layer holds at least this many of the neighbours.
constexpr std::size_t kMinLayerPoints = 3;
// A neighbour counts towards a point's scatter only when its normal is within about 32 degrees of
// the point's (|cos|, the segmenter's default τ): the neighbours across an edge lie on another
// face, and their distance to a plane through both faces is the edge's shape, not noise.
constexpr double kNoiseNormalAgreement = 0.85;
// A point with fewer agreeing neighbours (a corner, a sliver of a face) is not read.
constexpr std::size_t kMinAgreeingNeighbours = 6;

// The covariance of `points` (about each group's own mean when `group` splits them; divided by
// the count) and its eigen decomposition.
Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> pooledCovariance(const std::vector<Eigen::Vector3d>& points,
                                                                const std::vector<int>& group) {
  Eigen::Vector3d means[2] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  double counts[2] = {0.0, 0.0};
  for (std::size_t i = 0; i < points.size(); ++i) {
    means[group[i]] += points[i];
    counts[group[i]] += 1.0;
  }
  for (int g = 0; g < 2; ++g)
    if (counts[g] > 0.0) means[g] /= counts[g];
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d d = points[i] - means[group[i]];
    covariance += d * d.transpose();
  }
  covariance /= static_cast<double>(points.size());
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance);
}

// The scatter of the points `indices` names off their best plane: the root-mean-square distance
// to it, or, when the distances fall into two layers (kLayerGapRatio), the scatter of each layer
// off its own plane (the layers' covariances pooled about their own means).
double scatterOffSurface(const pcl::PointCloud<pcl::PointNormal>& cloud, const pcl::Indices& indices) {
  const std::size_t n = indices.size();
  std::vector<Eigen::Vector3d> points(n);
  for (std::size_t i = 0; i < n; ++i) points[i] = cloud[static_cast<std::size_t>(indices[i])].getVector3fMap().cast<double>();
  std::vector<int> group(n, 0);
  const auto whole = pooledCovariance(points, group);
  const double scatter = std::sqrt(std::max(0.0, whole.eigenvalues()[0]));
  if (n < 2 * kMinLayerPoints) return scatter;
  const Eigen::Vector3d normal = whole.eigenvectors().col(0);
  std::vector<std::pair<double, std::size_t>> offsets(n);
  for (std::size_t i = 0; i < n; ++i) offsets[i] = {points[i].dot(normal), i};
  std::sort(offsets.begin(), offsets.end());
  std::size_t split = 0;
  double widest = 0.0;
  for (std::size_t s = kMinLayerPoints; s + kMinLayerPoints <= n; ++s)
    if (offsets[s].first - offsets[s - 1].first > widest) {
      widest = offsets[s].first - offsets[s - 1].first;
      split = s;
    }
  if (split == 0) return scatter;
  for (std::size_t s = split; s < n; ++s) group[offsets[s].second] = 1;
  const double layered = std::sqrt(std::max(0.0, pooledCovariance(points, group).eigenvalues()[0]));
  return widest > kLayerGapRatio * layered ? layered : scatter;
}

}  // namespace

const std::vector<std::vector<int>>& PreparedCloud::neighbours(int k) const {
  if (neighbours_k_ == k) return neighbours_;
  const std::size_t n = size();
  const int wanted = std::min<int>(k + 1, static_cast<int>(n));
  neighbours_.assign(n, {});
  pcl::Indices found;
  std::vector<float> distances;
  for (std::size_t i = 0; i < n; ++i) {
    tree->nearestKSearch((*points)[i], wanted, found, distances);
    auto& list = neighbours_[i];
    list.reserve(found.size());
    for (const auto j : found)
      if (static_cast<std::size_t>(j) != i) list.push_back(static_cast<int>(j));
    if (static_cast<int>(list.size()) > k) list.resize(static_cast<std::size_t>(k));
  }
  neighbours_k_ = k;
  return neighbours_;
}

double PreparedCloud::noiseLevel(int k, double quantile) const {
  if (k < 3) throw InvalidInputError("PreparedCloud::noiseLevel: k must be at least 3; got " + std::to_string(k));
  if (!(quantile >= 0.0 && quantile <= 1.0))
    throw InvalidInputError("PreparedCloud::noiseLevel: the quantile must be in [0, 1]; got " + std::to_string(quantile));
  const std::size_t n = size();
  if (n < 3) return 0.0;
  const int wanted = std::min<int>(k + 1, static_cast<int>(n));
  const std::size_t stride = std::max<std::size_t>(1, n / 5000);
  std::vector<double> scatter;
  pcl::Indices found, agreeing;
  std::vector<float> sq_distances;
  for (std::size_t i = 0; i < n; i += stride) {
    tree->nearestKSearch((*points)[i], wanted, found, sq_distances);
    const Eigen::Vector3f normal = (*points)[i].getNormalVector3fMap();
    agreeing.clear();
    for (const auto j : found)
      if (std::abs(normal.dot((*points)[static_cast<std::size_t>(j)].getNormalVector3fMap())) >= kNoiseNormalAgreement)
        agreeing.push_back(j);
    if (agreeing.size() >= kMinAgreeingNeighbours) scatter.push_back(scatterOffSurface(*points, agreeing));
  }
  if (scatter.empty()) return 0.0;
  const std::size_t at = std::min(scatter.size() - 1, static_cast<std::size_t>(quantile * static_cast<double>(scatter.size() - 1) + 0.5));
  std::nth_element(scatter.begin(), scatter.begin() + static_cast<std::ptrdiff_t>(at), scatter.end());
  return scatter[at];
}

double PreparedCloud::averageSpacing() const {
  if (average_spacing_) return *average_spacing_;
  const std::size_t n = size();
  const int wanted = std::min<int>(7, static_cast<int>(n));
  double total = 0.0;
  std::size_t counted = 0;
  pcl::Indices found;
  std::vector<float> sq_distances;
  // A subsample is enough for a mean spacing and keeps this cheap on large clouds.
  const std::size_t stride = std::max<std::size_t>(1, n / 5000);
  for (std::size_t i = 0; i < n; i += stride) {
    tree->nearestKSearch((*points)[i], wanted, found, sq_distances);
    double sum = 0.0;
    int m = 0;
    for (std::size_t j = 0; j < found.size(); ++j) {
      if (static_cast<std::size_t>(found[j]) == i) continue;
      sum += std::sqrt(static_cast<double>(sq_distances[j]));
      ++m;
    }
    if (m > 0) {
      total += sum / m;
      ++counted;
    }
  }
  average_spacing_ = counted > 0 ? total / static_cast<double>(counted) : 0.0;
  return *average_spacing_;
}

namespace detail {
namespace {

// Median surface variation above which estimated normals are taken again from twice the
// neighbours (doc/segmentation.md, "Noisy scans without normals").
constexpr float kNoisySurfaceVariation = 0.045f;

float medianSurfaceVariation(const pcl::PointCloud<pcl::Normal>& normals) {
  std::vector<float> variation;
  variation.reserve(normals.size());
  for (const auto& n : normals)
    if (std::isfinite(n.curvature)) variation.push_back(n.curvature);
  if (variation.empty()) return 0.0f;
  const auto middle = variation.begin() + static_cast<std::ptrdiff_t>(variation.size() / 2);
  std::nth_element(variation.begin(), middle, variation.end());
  return *middle;
}

bool usableNormal(const pcl::PointNormal& p) {
  const Eigen::Vector3f n = p.getNormalVector3fMap();
  return n.allFinite() && n.squaredNorm() > 1e-12f;
}

// Moves points with exactly the coordinates of an earlier point out of the working cloud, into
// prepared.repeats.
void setAsideRepeatedPoints(PreparedCloud& prepared) {
  auto& points = *prepared.points;
  const std::vector<int> first_of = findRepeatedPoints(points);
  if (std::none_of(first_of.begin(), first_of.end(), [](int f) { return f >= 0; })) return;
  std::vector<int> working_index(points.size(), -1);
  pcl::PointCloud<pcl::PointNormal> kept;
  std::vector<int> kept_sources;
  kept.reserve(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (first_of[i] >= 0) continue;
    working_index[i] = static_cast<int>(kept.size());
    kept.push_back(points[i]);
    kept_sources.push_back(prepared.source_indices[i]);
  }
  for (std::size_t i = 0; i < points.size(); ++i)
    if (first_of[i] >= 0)
      prepared.repeats.emplace_back(prepared.source_indices[i], working_index[static_cast<std::size_t>(first_of[i])]);
  points = std::move(kept);
  prepared.source_indices = std::move(kept_sources);
}

}  // namespace

void prepareCloud(const pcl::PointCloud<pcl::PointNormal>& gathered, std::vector<int> source_indices,
                  std::size_t input_size, const PrepareOptions& options, PreparedCloud& prepared) {
  prepared.input_size = input_size;
  auto& points = *prepared.points;
  points.clear();
  points.reserve(gathered.size());
  prepared.source_indices.clear();
  prepared.source_indices.reserve(gathered.size());
  prepared.repeats.clear();
  std::size_t dropped = 0;
  for (std::size_t i = 0; i < gathered.size(); ++i) {
    const auto& p = gathered[i];
    if (!(std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z))) {
      ++dropped;
      continue;
    }
    points.push_back(p);
    prepared.source_indices.push_back(source_indices[i]);
  }
  if (dropped > 0)
    PCL_WARN("[paco::PlanarSegmenter] dropped %zu of %zu points with NaN/Inf coordinates; they get label -1\n",
             dropped, gathered.size());
  setAsideRepeatedPoints(prepared);
  if (points.size() < 3)
    throw InvalidInputError(
        "PlanarSegmenter: a plane needs at least 3 distinct points with finite coordinates; the input has " +
        std::to_string(points.size()) +
        (dropped > 0 ? " (after dropping " + std::to_string(dropped) + " non-finite ones)" : std::string()) +
        (prepared.repeats.empty()
             ? std::string()
             : " (" + std::to_string(prepared.repeats.size()) + " more repeat their coordinates)") +
        "; give a larger cloud");
  points.width = static_cast<std::uint32_t>(points.size());
  points.height = 1;
  points.is_dense = true;

  // Normalization::fromBoundingBox throws InvalidInputError when all points coincide.
  prepared.normalization = Normalization::fromBoundingBox(points);
  prepared.normalization.apply(points);

  // Collinear points: the two largest principal variances carry everything.
  {
    // In the unit-diagonal frame, a spread below ~1e-6 across the line is float noise.
    prepared.collinear = !(principalVariances(points, nullptr)(1) > 1e-12);
    if (prepared.collinear)
      PCL_WARN("[paco::PlanarSegmenter] all %zu points are collinear: no plane can be segmented\n",
               points.size());
  }

  prepared.tree.reset(new pcl::search::KdTree<pcl::PointNormal>(false));
  prepared.tree->setInputCloud(prepared.points);

  std::vector<int> missing;
  for (std::size_t i = 0; i < points.size(); ++i) {
    auto& p = points[i];
    if (usableNormal(p)) {
      p.getNormalVector3fMap().normalize();
      if (!std::isfinite(p.curvature)) p.curvature = 0.0f;
    } else {
      missing.push_back(static_cast<int>(i));
    }
  }
  prepared.normals_estimated = !missing.empty();
  prepared.normal_neighbours_used = 0;
  prepared.estimated_normal.assign(points.size(), 0);
  for (const int i : missing) prepared.estimated_normal[static_cast<std::size_t>(i)] = 1;
  prepared.oriented_towards_viewpoint = options.viewpoint.has_value();
  if (missing.empty() || prepared.collinear) {
    for (const int i : missing) {
      points[static_cast<std::size_t>(i)].getNormalVector3fMap().setZero();
      points[static_cast<std::size_t>(i)].curvature = 1.0f;
    }
    return;
  }

  pcl::NormalEstimationOMP<pcl::PointNormal, pcl::Normal> estimation(options.threads);
  estimation.setInputCloud(prepared.points);
  estimation.setSearchMethod(prepared.tree);
  estimation.setIndices(pcl::IndicesPtr(new pcl::Indices(missing.begin(), missing.end())));
  pcl::PointCloud<pcl::Normal> normals;
  int neighbours = std::min<int>(options.normal_neighbours, static_cast<int>(points.size()));
  estimation.setKSearch(neighbours);
  estimation.compute(normals);
  // Noise comparable to the point spacing tilts normals from small neighbourhoods, and the
  // segmenters then label few points. The median surface variation (PCL's curvature) tells:
  // on clean MFCAD inputs it stays below 0.04, with noise of 1 % of the diagonal above 0.05.
  if (medianSurfaceVariation(normals) > kNoisySurfaceVariation && 2 * neighbours <= static_cast<int>(points.size())) {
    neighbours *= 2;
    estimation.setKSearch(neighbours);
    estimation.compute(normals);
  }
  prepared.normal_neighbours_used = neighbours;

  // Orientation: away from the bounding-box centre (the origin here), or towards a viewpoint.
  std::optional<Eigen::Vector3f> viewpoint;
  if (options.viewpoint) viewpoint = prepared.normalization.apply(*options.viewpoint).cast<float>();
  for (std::size_t m = 0; m < missing.size(); ++m) {
    auto& p = points[static_cast<std::size_t>(missing[m])];
    Eigen::Vector3f n = normals[m].getNormalVector3fMap();
    if (!n.allFinite() || n.squaredNorm() < 1e-12f) {
      p.getNormalVector3fMap().setZero();
      p.curvature = 1.0f;
      continue;
    }
    n.normalize();
    const Eigen::Vector3f position = p.getVector3fMap();
    const float towards = viewpoint ? n.dot(*viewpoint - position) : n.dot(position);
    if (towards < 0.0f) n = -n;
    p.getNormalVector3fMap() = n;
    p.curvature = std::isfinite(normals[m].curvature) ? normals[m].curvature : 1.0f;
  }
}

std::vector<std::vector<int>> membersByLabel(const std::vector<int>& labels) {
  int max_label = -1;
  for (const int l : labels) max_label = std::max(max_label, l);
  std::vector<std::vector<int>> members(static_cast<std::size_t>(max_label + 1));
  for (std::size_t i = 0; i < labels.size(); ++i)
    if (labels[i] >= 0) members[static_cast<std::size_t>(labels[i])].push_back(static_cast<int>(i));
  return members;
}

Plane fitPlane(const pcl::PointCloud<pcl::PointNormal>& points, const std::vector<int>& indices) {
  std::vector<Eigen::Vector3d> xyz;
  xyz.reserve(indices.size());
  for (const int i : indices) xyz.push_back(points[static_cast<std::size_t>(i)].getVector3fMap().cast<double>());
  return Plane::fit(xyz);
}

PlanarSegmentation finalizeSegmentation(const PreparedCloud& prepared, const std::vector<int>& labels,
                                        std::size_t min_points) {
  const auto& points = *prepared.points;
  min_points = std::max<std::size_t>(min_points, 3);
  std::vector<std::vector<int>> groups = membersByLabel(labels);

  struct Fitted {
    Plane plane;
    std::vector<int> members;
  };
  std::vector<Fitted> fitted;
  std::vector<Plane> working_planes;
  std::vector<std::vector<int>> working_members;
  for (auto& group : groups) {
    if (group.size() < min_points) continue;
    Plane plane;
    try {
      plane = fitPlane(points, group);
    } catch (const InvalidInputError&) {
      continue;  // collinear group: no unique plane
    }
    // Majority vote of the point normals (zero normals abstain); without any, face outwards.
    long votes = 0;
    for (const int i : group) {
      const Eigen::Vector3d n = points[static_cast<std::size_t>(i)].getNormalVector3fMap().cast<double>();
      const double c = n.dot(plane.normal);
      votes += c > 1e-6 ? 1 : (c < -1e-6 ? -1 : 0);
    }
    if (votes < 0 || (votes == 0 && plane.offset > 0)) plane = plane.flipped();
    working_planes.push_back(plane);
    working_members.push_back(std::move(group));
  }
  if (prepared.normals_estimated && !prepared.oriented_towards_viewpoint)
    orientEstimatedSegments(prepared, working_members, working_planes);
  for (std::size_t s = 0; s < working_planes.size(); ++s)
    fitted.push_back({prepared.normalization.applyInverse(working_planes[s]), std::move(working_members[s])});
  std::stable_sort(fitted.begin(), fitted.end(),
                   [](const Fitted& a, const Fitted& b) { return a.members.size() > b.members.size(); });

  PlanarSegmentation result;
  result.labels.assign(prepared.input_size, -1);
  std::vector<int> segment_of(points.size(), -1);
  for (std::size_t s = 0; s < fitted.size(); ++s)
    for (const int i : fitted[s].members) segment_of[static_cast<std::size_t>(i)] = static_cast<int>(s);
  std::vector<std::vector<int>> repeats_of(fitted.size());
  for (const auto& [source, working] : prepared.repeats)
    if (segment_of[static_cast<std::size_t>(working)] >= 0)
      repeats_of[static_cast<std::size_t>(segment_of[static_cast<std::size_t>(working)])].push_back(source);
  for (std::size_t s = 0; s < fitted.size(); ++s) {
    pcl::PointIndices segment;
    segment.indices.reserve(fitted[s].members.size() + repeats_of[s].size());
    for (const int i : fitted[s].members)
      segment.indices.push_back(prepared.source_indices[static_cast<std::size_t>(i)]);
    segment.indices.insert(segment.indices.end(), repeats_of[s].begin(), repeats_of[s].end());
    for (const int source : segment.indices) result.labels[static_cast<std::size_t>(source)] = static_cast<int>(s);
    std::sort(segment.indices.begin(), segment.indices.end());
    result.planes.push_back(fitted[s].plane);
    result.segments.push_back(std::move(segment));
  }
  return result;
}

}  // namespace detail
}  // namespace paco
