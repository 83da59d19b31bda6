#pragma once
// The completion and observed-fusion steps of paco_reconstruct and paco_complete, timed and
// reported alike.
#include "app_support.h"

#include <paco/common/normalization.h>
#include <paco/completion/observed_fusion.h>
#include <paco/completion/turn_ensemble.h>

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

/// "complete: N primitives with confidence > T", how many turns voted, and how far the scan was
/// turned for the network (models with input orientation "seen-planes"), so that a user sees
/// what the model was given.
inline void reportCompletion(std::size_t primitives, double threshold, int turns, const Normalization& frame) {
  const double degrees = Eigen::AngleAxisd(frame.rotation).angle() * 180.0 / 3.14159265358979323846;
  std::printf("complete: %zu primitives with confidence > %.2f", primitives, threshold);
  if (turns > 1) std::printf(" (voted over %d turns of the scan)", turns);
  if (degrees > 0.05) std::printf(" (the scan turned by %.1f deg onto its seen faces for the network)", degrees);
  std::printf("\n");
}

/// Stages 2-3: encodes and completes the scan, the network run on `turns` turns of it and the
/// planes voted on (paco::completeWithTurns), timed as "complete" (encoder and network).
inline std::vector<PlanarPrimitive> completeScan(const CompletionModel::ConstPtr& model,
                                                 const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                                 const PlanarSegmentation& segmentation, double threshold, int turns,
                                                 int points, StageTimer& timer) {
  TurnEnsembleOptions options;
  options.turns = turns;
  options.threshold = threshold;
  options.num_points = points;
  Normalization frame;
  timer.start("complete");
  std::vector<PlanarPrimitive> primitives = completeWithTurns(model, cloud, segmentation, options, &frame);
  timer.stop();
  reportCompletion(primitives.size(), threshold, turns, frame);
  return primitives;
}

/// The --turns option of the tools that complete (TurnEnsembleOptions::turns).
inline void addTurnsOption(boost::program_options::options_description& options, int& turns) {
  options.add_options()("turns", boost::program_options::value(&turns)->default_value(turns),
                        "run the network on this many 90-degree turns of the scan and keep the planes most turns "
                        "predict (1 to 24; 1: once)");
}

/// Throws UsageError unless 1 <= turns <= kMaxEnsembleTurns.
inline void checkTurns(int turns) {
  if (turns < 1 || turns > kMaxEnsembleTurns)
    throw UsageError("--turns must be 1 to " + std::to_string(kMaxEnsembleTurns) + ", got " + std::to_string(turns));
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
