#pragma once
// The tools' default plane sizes as shares of a scan's points, and how their texts print them.
//   int min_points = paco::scanMinPointsPerPlane(cloud.size());   // paco/segmentation/planar_segmenter.h
//   std::string help = "0: " + paco::percentText(paco::kScanMinPlaneFraction) + " of the points";
// Here, in common, so that tools and modules without the segmentation module (paco_dataset,
// paco_eval, paco::data) print the same rule.
#include <sstream>
#include <string>

namespace paco {

/// The smallest plane paco_reconstruct, paco_complete and paco_eval keep by default, as a share
/// of the segmented points (PlanarSegmenter's own default, 50 points, does not scale with the
/// cloud). On the 2,048-point partial MFCAD scans the network is trained for, 50 points (2.4 %)
/// leave out many of a part's pockets and steps. 1 % (20 points) finds the walls of small holes
/// and pockets that 1.5 % (31) left out: on 300 validation parts PolyFit's CD fell by 0.064 and
/// HD by 0.37, with no failure (thirty-fourth session; 1.5 % before, when 1 % still made PolyFit
/// fail and the real roof scans worse). 0.4 % gained more on MFCAD (forty-fourth session), but
/// gave the cell complex two components on three of the six real-scan runs. A share, unlike a
/// count, also keeps the noise planes of dense real scans out (doc/results.md, "Smaller planes").
constexpr double kScanMinPlaneFraction = 0.01;

/// The smallest plane on an exact scan, one whose points lie on their surfaces to within
/// kExactScanNoiseLevel (samples of a CAD model or of a synthetic scan; no real scan measured so
/// far is one): 0.25 %, 5 of a 2,048-point input (PlanarSegmenter::setExactScanMinPointsPerPlane).
/// Without noise, a handful of points that fit one plane with agreeing normals is a face: the wall
/// of a small hole or pocket, seen by 8 to 20 points, which the 1 % rule closes over. On 300
/// validation parts PolyFit's CD fell by 0.047 and HD by 0.45, the cell complex's by 0.064 and
/// 0.43 (forty-eighth session, doc/results.md "Exact scans keep planes of 0.25 %"). Real scans,
/// where the 0.4 % of the forty-fourth session gave the cell complex two components, keep 1 %.
constexpr double kExactScanMinPlaneFraction = 0.0025;

/// The share of a scan's points a plane parallel to a larger one needs in the tools
/// (PlanarSegmenter::setMinPointsPerParallelPlane): 0.15 %, 3 of a 2,048-point input, the fewest
/// any plane may have. Such a plane is nearly always a pocket's floor or a step's face seen by a
/// handful of points; 0.5 % (10 points, before the forty-fourth session) left most of them out.
constexpr double kScanMinParallelPlaneFraction = 0.0015;

/// The share a parallel plane needs on a noisy scan, one whose noise widens the segmenter's inlier
/// distance (PlanarSegmenter::setNoiseAdaptation): 0.5 %, the rule before the forty-fourth
/// session. Noise scatters a face's points off its plane, and planes of a handful of points are
/// then pieces of that scatter (doc/results.md, forty-fourth session). Since the forty-seventh
/// session the scatter over a face is never a plane (detail::recoverParallelPlanes); with that, the
/// clean-scan share on noisy scans scored the same CD and more planes, so this one stays.
constexpr double kNoisyScanMinParallelPlaneFraction = 0.005;

/// A share of points as the tools' help texts and messages print it: 0.01 -> "1 %". Texts print
/// the constants above with it, so that a new rule needs no edit of them.
inline std::string percentText(double fraction) {
  std::ostringstream text;
  text << fraction * 100.0 << " %";
  return text.str();
}

}  // namespace paco
