#pragma once
// Generated clouds with known planes for the segmentation tests: points sampled on the
// test/support shapes (one plane per face), partial views, and plane-recovery scoring.
#include "shapes.h"

#include <paco/common/angles.h>
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <vector>

namespace paco::test {

/// A cloud with a ground-truth plane label per point (the face of a shape whose faces are all on
/// distinct planes) and the GT plane normals.
struct LabelledSample {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud{new pcl::PointCloud<pcl::PointNormal>};
  std::vector<int> labels;
  std::vector<Eigen::Vector3d> plane_normals;
};

inline LabelledSample sampleShape(const SurfaceMesh& mesh, std::size_t count, std::uint64_t seed) {
  const SurfaceSample s = sampleSurface(mesh, count, seed);
  LabelledSample out;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) out.plane_normals.push_back(faceNormal(mesh, f));
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    pcl::PointNormal p;
    p.getVector3fMap() = s.points[i].cast<float>();
    p.getNormalVector3fMap() = s.normals[i].cast<float>();
    p.curvature = 0.0f;
    out.cloud->push_back(p);
    out.labels.push_back(static_cast<int>(s.faces[i]));
  }
  return out;
}

/// Drops the fraction `missing` of the points nearest to `viewpoint` (AdaPoinTr-style partial view).
inline LabelledSample partialView(const LabelledSample& full, const Eigen::Vector3f& viewpoint, double missing) {
  const std::size_t n = full.cloud->size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return ((*full.cloud)[a].getVector3fMap() - viewpoint).squaredNorm() <
           ((*full.cloud)[b].getVector3fMap() - viewpoint).squaredNorm();
  });
  const auto drop = static_cast<std::size_t>(std::round(missing * static_cast<double>(n)));
  std::vector<std::size_t> keep(order.begin() + static_cast<long>(drop), order.end());
  std::sort(keep.begin(), keep.end());
  LabelledSample out;
  out.plane_normals = full.plane_normals;
  for (const auto i : keep) {
    out.cloud->push_back((*full.cloud)[i]);
    out.labels.push_back(full.labels[i]);
  }
  return out;
}

inline pcl::PointCloud<pcl::PointXYZ>::Ptr withoutNormals(const pcl::PointCloud<pcl::PointNormal>& cloud) {
  pcl::PointCloud<pcl::PointXYZ>::Ptr out(new pcl::PointCloud<pcl::PointXYZ>);
  for (const auto& p : cloud) out->push_back(pcl::PointXYZ(p.x, p.y, p.z));
  return out;
}

/// How well a segmentation recovers the GT planes that have at least `min_points` points: a GT
/// plane is found when a segment overlaps it with IoU >= 0.5.
struct PlaneRecovery {
  int visible = 0;          ///< GT planes with >= min_points points
  int found = 0;
  double worst_angle_deg = 0.0;  ///< largest angle between a found GT plane and its segment's plane
  int facing_inwards = 0;        ///< found planes whose segment's normal is against the GT's outward one
};

inline PlaneRecovery scoreRecovery(const LabelledSample& gt, const PlanarSegmentation& seg, int min_points = 50) {
  std::map<int, int> gt_size;
  for (const int l : gt.labels) ++gt_size[l];
  std::vector<int> seg_size(seg.size(), 0);
  for (const int l : seg.labels)
    if (l >= 0) ++seg_size[static_cast<std::size_t>(l)];
  std::map<std::pair<int, int>, int> overlap;
  for (std::size_t i = 0; i < gt.labels.size(); ++i)
    if (seg.labels[i] >= 0) ++overlap[{gt.labels[i], seg.labels[i]}];
  PlaneRecovery r;
  for (const auto& [g, size] : gt_size) {
    if (size < min_points) continue;
    ++r.visible;
    double best_iou = 0.0;
    int best = -1;
    for (std::size_t s = 0; s < seg.size(); ++s) {
      const auto it = overlap.find({g, static_cast<int>(s)});
      if (it == overlap.end()) continue;
      const double iou = it->second / static_cast<double>(size + seg_size[s] - it->second);
      if (iou > best_iou) {
        best_iou = iou;
        best = static_cast<int>(s);
      }
    }
    if (best_iou >= 0.5) {
      ++r.found;
      const double oriented = seg.planes[static_cast<std::size_t>(best)].normal.dot(
          gt.plane_normals[static_cast<std::size_t>(g)]);
      if (oriented < 0.0) ++r.facing_inwards;
      const double c = std::min(1.0, std::abs(oriented));
      r.worst_angle_deg = std::max(r.worst_angle_deg, paco::radiansToDegrees(std::acos(c)));
    }
  }
  return r;
}

/// A rotation that puts no face of an axis-aligned shape on an axis plane.
inline Eigen::Matrix3d obliqueRotation() {
  return (Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) *
          Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitY()))
      .toRotationMatrix();
}

}  // namespace paco::test
