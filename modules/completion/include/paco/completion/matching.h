#pragma once
// Usage:
//   paco::completion::LossConfig config;                                   // cost weights
//   paco::completion::Matching m = paco::completion::matchPredictions(output, batch.truth, config);
//   int prediction = m[b][g];   // the prediction matched to GT plane g of sample b (-1: none)
#include <paco/common/assignment.h>
#include <paco/completion/batch.h>
#include <paco/completion/losses.h>
#include <paco/completion/network.h>

#include <Eigen/Core>

namespace paco::completion {

/// Matching cost of sample `b` (rows: its GT planes, columns: its M predictions), in doubles,
/// without autograd: C = wc·cls + wn·normal + wo·offset + wp·plane chamfer + wr·repulsion with
/// the `match_*` weights of `config`; a term whose loss is disabled is left out. The
/// classification part is aligned with the loss: CE("plane") minus the weighted CE("empty")
/// that the prediction no longer pays once matched, so the minimum-cost matching minimises the
/// classification loss too. A GT plane without GT points is matched on its parameters alone.
Eigen::MatrixXd matchingCost(const NetworkOutput& output, const GroundTruthBatch& truth, int b,
                             const LossConfig& config);

/// Hungarian matching (paco::solveAssignment) of every sample of the batch: the GT planes, padded
/// with "empty", against the M predictions. Throws ModelError when a cost is not finite
/// (diverged training).
Matching matchPredictions(const NetworkOutput& output, const GroundTruthBatch& truth,
                          const LossConfig& config);

}  // namespace paco::completion
