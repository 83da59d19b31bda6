#pragma once
// Usage:
//   paco::completion::LossConfig config;  config.disable("repulsion");   // ablation
//   paco::completion::LossResult loss = paco::completion::computeLosses(output, batch.truth, config);
//   loss.total.backward();   // loss.terms["plane_chamfer"] etc. for logs
#include <paco/completion/batch.h>
#include <paco/completion/network.h>

#include <Eigen/Core>
#include <torch/torch.h>

#include <map>
#include <string>
#include <vector>

namespace paco::completion {

/// Weights and switches of the training objective (paper Section 3.4; defaults as the authors'
/// code, plus the offset and ranking terms they lack). Normalisation: the two chamfer terms are
/// divided by the batch size, every other per-plane term by the number of GT planes in the batch,
/// the ranking term is a mean over all candidates.
struct LossConfig {
  bool classification = true;     ///< BCE plane/empty on every prediction
  double classification_weight = 1.0;
  double empty_weight = 0.4;      ///< weight of the "empty" target, in [0, 1]
  /// A matched prediction's classification target is 1 only when its plane lies within
  /// quality_angle_deg and quality_offset of the GT plane it was matched to; otherwise 0, with the
  /// empty target's weight. Off (the paper's target): every matched prediction gets 1, so a query
  /// matched to an unseen plane that the network cannot place still learns high confidence, and
  /// the network hedges: averaged planes through the part's centre at confidence 0.8-0.9, which
  /// the confidence threshold cannot tell from right ones (doc/results.md).
  bool quality_classification = false;
  double quality_angle_deg = 10.0;
  double quality_offset = 0.05;   ///< normalised units
  bool normal = true;             ///< ‖n̂−n‖² + cosine_weight·(1−cos) on matched pairs
  double normal_weight = 1.0;
  double cosine_weight = 1.0;     ///< λ of the paper's normal loss
  bool offset = true;             ///< |r̂−r| on matched pairs (normalised units)
  double offset_weight = 1.0;
  bool plane_chamfer = true;      ///< squared-L2 chamfer between matched point sets
  double plane_chamfer_weight = 20.0;
  bool overall_chamfer = true;    ///< squared-L2 chamfer between all matched points and all GT points
  double overall_chamfer_weight = 20.0;
  bool repulsion = true;          ///< PU-Net repulsion inside each matched primitive
  double repulsion_weight = 2.0;
  int repulsion_k = 5;            ///< neighbours per point
  double repulsion_h = 0.03;      ///< kernel width h (normalised units)
  double repulsion_radius = 0.07; ///< constant of radius − d·exp(−d²/h²); keeps the term ≥ 0
  bool ranking = true;            ///< BCE on candidate scores: does its coarse plane match a GT plane?
  double ranking_weight = 1.0;
  double ranking_angle_deg = 10.0;   ///< a candidate matches when its normal is within this angle ...
  double ranking_offset = 0.02;      ///< ... and |Δr| is below this (normalised units)

  /// Weights of the matching cost C = wc·cls + wn·normal + wo·offset + wp·chamfer + wr·repulsion.
  /// A term whose loss is disabled is left out of the cost too.
  double match_classification_weight = 1.0;
  double match_normal_weight = 1.0;
  double match_offset_weight = 1.0;
  double match_chamfer_weight = 20.0;
  double match_repulsion_weight = 2.0;
  /// The matching cost only ranks pairs, so its chamfer part uses a strided subset: at most this
  /// many GT points per sample and points per predicted plane (0: all). The losses use all.
  int match_gt_points = 2048;
  int match_points_per_plane = 64;

  /// Names accepted by disable(): classification, normal, offset, plane_chamfer,
  /// overall_chamfer, repulsion, ranking.
  static const std::vector<std::string>& termNames();
  /// Switches one term off; throws InvalidInputError on an unknown name (the message lists them).
  void disable(const std::string& name);
  bool enabled(const std::string& name) const;
};

/// For each sample, for each of its GT planes, the index of the prediction matched to it.
using Matching = std::vector<std::vector<int>>;

struct LossResult {
  torch::Tensor total;                  ///< scalar, differentiable
  std::map<std::string, double> terms;  ///< each enabled term, weighted, as added to the total
  Matching matching;                    ///< the assignment used
  double matching_seconds = 0.0;        ///< wall time of the Hungarian matching (cost + assignment)
};

/// Squared distances (n, m) between the rows of a (n, 3) and b (m, 3), clamped at 0.
torch::Tensor pairwiseSquaredDistances(const torch::Tensor& a, const torch::Tensor& b);

/// Squared-L2 chamfer distance mean_a min_b ‖a−b‖² + mean_b min_a ‖a−b‖² between a (n, 3) and
/// b (m, 3). Differentiable in both (nearest neighbours found without autograd, then gathered).
torch::Tensor chamferSquared(const torch::Tensor& a, const torch::Tensor& b);

/// Repulsion of each point set of `points` (T, P, 3): the mean over points and their k nearest
/// neighbours (same set) of radius − d·exp(−d²/h²). Returns (T). Needs P > k.
torch::Tensor repulsionLoss(const torch::Tensor& points, int k, double h, double radius);

/// Normal loss per row of (T, 3) unit normals: ‖n̂−n‖² + cosine_weight·(1 − n̂·n). Returns (T).
torch::Tensor normalLoss(const torch::Tensor& predicted, const torch::Tensor& truth, double cosine_weight);

/// Ranking targets (B, Q) float in {0, 1}: 1 when a candidate's coarse plane is within
/// `ranking_angle_deg` and `ranking_offset` of one of the sample's GT planes (oriented).
torch::Tensor rankingTargets(const torch::Tensor& candidate_normals, const torch::Tensor& candidate_offsets,
                             const GroundTruthBatch& truth, const LossConfig& config);

/// Matches, then sums the enabled terms. Throws InvalidInputError on mismatched shapes and
/// ModelError when the predictions are not finite (diverged training).
LossResult computeLosses(const NetworkOutput& output, const GroundTruthBatch& truth, const LossConfig& config);

/// Plane-level quality of a batch, for validation.
struct PlaneMetrics {
  double recall = 0.0;     ///< GT planes with a confident prediction within the ranking tolerances
  double precision = 0.0;  ///< confident predictions within the tolerances of some GT plane
  double nc_prim = 0.0;    ///< mean |n̂·n| over matched pairs (NC_prim-like)
  int gt_planes = 0;       ///< counts behind the ratios, so batches can be pooled
  int confident = 0;
  int recalled = 0;
  int precise = 0;
  double nc_sum = 0.0;
  /// Adds another batch's counts and recomputes the ratios.
  void accumulate(const PlaneMetrics& other);
};

/// Confident = sigmoid(logit) > `confidence_threshold` (default 0.7 as at inference).
PlaneMetrics planeMetrics(const NetworkOutput& output, const GroundTruthBatch& truth, const Matching& matching,
                          const LossConfig& config, double confidence_threshold = 0.7);

}  // namespace paco::completion
