#include <paco/common/error.h>
#include <paco/common/primitive.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

namespace paco {

double PlanarSegmentation::coverage() const {
  if (labels.empty()) return 0.0;
  std::size_t assigned = 0;
  for (int l : labels) assigned += (l >= 0);
  return static_cast<double>(assigned) / static_cast<double>(labels.size());
}

std::vector<std::size_t> PlanarSegmentation::pointsPerSegment() const {
  std::vector<std::size_t> counts(planes.size(), 0);
  for (int label : labels)
    if (label >= 0 && static_cast<std::size_t>(label) < counts.size()) ++counts[static_cast<std::size_t>(label)];
  return counts;
}

void PlanarSegmentation::rebuildSegmentsFromLabels() {
  segments.assign(planes.size(), pcl::PointIndices());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const int l = labels[i];
    if (l < 0) continue;
    if (static_cast<std::size_t>(l) >= planes.size())
      throw InvalidInputError("PlanarSegmentation: label " + std::to_string(l) + " of point " +
                              std::to_string(i) + " has no plane (" + std::to_string(planes.size()) +
                              " planes)");
    segments[l].indices.push_back(static_cast<int>(i));
  }
}

PlanarSegmentation PlanarSegmentation::fromLabels(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                                  const std::vector<int>& labels) {
  if (labels.size() != cloud.size())
    throw InvalidInputError("PlanarSegmentation::fromLabels: " + std::to_string(labels.size()) + " labels for " +
                            std::to_string(cloud.size()) + " points");
  int count = 0;
  for (int l : labels) count = std::max(count, l + 1);
  std::vector<std::vector<Eigen::Vector3d>> groups(static_cast<std::size_t>(count));
  std::vector<Eigen::Vector3d> hints(static_cast<std::size_t>(count), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (labels[i] < 0) continue;
    const auto l = static_cast<std::size_t>(labels[i]);
    groups[l].push_back(cloud[i].getVector3fMap().cast<double>());
    const Eigen::Vector3d n = cloud[i].getNormalVector3fMap().cast<double>();
    if (n.allFinite()) hints[l] += n;
  }
  PlanarSegmentation seg;
  std::vector<int> renumber(static_cast<std::size_t>(count), -1);
  for (std::size_t l = 0; l < groups.size(); ++l) {
    if (groups[l].size() < 3) continue;
    try {
      seg.planes.push_back(Plane::fit(groups[l], hints[l]));
      renumber[l] = static_cast<int>(seg.planes.size()) - 1;
    } catch (const Error&) {
      // collinear points: no plane
    }
  }
  seg.labels.resize(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    seg.labels[i] = labels[i] >= 0 ? renumber[static_cast<std::size_t>(labels[i])] : -1;
  seg.rebuildSegmentsFromLabels();
  return seg;
}

void PlanarSegmentation::rebuildLabelsFromSegments(std::size_t num_points) {
  labels.assign(num_points, -1);
  for (std::size_t s = 0; s < segments.size(); ++s)
    for (int i : segments[s].indices) {
      if (i < 0 || static_cast<std::size_t>(i) >= num_points)
        throw InvalidInputError("PlanarSegmentation: segment " + std::to_string(s) +
                                " has point index " + std::to_string(i) + " outside the cloud of " +
                                std::to_string(num_points) + " points");
      labels[i] = static_cast<int>(s);
    }
}

void PlanarSegmentation::validate(std::size_t num_points) const {
  if (labels.size() != num_points)
    throw InvalidInputError("PlanarSegmentation: " + std::to_string(labels.size()) +
                            " labels for a cloud of " + std::to_string(num_points) + " points");
  if (segments.size() != planes.size())
    throw InvalidInputError("PlanarSegmentation: " + std::to_string(segments.size()) +
                            " segments but " + std::to_string(planes.size()) + " planes");
  for (std::size_t s = 0; s < segments.size(); ++s)
    for (int i : segments[s].indices)
      if (i < 0 || static_cast<std::size_t>(i) >= num_points || labels[i] != static_cast<int>(s))
        throw InvalidInputError("PlanarSegmentation: segment " + std::to_string(s) +
                                " and the labels disagree at point " + std::to_string(i));
}

namespace {
template <typename PointT>
std::vector<PlanarPrimitive> makePrimitivesImpl(const pcl::PointCloud<PointT>& cloud,
                                                const PlanarSegmentation& seg) {
  seg.validate(cloud.size());
  std::vector<PlanarPrimitive> primitives(seg.planes.size());
  for (std::size_t s = 0; s < seg.planes.size(); ++s) {
    PlanarPrimitive& prim = primitives[s];
    prim.plane = seg.planes[s];
    prim.points.reserve(seg.segments[s].indices.size());
    for (int i : seg.segments[s].indices) {
      const PointT& src = cloud[i];
      pcl::PointNormal p;
      p.x = src.x; p.y = src.y; p.z = src.z;
      Eigen::Vector3f n = prim.plane.normal.cast<float>();
      if constexpr (std::is_same_v<PointT, pcl::PointNormal>) {
        // Keep the point's own normal only when it is usable; else the plane's.
        Eigen::Vector3f own(src.normal_x, src.normal_y, src.normal_z);
        if (own.allFinite() && own.squaredNorm() > 0.25f) n = own.normalized();
      }
      p.normal_x = n.x(); p.normal_y = n.y(); p.normal_z = n.z();
      p.curvature = 0.0f;
      prim.points.push_back(p);
    }
  }
  return primitives;
}
}  // namespace

std::vector<PlanarPrimitive> makePrimitives(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                            const PlanarSegmentation& seg) {
  return makePrimitivesImpl(cloud, seg);
}
std::vector<PlanarPrimitive> makePrimitives(const pcl::PointCloud<pcl::PointXYZ>& cloud,
                                            const PlanarSegmentation& seg) {
  return makePrimitivesImpl(cloud, seg);
}

void flattenPrimitives(const std::vector<PlanarPrimitive>& primitives,
                       pcl::PointCloud<pcl::PointNormal>& cloud, std::vector<int>& labels) {
  cloud.clear();
  labels.clear();
  for (std::size_t s = 0; s < primitives.size(); ++s)
    for (const auto& p : primitives[s].points) {
      cloud.push_back(p);
      labels.push_back(static_cast<int>(s));
    }
}

namespace {
double squaredDistance(const Plane& plane, const pcl::PointNormal& p) {
  return std::pow(plane.signedDistance(Eigen::Vector3d(p.x, p.y, p.z)), 2);
}
}  // namespace

double rmsDistance(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& plane) {
  if (points.empty()) return 0.0;
  double squares = 0.0;
  for (const auto& p : points) squares += squaredDistance(plane, p);
  return std::sqrt(squares / static_cast<double>(points.size()));
}

double rmsDistance(const pcl::PointCloud<pcl::PointNormal>& points, const std::vector<int>& indices,
                   const Plane& plane) {
  if (indices.empty()) return 0.0;
  double squares = 0.0;
  for (const int i : indices) squares += squaredDistance(plane, points[static_cast<std::size_t>(i)]);
  return std::sqrt(squares / static_cast<double>(indices.size()));
}

}  // namespace paco
