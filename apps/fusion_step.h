#pragma once
// The completion's report and the observed-fusion step of paco_reconstruct and paco_complete,
// timed and reported alike.
#include "app_support.h"

#include <paco/common/normalization.h>
#include <paco/completion/observed_fusion.h>

#include <Eigen/Geometry>

#include <cmath>
#include <cstdio>
#include <vector>

namespace paco::app {

/// The fusion flags with the library's defaults (paco::ObservedFusionOptions).
inline FusionFlags libraryFusionFlags() {
  const ObservedFusionOptions defaults;
  return FusionFlags(defaults.align_unseen_degrees, defaults.clip_margin, defaults.fill_spacing,
                     defaults.unseen_point_fraction);
}

/// "complete: N primitives with confidence > T", and how far the scan was turned for the network
/// (models with input orientation "seen-planes"), so that a user sees what the model was given.
inline void reportCompletion(std::size_t primitives, double threshold, const Normalization& frame) {
  const double degrees = Eigen::AngleAxisd(frame.rotation).angle() * 180.0 / 3.14159265358979323846;
  std::printf("complete: %zu primitives with confidence > %.2f", primitives, threshold);
  if (degrees > 0.05) std::printf(" (the scan turned by %.1f deg onto its seen faces for the network)", degrees);
  std::printf("\n");
}

/// Replaces `primitives` (the completion) by their fusion with the seen faces of `cloud`.
inline void fuseWithSeenFaces(std::vector<PlanarPrimitive>& primitives, const pcl::PointCloud<pcl::PointNormal>& cloud,
                              const PlanarSegmentation& segmentation, const FusionFlags& flags, StageTimer& timer) {
  timer.start("fuse");
  ObservedFusionReport report;
  ObservedFusionOptions options;
  options.align_unseen_degrees = flags.align_unseen_degrees;
  options.clip_margin = flags.clipMargin();
  options.fill_spacing = flags.fill_box_spacing;
  options.unseen_point_fraction = flags.unseen_point_fraction;
  primitives = fuseWithObserved(std::move(primitives), makePrimitives(cloud, segmentation), options, &report);
  timer.stop();
  std::printf("fuse with the seen faces: %s\n", describe(report).c_str());
}

}  // namespace paco::app
