#include <paco/common/normal_sides.h>

#include <pcl/common/point_tests.h>

#include <Eigen/Geometry>

#include <cmath>

namespace paco {

namespace {

// A normal the sides can be read from: finite and not zero (files without normals read as zero).
bool hasNormal(const pcl::PointNormal& p) {
  const Eigen::Vector3f n = p.getNormalVector3fMap();
  return n.allFinite() && n.squaredNorm() > 0.0f;
}

}  // namespace

NormalSides normalSides(const pcl::PointCloud<pcl::PointNormal>& cloud) {
  NormalSides sides;
  Eigen::AlignedBox3d box;
  for (const auto& p : cloud)
    if (pcl::isXYZFinite(p)) box.extend(p.getVector3fMap().cast<double>());
  if (box.isEmpty()) return sides;
  const Eigen::Vector3d centre = box.center();
  const double margin = kNormalSideMargin * box.diagonal().norm();
  if (!(margin > 0.0)) return sides;
  Eigen::Vector3d inward_sum = Eigen::Vector3d::Zero();
  for (const auto& p : cloud) {
    if (!pcl::isXYZFinite(p) || !hasNormal(p)) continue;
    const Eigen::Vector3d normal = p.getNormalVector3fMap().cast<double>().normalized();
    const double along = (p.getVector3fMap().cast<double>() - centre).dot(normal);
    if (std::abs(along) < margin) continue;
    if (along < 0.0) {
      ++sides.inwards;
      inward_sum += normal;
    } else {
      ++sides.outwards;
    }
  }
  if (sides.inwards > 0) sides.inward_agreement = inward_sum.norm() / static_cast<double>(sides.inwards);
  return sides;
}

void flipNormals(pcl::PointCloud<pcl::PointNormal>& cloud) {
  for (auto& p : cloud) p.getNormalVector3fMap() = -p.getNormalVector3fMap();
}

NormalSides turnInwardNormalsOutward(pcl::PointCloud<pcl::PointNormal>& cloud) {
  NormalSides sides = normalSides(cloud);
  if (!sides.faceInwards()) return sides;
  flipNormals(cloud);
  sides.turned = true;
  return sides;
}

}  // namespace paco
