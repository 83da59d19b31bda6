#pragma once
// Which way a scan's given normals face as a whole. An object scanned from outside has normals
// facing away from its middle; a room scanned from inside, or an object whose normals were
// turned towards a viewpoint inside it (pcl::NormalEstimation's default viewpoint is the origin),
// has them facing the middle. The assemblers read a face's outward side from its normals, so on
// such a scan the cell complex kept the space outside the walls as solid (an L-shaped room
// 6 x 7 x 2.6 m came back as three components 7.2 x 10.3 x 6.8 m).
// Usage:
//   const paco::NormalSides sides = paco::turnInwardNormalsOutward(*cloud);
//   if (sides.turned) std::printf("%.0f %% faced inwards; turned\n", 100 * sides.inwardShare());
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>

namespace paco {

/// Above this share of facing-inwards points (NormalSides::inwardShare) a scan's normals face
/// inwards as a whole. The 900 MFCAD validation inputs (300 parts at 25 / 50 / 75 % missing) read
/// at most 0.35; the real scans in ../shared/data/scans 0.00 (AHN3_02373) and 0.18 (AHN3_16627); a
/// room scanned from inside 1.00 (doc/segmentation.md, "Normals that face inwards").
constexpr double kInwardNormalShare = 0.75;

/// Below this length of the mean unit normal of the facing-inwards points they face many ways,
/// as a room's floor, ceiling and walls face its middle. Ground under an airborne scan's roof
/// also faces the middle, but all of it one way (up), and it is not a room.
constexpr double kInwardNormalSpread = 0.8;

/// How the given normals of a cloud face: each point with a finite, non-zero normal that lies at
/// least kNormalSideMargin of the bounding-box diagonal from the box's centre along its normal
/// counts as facing inwards (towards the centre) or outwards. Points nearer the centre's plane
/// tell little (a flat scan has them all there) and are not counted.
struct NormalSides {
  std::size_t inwards = 0;   ///< points whose normal points towards the box centre
  std::size_t outwards = 0;  ///< points whose normal points away from it
  /// Length of the mean unit normal of the facing-inwards points (0 when there are none): near
  /// 1 when they all face one way, small when they face the middle from all sides.
  double inward_agreement = 0.0;
  bool turned = false;  ///< turnInwardNormalsOutward flipped every normal

  /// Share of the counted points that face inwards; 0 when none counts.
  double inwardShare() const {
    const std::size_t counted = inwards + outwards;
    return counted == 0 ? 0.0 : static_cast<double>(inwards) / static_cast<double>(counted);
  }
  /// True when the normals face inwards as a whole: more than kInwardNormalShare of the counted
  /// points face inwards, and those face many ways (inward_agreement below kInwardNormalSpread).
  bool faceInwards() const { return inwardShare() > kInwardNormalShare && inward_agreement < kInwardNormalSpread; }
};

/// Fraction of the bounding-box diagonal a point must lie from the box centre along its normal to
/// count in NormalSides.
constexpr double kNormalSideMargin = 0.05;

/// How the normals of `cloud` face (NormalSides). Non-finite points are ignored.
NormalSides normalSides(const pcl::PointCloud<pcl::PointNormal>& cloud);

/// Flips every normal of `cloud` (non-finite and zero ones stay so).
void flipNormals(pcl::PointCloud<pcl::PointNormal>& cloud);

/// Flips every normal of `cloud` when its normals face inwards as a whole (NormalSides::faceInwards),
/// so that the pipeline reconstructs the solid they enclose: a room's volume, with its faces
/// facing out of it. Returns what normalSides read, with `turned` set when it flipped.
NormalSides turnInwardNormalsOutward(pcl::PointCloud<pcl::PointNormal>& cloud);

}  // namespace paco
