#include <paco/evaluation/metrics.h>

#include <paco/common/assignment.h>
#include <paco/common/error.h>
#include <paco/common/normalization.h>

#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace paco::evaluation {

namespace {

struct Directed {
  double mean_distance = 0.0;
  double max_distance = 0.0;
  double mean_normal_agreement = 0.0;
};

pcl::PointCloud<pcl::PointXYZ>::Ptr toCloud(const std::vector<Eigen::Vector3d>& points) {
  auto cloud = pcl::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  cloud->resize(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& p = points[i];
    (*cloud)[i] = pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  }
  return cloud;
}

// For every point of `from`, its nearest neighbour in `to` (the kd-tree of `to`). Distances are
// recomputed in double from the original coordinates: the tree only picks the neighbour. Each
// point's distance and normal agreement go to `distances` and `agreements` when given.
Directed directed(const SurfaceSample& from, const SurfaceSample& to, const pcl::KdTreeFLANN<pcl::PointXYZ>& tree,
                  std::vector<double>* distances = nullptr, std::vector<double>* agreements = nullptr) {
  Directed result;
  std::vector<int> index(1);
  std::vector<float> squared(1);
  double sum_distance = 0.0, sum_agreement = 0.0;
  for (std::size_t i = 0; i < from.points.size(); ++i) {
    const Eigen::Vector3d& p = from.points[i];
    const pcl::PointXYZ query(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    if (tree.nearestKSearch(query, 1, index, squared) < 1)
      throw InvalidInputError("compareSamples: nearest-neighbour search found nothing");
    const auto j = static_cast<std::size_t>(index[0]);
    const double distance = (p - to.points[j]).norm();
    if (distances) distances->push_back(distance);
    sum_distance += distance;
    result.max_distance = std::max(result.max_distance, distance);
    const double agreement = std::abs(from.normals[i].dot(to.normals[j]));
    if (agreements) agreements->push_back(agreement);
    sum_agreement += agreement;
  }
  const double n = static_cast<double>(from.points.size());
  result.mean_distance = sum_distance / n;
  result.mean_normal_agreement = sum_agreement / n;
  return result;
}

void checkSample(const SurfaceSample& sample, const char* which) {
  if (sample.points.empty())
    throw InvalidInputError(std::string("compareSamples: the ") + which + " sample has no points");
  if (sample.normals.size() != sample.points.size())
    throw InvalidInputError(std::string("compareSamples: the ") + which +
                            " sample has a different number of normals and points");
}

SurfaceMesh boxMesh(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  SurfaceMesh box;
  for (int i = 0; i < 8; ++i)
    box.vertices.emplace_back((i & 1) ? hi.x() : lo.x(), (i & 2) ? hi.y() : lo.y(), (i & 4) ? hi.z() : lo.z());
  // Counter-clockwise seen from outside.
  box.faces = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  return box;
}

// compareSamples, and each reference point's distance to the prediction and normal agreement
// with it when asked.
SurfaceDistances compare(const SurfaceSample& predicted, const SurfaceSample& reference,
                         std::vector<double>* reference_distances, std::vector<double>* reference_agreements) {
  checkSample(predicted, "predicted");
  checkSample(reference, "reference");
  pcl::KdTreeFLANN<pcl::PointXYZ> predicted_tree, reference_tree;
  predicted_tree.setInputCloud(toCloud(predicted.points));
  reference_tree.setInputCloud(toCloud(reference.points));
  const Directed forward = directed(predicted, reference, reference_tree);
  const Directed backward = directed(reference, predicted, predicted_tree, reference_distances, reference_agreements);
  SurfaceDistances d;
  d.chamfer_pred_to_gt = forward.mean_distance;
  d.chamfer_gt_to_pred = backward.mean_distance;
  d.chamfer = forward.mean_distance + backward.mean_distance;
  d.hausdorff = std::max(forward.max_distance, backward.max_distance);
  d.hausdorff_pred_to_gt = forward.max_distance;
  d.hausdorff_gt_to_pred = backward.max_distance;
  d.normal_consistency_pred_to_gt = forward.mean_normal_agreement;
  d.normal_consistency_gt_to_pred = backward.mean_normal_agreement;
  d.normal_consistency = 0.5 * (forward.mean_normal_agreement + backward.mean_normal_agreement);
  return d;
}

// Which reference samples lie within `radius` of a seen point: a kd-tree of the seen points,
// one nearest-neighbour query per sample.
std::vector<bool> seenSamples(const SurfaceSample& reference, const std::vector<Eigen::Vector3d>& seen, double radius) {
  std::vector<bool> is_seen(reference.points.size(), false);
  if (seen.empty()) return is_seen;
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(toCloud(seen));
  std::vector<int> index(1);
  std::vector<float> squared(1);
  for (std::size_t i = 0; i < reference.points.size(); ++i) {
    const Eigen::Vector3d& p = reference.points[i];
    const pcl::PointXYZ query(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    if (tree.nearestKSearch(query, 1, index, squared) < 1) continue;
    is_seen[i] = (p - seen[static_cast<std::size_t>(index[0])]).norm() <= radius;
  }
  return is_seen;
}

// evaluateMesh with or without the seen points (`seen` may be null).
MeshMetrics measure(const SurfaceMesh& predicted, const SurfaceMesh& reference, const std::vector<Eigen::Vector3d>* seen,
                    const MetricOptions& options) {
  if (options.num_samples == 0) throw InvalidInputError("evaluateMesh: num_samples must be at least 1");
  if (!(options.distance_scale > 0.0)) throw InvalidInputError("evaluateMesh: distance_scale must be > 0");
  predicted.validate("predicted mesh");
  reference.validate("reference mesh");
  if (predicted.empty()) throw InvalidInputError("evaluateMesh: the predicted mesh has no faces");
  if (reference.empty()) throw InvalidInputError("evaluateMesh: the reference mesh has no faces");

  if (seen) {
    if (!(options.seen_radius > 0.0)) throw InvalidInputError("evaluateMesh: seen_radius must be > 0");
    for (std::size_t i = 0; i < seen->size(); ++i)
      if (!(*seen)[i].allFinite())
        throw InvalidInputError("evaluateMesh: seen point " + std::to_string(i) + " is not finite");
  }

  SurfaceMesh pred = predicted, ref = reference;
  std::vector<Eigen::Vector3d> seen_points = seen ? *seen : std::vector<Eigen::Vector3d>();
  if (options.normalize_by_reference) {
    Eigen::Vector3d lo, hi;
    boundingBox(reference, lo, hi);
    const Normalization frame = Normalization::fromBoundingBox(lo, hi);
    frame.apply(pred);
    frame.apply(ref);
    for (auto& p : seen_points) p = frame.apply(p);
  }
  const SurfaceSample pred_sample = sampleSurface(pred, options.num_samples, options.prediction_seed);
  const SurfaceSample ref_sample = sampleSurface(ref, options.num_samples, options.reference_seed);
  std::vector<double> ref_distances, ref_agreements;
  const SurfaceDistances d =
      compare(pred_sample, ref_sample, seen ? &ref_distances : nullptr, seen ? &ref_agreements : nullptr);

  MeshMetrics m;
  m.chamfer = d.chamfer * options.distance_scale;
  m.chamfer_pred_to_gt = d.chamfer_pred_to_gt * options.distance_scale;
  m.chamfer_gt_to_pred = d.chamfer_gt_to_pred * options.distance_scale;
  m.hausdorff = d.hausdorff * options.distance_scale;
  m.hausdorff_pred_to_gt = d.hausdorff_pred_to_gt * options.distance_scale;
  m.hausdorff_gt_to_pred = d.hausdorff_gt_to_pred * options.distance_scale;
  m.normal_consistency = d.normal_consistency;
  m.normal_consistency_pred_to_gt = d.normal_consistency_pred_to_gt;
  m.normal_consistency_gt_to_pred = d.normal_consistency_gt_to_pred;
  m.num_faces = predicted.faces.size();
  m.num_vertices = predicted.vertices.size();
  m.closed = analyseTopology(predicted).isClosedManifold();
  m.volume_ratio = std::numeric_limits<double>::quiet_NaN();
  const double ref_volume = signedVolume(reference);
  if (m.closed && ref_volume != 0.0) m.volume_ratio = signedVolume(predicted) / ref_volume;
  if (seen) {
    const std::vector<bool> is_seen = seenSamples(ref_sample, seen_points, options.seen_radius);
    double sum_seen = 0.0, sum_hidden = 0.0, agreement_seen = 0.0, agreement_hidden = 0.0;
    std::size_t num_seen = 0;
    for (std::size_t i = 0; i < is_seen.size(); ++i) {
      if (is_seen[i]) {
        sum_seen += ref_distances[i];
        agreement_seen += ref_agreements[i];
        ++num_seen;
      } else {
        sum_hidden += ref_distances[i];
        agreement_hidden += ref_agreements[i];
      }
    }
    const std::size_t num_hidden = is_seen.size() - num_seen;
    m.hidden_fraction = static_cast<double>(num_hidden) / static_cast<double>(is_seen.size());
    if (num_seen) {
      m.chamfer_gt_to_pred_seen = sum_seen / static_cast<double>(num_seen) * options.distance_scale;
      m.normal_consistency_gt_to_pred_seen = agreement_seen / static_cast<double>(num_seen);
    }
    if (num_hidden) {
      m.chamfer_gt_to_pred_hidden = sum_hidden / static_cast<double>(num_hidden) * options.distance_scale;
      m.normal_consistency_gt_to_pred_hidden = agreement_hidden / static_cast<double>(num_hidden);
    }
  }
  return m;
}

}  // namespace

SurfaceDistances compareSamples(const SurfaceSample& predicted, const SurfaceSample& reference) {
  return compare(predicted, reference, nullptr, nullptr);
}

MeshMetrics evaluateMesh(const SurfaceMesh& predicted, const SurfaceMesh& reference, const MetricOptions& options) {
  return measure(predicted, reference, nullptr, options);
}

MeshMetrics evaluateMesh(const SurfaceMesh& predicted, const SurfaceMesh& reference,
                         const std::vector<Eigen::Vector3d>& seen_points, const MetricOptions& options) {
  return measure(predicted, reference, &seen_points, options);
}

SurfaceMesh failureBox(const SurfaceMesh& reference, FailureBox box) {
  reference.validate("reference mesh");
  if (reference.vertices.empty()) throw InvalidInputError("failureBox: the reference mesh has no vertices");
  Eigen::Vector3d lo, hi;
  boundingBox(reference, lo, hi);
  const Normalization frame = Normalization::fromBoundingBox(lo, hi);
  // Built in the normalised frame (diagonal 1, centre 0), then moved to the reference's frame.
  Eigen::Vector3d half = 0.5 * (hi - lo) * frame.scale;
  if (box == FailureBox::UnitDiagonalCube) half = Eigen::Vector3d::Constant(0.5 / std::sqrt(3.0));
  SurfaceMesh result = boxMesh(-half, half);
  frame.applyInverse(result);
  return result;
}

namespace {

// A failure box's metrics: nothing was produced.
MeshMetrics asFailure(MeshMetrics m) {
  m.num_faces = 0;
  m.num_vertices = 0;
  m.closed = false;
  m.volume_ratio = std::numeric_limits<double>::quiet_NaN();
  return m;
}

}  // namespace

MeshMetrics evaluateFailure(const SurfaceMesh& reference, const MetricOptions& options, FailureBox box) {
  return asFailure(evaluateMesh(failureBox(reference, box), reference, options));
}

MeshMetrics evaluateFailure(const SurfaceMesh& reference, const std::vector<Eigen::Vector3d>& seen_points,
                            const MetricOptions& options, FailureBox box) {
  return asFailure(evaluateMesh(failureBox(reference, box), reference, seen_points, options));
}

PrimitiveAgreement comparePrimitives(const std::vector<Plane>& predicted, const std::vector<Plane>& reference) {
  PrimitiveAgreement a;
  a.reference_of_predicted.assign(predicted.size(), -1);
  if (reference.empty()) {
    a.nc_prim = std::numeric_limits<double>::quiet_NaN();
    a.unmatched_predicted = predicted.size();
    return a;
  }
  Eigen::MatrixXd agreement(static_cast<Eigen::Index>(predicted.size()), static_cast<Eigen::Index>(reference.size()));
  for (std::size_t i = 0; i < predicted.size(); ++i) {
    if (!predicted[i].normal.allFinite())
      throw InvalidInputError("comparePrimitives: predicted plane " + std::to_string(i) + " has a non-finite normal");
    for (std::size_t j = 0; j < reference.size(); ++j)
      agreement(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) =
          std::min(1.0, std::abs(predicted[i].normal.normalized().dot(reference[j].normal.normalized())));
  }
  const Eigen::MatrixXd cost = Eigen::MatrixXd::Ones(agreement.rows(), agreement.cols()) - agreement;
  const std::vector<int> match = solveAssignment(cost);
  double sum = 0.0;
  for (std::size_t i = 0; i < match.size(); ++i) {
    if (match[i] < 0) continue;
    a.reference_of_predicted[i] = match[i];
    sum += agreement(static_cast<Eigen::Index>(i), match[i]);
    ++a.matched;
  }
  a.unmatched_predicted = predicted.size() - a.matched;
  a.unmatched_reference = reference.size() - a.matched;
  a.nc_prim = sum / static_cast<double>(reference.size());
  return a;
}

}  // namespace paco::evaluation
