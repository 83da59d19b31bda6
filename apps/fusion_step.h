#pragma once
// The completion and observed-fusion steps of paco_reconstruct and paco_complete, timed and
// reported alike.
#include "app_support.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/common/point_types.h>
#include <paco/completion/observed_fusion.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/io/cloud_io.h>

#include <Eigen/Geometry>
#include <boost/algorithm/string.hpp>

#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

namespace paco::app {

/// The fusion flags with the library's defaults (paco::ObservedFusionOptions).
inline FusionFlags libraryFusionFlags() {
  const ObservedFusionOptions defaults;
  return FusionFlags(defaults.align_unseen_degrees, defaults.clip_margin, defaults.fill_spacing,
                     defaults.unseen_point_fraction, defaults.contradiction_radius, defaults.join_distance);
}

/// "complete: N primitives with confidence > T", how many turns voted, and how far the scan was
/// turned for the network (models with input orientation "seen-planes"), so that a user sees
/// what the model was given.
inline void reportCompletion(std::size_t primitives, double threshold, int turns, const Normalization& frame) {
  const double degrees = paco::radiansToDegrees(Eigen::AngleAxisd(frame.rotation).angle());
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

/// The --known-extent option of the tools that fuse (ObservedFusionOptions::known_extent_points).
inline void addKnownExtentOption(boost::program_options::options_description& options, std::string& text) {
  options.add_options()("known-extent", boost::program_options::value(&text),
                        "X0,Y0,Z0,X1,Y1,Z1 (a box), or a cloud file of points (e.g. a footprint's corners at ground "
                        "and roof height): where the object is known to reach, in the input's units and frame; the "
                        "hidden side is closed there instead of at the scan's box (with fusion)");
}

/// The points of --known-extent: the cloud in the file `text` names when it exists, else the
/// corners of the box "X0,Y0,Z0,X1,Y1,Z1"; none for empty text. Throws UsageError unless the box
/// is six finite numbers with X0 <= X1, Y0 <= Y1 and Z0 <= Z1, and IoError for a cloud file that
/// cannot be read.
inline std::vector<Eigen::Vector3d> parseKnownExtent(const std::string& text) {
  if (text.empty()) return {};
  if (std::filesystem::is_regular_file(text)) {
    const std::vector<Eigen::Vector3d> points = positionsOf(io::loadCloud(text).points);  // finite: checked
    if (points.empty()) throw IoError("--known-extent: '" + text + "' has no points");
    return points;
  }
  std::vector<std::string> items;
  boost::algorithm::split(items, text, boost::is_any_of(","));
  std::vector<double> values;
  for (const std::string& item : items) {
    std::size_t used = 0;
    double value = std::nan("");
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(value))
      throw UsageError("--known-extent takes X0,Y0,Z0,X1,Y1,Z1 (six numbers) or an existing cloud file; '" + item +
                       "' in '" + text + "' is not a finite number");
    values.push_back(value);
  }
  if (values.size() != 6)
    throw UsageError("--known-extent takes X0,Y0,Z0,X1,Y1,Z1 (six numbers), got " + std::to_string(values.size()));
  const Eigen::AlignedBox3d box(Eigen::Vector3d(values[0], values[1], values[2]),
                                Eigen::Vector3d(values[3], values[4], values[5]));
  if ((box.min().array() > box.max().array()).any())
    throw UsageError("--known-extent: X0,Y0,Z0 must not exceed X1,Y1,Z1 (got '" + text + "')");
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < 8; ++i) corners.push_back(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i)));
  return corners;
}

/// Replaces `primitives` (the completion) by their fusion with the seen faces of `cloud`; the box
/// fill reaches `known_extent` (parseKnownExtent) when given.
inline void fuseWithSeenFaces(std::vector<PlanarPrimitive>& primitives, const pcl::PointCloud<pcl::PointNormal>& cloud,
                              const PlanarSegmentation& segmentation, const FusionFlags& flags,
                              const std::vector<Eigen::Vector3d>& known_extent, StageTimer& timer) {
  timer.start("fuse");
  ObservedFusionReport report;
  ObservedFusionOptions options;
  options.align_unseen_degrees = flags.align_unseen_degrees;
  options.clip_margin = flags.clipMargin();
  options.fill_spacing = flags.fill_box_spacing;
  options.unseen_point_fraction = flags.unseen_point_fraction;
  options.contradiction_radius = flags.contradiction_radius;
  options.join_distance = flags.join_distance;
  options.known_extent_points = known_extent;
  primitives = fuseWithObserved(std::move(primitives), makePrimitives(cloud, segmentation), options, &report);
  timer.stop();
  std::printf("fuse with the seen faces%s: %s\n", known_extent.empty() ? "" : " (box fill to the known extent)",
              describe(report).c_str());
}

}  // namespace paco::app
