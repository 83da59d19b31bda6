#include <paco/completion/matching.h>

#include <paco/common/error.h>

#include <algorithm>
#include <limits>
#include <string>

namespace paco::completion {
namespace {
// Elements of a temporary distance block: keeps no-grad distance matrices near 64 MB.
constexpr int64_t kBlockElements = int64_t{1} << 24;
}  // namespace

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
    // Chamfer between every prediction and every GT plane: the GT points are sorted by plane
    // once, so each plane is a contiguous slice of the distance block; chunks of predictions
    // bound memory (paper preset: 40 x 1280 points vs 8192).
    const int64_t all_gt = truth.points.size(1);
    const int64_t gt_stride = config.match_gt_points > 0 ? (all_gt + config.match_gt_points - 1) / config.match_gt_points : 1;
    const int64_t pred_stride =
        config.match_points_per_plane > 0 ? (P + config.match_points_per_plane - 1) / config.match_points_per_plane : 1;
    const auto y = truth.points[b].slice(0, 0, all_gt, std::max<int64_t>(gt_stride, 1));
    const auto labels = truth.labels[b].slice(0, 0, all_gt, std::max<int64_t>(gt_stride, 1));
    const auto predicted = output.points[b].slice(1, 0, P, std::max<int64_t>(pred_stride, 1));
    const int64_t Ps = predicted.size(1);
    const int64_t G = y.size(0);
    const auto y_sorted = y.index_select(0, torch::argsort(labels));
    const auto counts = torch::bincount(labels, {}, planes);
    std::vector<int64_t> first(planes + 1, 0);
    for (int g = 0; g < planes; ++g) first[g + 1] = first[g] + counts[g].item<int64_t>();
    const int64_t chunk = std::max<int64_t>(1, kBlockElements / (Ps * G));
    for (int64_t start = 0; start < M; start += chunk) {
      const int64_t end = std::min(M, start + chunk);
      const int64_t c = end - start;
      const auto x = predicted.slice(0, start, end).reshape({c * Ps, 3});
      const auto d = pairwiseSquaredDistances(x, y_sorted).view({c, Ps, G});
      for (int g = 0; g < planes; ++g) {
        if (first[g + 1] == first[g]) continue;  // no GT points: judged by its parameters only
        const auto dg = d.slice(2, first[g], first[g + 1]);
        const auto chamfer = std::get<0>(dg.min(2)).mean(1) + std::get<0>(dg.min(1)).mean(1);  // (c)
        cost[g].slice(0, start, end) += config.match_chamfer_weight * chamfer.to(torch::kDouble);
      }
    }
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
  Matching matching(truth.batchSize());
  for (int b = 0; b < truth.batchSize(); ++b) {
    const Eigen::MatrixXd cost = matchingCost(output, truth, b, config);
    if (!cost.allFinite())
      throw ModelError("training diverged: the network's predictions for sample " + std::to_string(b) +
                       " are not finite; lower the learning rate or resume from an earlier checkpoint");
    matching[b] = paco::solveAssignment(cost);
  }
  return matching;
}

}  // namespace paco::completion
