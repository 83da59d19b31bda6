#pragma once
// Usage:
//   paco::TurnEnsembleOptions options; options.turns = 4;
//   std::vector<paco::PlanarPrimitive> primitives =
//       paco::completeWithTurns(model, cloud, segmentation, options);  // user frame, as ParametricCompleter
//
// Test-time ensembling. The network sees a scan in its own bounding-box frame; turned by 90
// degrees about an axis, the same scan is as plausible an input, and the network's guesses for
// the unseen side change with the turn. A plane predicted under most turns is a part's face
// more often than one predicted under a single turn; the vote keeps those, and the points of
// the turns that agree cover more of the face than one turn's.
#include <paco/common/normalization.h>
#include <paco/common/primitive.h>
#include <paco/encoding/completion_model.h>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <vector>

namespace paco {

/// The most turns completeWithTurns takes: the 24 rotations that map the coordinate axes onto
/// themselves.
constexpr int kMaxEnsembleTurns = 24;

/// The first `count` (1..kMaxEnsembleTurns) of the axis-preserving rotations, in a fixed order:
/// the identity, the three half turns about the axes (a box keeps its extent along every axis),
/// then the other 20 (quarter turns about an axis, turns about a diagonal). Throws
/// InvalidInputError outside 1..kMaxEnsembleTurns.
std::vector<Eigen::Matrix3d> ensembleTurns(int count);

struct TurnEnsembleOptions {
  /// Turns of the input the network sees (1..kMaxEnsembleTurns; 1: the input as it is, the
  /// network run once, exactly as ParametricCompleter). 4 (the identity and the three half
  /// turns) lowered the shipped model's mean CD at 25 % and 50 % missing and the cell complex's
  /// at 75 % on MFCAD validation parts, for four times the network's time (doc/results.md).
  int turns = 4;
  /// Keep a merged primitive when its confidence, the mean over the turns of its best member's
  /// confidence (0 for a turn that did not predict it), is above this (as
  /// ParametricCompleter::setConfidenceThreshold).
  double threshold = 0.7;
  /// Predictions of one turn enter the vote above this confidence (in [0, 1]; `threshold` when
  /// that is lower). A face the network is unsure of under some turns still gets their votes.
  double candidate_threshold = 0.3;
  /// Two predictions are of the same face when their oriented normals are within this angle
  /// (degrees)...
  double max_angle_degrees = 10.0;
  /// ...and the points of the less confident one lie on average within this distance of the
  /// other's plane (fraction of the input's bounding-box diagonal).
  double max_distance = 0.02;
  /// Points fed to the network per turn (PlaneProxyEncoder::setNumPoints).
  int num_points = 2048;
};

/// Merges the predictions of several runs (all in one frame) into one set of primitives. Runs
/// are taken as turns: a primitive's confidence is the mean over the runs of the best confidence
/// among its members from that run. Each merged primitive has the confidence-weighted mean plane
/// of its members and their points projected onto it, evenly thinned to the most confident
/// member's count. Sorted by decreasing confidence; those at or below `options.threshold` are
/// dropped. `diagonal` (> 0) scales options.max_distance. Throws InvalidInputError for no run, a
/// non-positive diagonal or options out of range.
std::vector<PlanarPrimitive> mergeTurnPredictions(const std::vector<std::vector<PlanarPrimitive>>& runs,
                                                  double diagonal, const TurnEnsembleOptions& options);

/// Stages 2-3 with test-time ensembling: encodes and completes the cloud under each of
/// ensembleTurns(options.turns) (PlaneProxyEncoder::setTurn), then merges the predictions
/// (mergeTurnPredictions). With one turn the result is ParametricCompleter's at options.threshold.
/// Primitives are in the cloud's frame and units. `frame`, when given, receives the network frame
/// of the unturned run (PlaneProxies::normalization). Throws as the encoder and the completer do,
/// and InvalidInputError for options out of range.
std::vector<PlanarPrimitive> completeWithTurns(const CompletionModel::ConstPtr& model,
                                               const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                               const PlanarSegmentation& segmentation,
                                               const TurnEnsembleOptions& options, Normalization* frame = nullptr);

}  // namespace paco
