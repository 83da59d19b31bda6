#pragma once
// The observed-fusion step of paco_reconstruct and paco_complete, timed and reported alike.
#include "app_support.h"

#include <paco/completion/observed_fusion.h>

#include <cstdio>
#include <vector>

namespace paco::app {

/// Replaces `primitives` (the completion) by their fusion with the seen faces of `cloud`.
inline void fuseWithSeenFaces(std::vector<PlanarPrimitive>& primitives, const pcl::PointCloud<pcl::PointNormal>& cloud,
                              const PlanarSegmentation& segmentation, StageTimer& timer) {
  timer.start("fuse");
  ObservedFusionReport report;
  primitives = fuseWithObserved(std::move(primitives), makePrimitives(cloud, segmentation), {}, &report);
  timer.stop();
  std::printf("fuse with the seen faces: %s\n", describe(report).c_str());
}

}  // namespace paco::app
