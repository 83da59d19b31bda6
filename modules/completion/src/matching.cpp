#include <paco/completion/matching.h>

#include <paco/common/error.h>

#include "nearest_neighbours.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <limits>
#include <string>

namespace paco::completion {
Eigen::MatrixXd matchingCost(const NetworkOutput& output, const GroundTruthBatch& truth, int b,
                             const LossConfig& config) {
  torch::NoGradGuard no_grad;
  const int planes = truth.planeCount(b);
  const int64_t M = output.normals.size(1);
  const int64_t P = output.points.size(2);
  auto cost = torch::zeros({planes, M}, torch::kDouble);
  if (planes == 0) return Eigen::MatrixXd(0, M);
  const auto normals = output.normals[b].to(torch::kDouble);              // (M, 3)
  const auto gt_normals = truth.normals[b].slice(0, 0, planes).to(torch::kDouble);  // (G, 3)
  if (config.classification) {
    const auto logits = output.logits[b].to(torch::kDouble);
    // Aligned with the loss: matching j costs its "plane" CE and saves its weighted "empty" CE.
    const auto c = torch::softplus(-logits) - config.empty_weight * torch::softplus(logits);
    cost += config.match_classification_weight * c.unsqueeze(0);
  }
  if (config.normal) {
    const auto cosine = torch::matmul(gt_normals, normals.transpose(0, 1));  // (G, M)
    const auto squared = (gt_normals.unsqueeze(1) - normals.unsqueeze(0)).pow(2).sum(-1);
    cost += config.match_normal_weight * (squared + config.cosine_weight * (1.0 - cosine));
  }
  if (config.offset) {
    const auto r = output.offsets[b].to(torch::kDouble);
    const auto gt_r = truth.offsets[b].slice(0, 0, planes).to(torch::kDouble);
    cost += config.match_offset_weight * (gt_r.unsqueeze(1) - r.unsqueeze(0)).abs();
  }
  if (config.plane_chamfer) {
    // Chamfer between every prediction and every GT plane on strided subsets (the cost only
    // ranks pairs): at most match_gt_points GT points and match_points_per_plane per prediction.
    const int64_t all_gt = truth.points.size(1);
    const int64_t gt_stride = config.match_gt_points > 0 ? (all_gt + config.match_gt_points - 1) / config.match_gt_points : 1;
    const int64_t pred_stride =
        config.match_points_per_plane > 0 ? (P + config.match_points_per_plane - 1) / config.match_points_per_plane : 1;
    const auto y = truth.points[b].slice(0, 0, all_gt, std::max<int64_t>(gt_stride, 1)).to(torch::kFloat).contiguous();
    const auto labels = truth.labels[b].slice(0, 0, all_gt, std::max<int64_t>(gt_stride, 1)).to(torch::kLong).contiguous();
    const auto predicted = output.points[b].slice(1, 0, P, std::max<int64_t>(pred_stride, 1)).to(torch::kFloat).contiguous();
    auto chamfer = torch::empty({planes, M}, torch::kDouble);
    detail::planeChamferTable(predicted.data_ptr<float>(), M, predicted.size(1), y.data_ptr<float>(),
                              labels.data_ptr<int64_t>(), y.size(0), planes, chamfer.data_ptr<double>());
    cost += config.match_chamfer_weight * chamfer;
  }
  if (config.repulsion && P > config.repulsion_k) {
    const auto rep = repulsionLoss(output.points[b], config.repulsion_k, config.repulsion_h,
                                   config.repulsion_radius);
    cost += config.match_repulsion_weight * rep.to(torch::kDouble).unsqueeze(0);
  }
  const auto contiguous = cost.contiguous();
  Eigen::MatrixXd result(planes, M);
  const double* data = contiguous.data_ptr<double>();
  for (int g = 0; g < planes; ++g)
    for (int64_t j = 0; j < M; ++j) result(g, j) = data[g * M + j];
  return result;
}

Matching matchPredictions(const NetworkOutput& output, const GroundTruthBatch& truth, const LossConfig& config) {
  const int B = truth.batchSize();
  Matching matching(B);
  std::vector<char> finite(static_cast<std::size_t>(B), 1);
  // Samples are independent: one per thread (LibTorch ops inside run single-threaded).
  at::parallel_for(0, B, 1, [&](int64_t begin, int64_t end) {
    for (int64_t b = begin; b < end; ++b) {
      const Eigen::MatrixXd cost = matchingCost(output, truth, static_cast<int>(b), config);
      if (!cost.allFinite()) {
        finite[b] = 0;
        continue;
      }
      matching[b] = paco::solveAssignment(cost);
    }
  });
  for (int b = 0; b < B; ++b)
    if (!finite[b])
      throw ModelError("training diverged: the network's predictions for sample " + std::to_string(b) +
                       " are not finite; lower the learning rate or resume from an earlier checkpoint");
  return matching;
}

}  // namespace paco::completion
