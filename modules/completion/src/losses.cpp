#include <paco/completion/losses.h>

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/completion/matching.h>

#include "nearest_neighbours.h"

#include <ATen/Parallel.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace paco::completion {

torch::Tensor pairwiseSquaredDistances(const torch::Tensor& a, const torch::Tensor& b) {
  const auto a2 = a.pow(2).sum(-1).unsqueeze(1);
  const auto b2 = b.pow(2).sum(-1).unsqueeze(0);
  return (a2 + b2 - 2.0 * torch::matmul(a, b.transpose(0, 1))).clamp_min(0.0);
}

namespace {


void requireShape(const torch::Tensor& t, const std::vector<int64_t>& shape, const char* name) {
  bool ok = t.defined() && t.dim() == static_cast<int64_t>(shape.size());
  for (std::size_t i = 0; ok && i < shape.size(); ++i)
    ok = shape[i] < 0 || t.size(static_cast<int64_t>(i)) == shape[i];
  if (!ok) {
    std::ostringstream message;
    message << "computeLosses: " << name << " has shape ";
    if (t.defined()) message << t.sizes(); else message << "(undefined)";
    message << ", expected [";
    for (std::size_t i = 0; i < shape.size(); ++i)
      message << (i ? ", " : "") << (shape[i] < 0 ? std::string("*") : std::to_string(shape[i]));
    message << "]; the network output and the ground-truth batch do not belong together";
    throw InvalidInputError(message.str());
  }
}

void validate(const NetworkOutput& output, const GroundTruthBatch& truth) {
  const int64_t B = truth.batchSize();
  if (B == 0) throw InvalidInputError("computeLosses: the ground-truth batch is empty");
  requireShape(truth.points, {B, -1, 3}, "truth.points");
  requireShape(truth.labels, {B, truth.points.size(1)}, "truth.labels");
  requireShape(truth.normals, {B, -1, 3}, "truth.normals");
  requireShape(truth.offsets, {B, truth.normals.size(1)}, "truth.offsets");
  requireShape(truth.mask, {B, truth.normals.size(1)}, "truth.mask");
  requireShape(output.normals, {B, -1, 3}, "output.normals");
  const int64_t M = output.normals.size(1);
  requireShape(output.offsets, {B, M}, "output.offsets");
  requireShape(output.points, {B, M, -1, 3}, "output.points");
  requireShape(output.logits, {B, M}, "output.logits");
  // Real planes must come first in each row of the mask (collate() writes them so).
  const auto mask = truth.mask.to(torch::kCPU).to(torch::kBool);
  for (int64_t b = 0; b < B; ++b) {
    const int64_t count = mask[b].sum().item<int64_t>();
    if (count > 0 && !mask[b].slice(0, 0, count).all().item<bool>())
      throw InvalidInputError("computeLosses: truth.mask of sample " + std::to_string(b) +
                              " is not a prefix; real planes must come before the padding");
  }
}

// Indices (T, P, k) of the k nearest other points of each point inside its own set.
torch::Tensor neighbourIndices(const torch::Tensor& points, int k) {
  const auto x = points.detach().to(torch::kFloat).contiguous();
  const int64_t T = x.size(0), P = x.size(1);
  auto result = torch::empty({T, P, k}, torch::kLong);
  const float* data = x.data_ptr<float>();
  int64_t* out = result.data_ptr<int64_t>();
  at::parallel_for(0, T, 1, [&](int64_t begin, int64_t end) {
    for (int64_t t = begin; t < end; ++t) detail::kNearestWithinSet(data + t * P * 3, P, k, out + t * P * k);
  });
  return result;
}

// Pairs (predicted point, GT point) whose weighted squared distances make up a chamfer term:
// term = Σ weight · ‖predicted − gt‖². Indices are into the flattened batch.
struct ChamferPairs {
  std::vector<int64_t> predicted, gt;
  std::vector<double> weight;
  void add(int64_t p, int64_t g, double w) {
    predicted.push_back(p);
    gt.push_back(g);
    weight.push_back(w);
  }
  void append(const ChamferPairs& other) {
    predicted.insert(predicted.end(), other.predicted.begin(), other.predicted.end());
    gt.insert(gt.end(), other.gt.begin(), other.gt.end());
    weight.insert(weight.end(), other.weight.begin(), other.weight.end());
  }
};

// Σ weight · ‖predicted[i] − gt[j]‖² over the pairs; `predicted` (n, 3) carries autograd.
torch::Tensor pairedSquaredSum(const torch::Tensor& predicted, const torch::Tensor& gt, const ChamferPairs& pairs) {
  if (pairs.predicted.empty()) return torch::zeros({}, predicted.options());
  const auto long_options = torch::TensorOptions().dtype(torch::kLong);
  const auto p = predicted.index_select(0, torch::tensor(pairs.predicted, long_options));
  const auto g = gt.index_select(0, torch::tensor(pairs.gt, long_options));
  const auto w = torch::tensor(pairs.weight, torch::kDouble).to(predicted.scalar_type());
  return ((p - g).pow(2).sum(-1) * w).sum();
}

}  // namespace

int GroundTruthBatch::planeCount(int b) const {
  return static_cast<int>(mask[b].sum().item<int64_t>());
}

const std::vector<std::string>& LossConfig::termNames() {
  static const std::vector<std::string> names{"classification", "normal", "offset", "plane_chamfer",
                                              "overall_chamfer", "repulsion", "ranking"};
  return names;
}

namespace {
bool* switchOf(LossConfig& c, const std::string& name) {
  if (name == "classification") return &c.classification;
  if (name == "normal") return &c.normal;
  if (name == "offset") return &c.offset;
  if (name == "plane_chamfer") return &c.plane_chamfer;
  if (name == "overall_chamfer") return &c.overall_chamfer;
  if (name == "repulsion") return &c.repulsion;
  if (name == "ranking") return &c.ranking;
  return nullptr;
}
}  // namespace

void LossConfig::disable(const std::string& name) {
  bool* flag = switchOf(*this, name);
  if (!flag) {
    std::string known;
    for (const auto& n : termNames()) known += (known.empty() ? "" : ", ") + n;
    throw InvalidInputError("unknown loss term '" + name + "'; known terms: " + known);
  }
  *flag = false;
}

bool LossConfig::enabled(const std::string& name) const {
  bool* flag = switchOf(const_cast<LossConfig&>(*this), name);
  return flag && *flag;
}

torch::Tensor chamferSquared(const torch::Tensor& a, const torch::Tensor& b) {
  if (a.dim() != 2 || b.dim() != 2 || a.size(1) != 3 || b.size(1) != 3 || a.size(0) == 0 || b.size(0) == 0)
    throw InvalidInputError("chamferSquared: needs two non-empty (n, 3) point sets");
  const auto a_rows = a.detach().to(torch::kFloat).contiguous();
  const auto b_rows = b.detach().to(torch::kFloat).contiguous();
  auto nearest_in_b = torch::empty({a.size(0)}, torch::kLong);
  auto nearest_in_a = torch::empty({b.size(0)}, torch::kLong);
  detail::mutualNearest(a_rows.data_ptr<float>(), a.size(0), b_rows.data_ptr<float>(), b.size(0),
                        nearest_in_b.data_ptr<int64_t>(), nearest_in_a.data_ptr<int64_t>());
  // The gathered distances have the same value and (sub)gradient as the min, without keeping
  // the (n, m) matrix in the autograd graph.
  const auto a_to_b = (a - b.index_select(0, nearest_in_b)).pow(2).sum(-1).mean();
  const auto b_to_a = (b - a.index_select(0, nearest_in_a)).pow(2).sum(-1).mean();
  return a_to_b + b_to_a;
}

torch::Tensor repulsionLoss(const torch::Tensor& points, int k, double h, double radius) {
  if (points.dim() != 3 || points.size(2) != 3 || points.size(1) <= k || k <= 0)
    throw InvalidInputError("repulsionLoss: needs (T, P, 3) points with P > k > 0");
  // Neighbours found without autograd, then gathered: same value and gradient as a
  // differentiable top-k, without a (T, P, P) matrix in the graph.
  const int64_t T = points.size(0), P = points.size(1);
  const auto index = neighbourIndices(points, k).view({T, P * k, 1}).expand({T, P * k, 3});
  const auto neighbours = points.gather(1, index).view({T, P, k, 3});
  const auto d2 = (neighbours - points.unsqueeze(2)).pow(2).sum(-1).clamp_min(1e-12);
  const auto d = d2.sqrt();
  const auto value = radius - d * torch::exp(-d2 / (h * h));
  return value.mean({1, 2});
}

torch::Tensor normalLoss(const torch::Tensor& predicted, const torch::Tensor& truth, double cosine_weight) {
  const auto cosine = (predicted * truth).sum(-1);
  return (predicted - truth).pow(2).sum(-1) + cosine_weight * (1.0 - cosine);
}

torch::Tensor rankingTargets(const torch::Tensor& candidate_normals, const torch::Tensor& candidate_offsets,
                             const GroundTruthBatch& truth, const LossConfig& config) {
  torch::NoGradGuard no_grad;
  const int64_t B = candidate_normals.size(0);
  const int64_t Q = candidate_normals.size(1);
  auto targets = torch::zeros({B, Q}, candidate_normals.options().dtype(torch::kFloat));
  const double min_cosine = std::cos(degreesToRadians(config.ranking_angle_deg));
  for (int64_t b = 0; b < B; ++b) {
    const int planes = truth.planeCount(static_cast<int>(b));
    if (planes == 0) continue;
    const auto n = candidate_normals[b].to(torch::kFloat);
    const auto gt_n = truth.normals[b].slice(0, 0, planes).to(torch::kFloat);
    const auto cosine = torch::matmul(n, gt_n.transpose(0, 1));  // (Q, G)
    const auto dr = (candidate_offsets[b].to(torch::kFloat).unsqueeze(1) -
                     truth.offsets[b].slice(0, 0, planes).to(torch::kFloat).unsqueeze(0)).abs();
    const auto near = (cosine > min_cosine).logical_and(dr < config.ranking_offset);
    targets[b] = near.any(1).to(torch::kFloat);
  }
  return targets;
}

LossResult computeLosses(const NetworkOutput& output, const GroundTruthBatch& truth, const LossConfig& config) {
  validate(output, truth);
  LossResult result;
  const auto matching_started = std::chrono::steady_clock::now();
  result.matching = matchPredictions(output, truth, config);
  result.matching_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - matching_started).count();
  const int64_t B = truth.batchSize();
  const int64_t M = output.normals.size(1);
  const int64_t P = output.points.size(2);

  // Matched pairs of the whole batch, flattened.
  std::vector<int64_t> pred_flat, gt_flat;  // indices into (B·M) and (B·Pmax)
  const int64_t Pmax = truth.normals.size(1);
  int64_t gt_planes = 0;
  for (int64_t b = 0; b < B; ++b) {
    const auto& columns = result.matching[b];
    gt_planes += static_cast<int64_t>(columns.size());
    for (std::size_t g = 0; g < columns.size(); ++g) {
      if (columns[g] < 0) continue;
      pred_flat.push_back(b * M + columns[g]);
      gt_flat.push_back(b * Pmax + static_cast<int64_t>(g));
    }
  }
  const double plane_norm = 1.0 / static_cast<double>(std::max<int64_t>(gt_planes, 1));
  const double batch_norm = 1.0 / static_cast<double>(B);
  const auto long_options = torch::TensorOptions().dtype(torch::kLong);
  const auto pred_index = torch::tensor(pred_flat, long_options);
  const auto gt_index = torch::tensor(gt_flat, long_options);
  const bool any_match = !pred_flat.empty();

  auto total = torch::zeros({}, output.normals.options());
  auto add = [&](const std::string& name, const torch::Tensor& value) {
    total = total + value;
    result.terms[name] = value.detach().item<double>();
  };

  // The plane parameters of the matched pairs, predicted and GT, for the terms that compare them.
  torch::Tensor n, gt_n, r, gt_r;
  if (any_match) {
    n = output.normals.reshape({B * M, 3}).index_select(0, pred_index);
    gt_n = truth.normals.reshape({B * Pmax, 3}).index_select(0, gt_index);
    r = output.offsets.reshape({B * M}).index_select(0, pred_index);
    gt_r = truth.offsets.reshape({B * Pmax}).index_select(0, gt_index);
  }

  if (config.classification) {
    auto target = torch::zeros({B * M}, output.logits.options());
    if (any_match && config.quality_classification) {
      const double min_cosine = std::cos(degreesToRadians(config.quality_angle_deg));
      const auto good = ((n.detach() * gt_n).sum(-1) > min_cosine)
                            .logical_and((r.detach() - gt_r).abs() < config.quality_offset);
      target.index_put_({pred_index}, good.to(target.dtype()));
    } else if (any_match) {
      target.index_fill_(0, pred_index, 1.0);
    }
    const auto weight = target + config.empty_weight * (1.0 - target);
    const auto ce = torch::binary_cross_entropy_with_logits(output.logits.reshape({B * M}), target, weight,
                                                            {}, at::Reduction::Sum);
    add("classification", config.classification_weight * plane_norm * ce);
  }
  if (any_match && config.normal)
    add("normal", config.normal_weight * plane_norm * normalLoss(n, gt_n, config.cosine_weight).sum());
  if (any_match && config.offset) add("offset", config.offset_weight * plane_norm * (r - gt_r).abs().sum());
  if (any_match && (config.plane_chamfer || config.overall_chamfer)) {
    // Nearest neighbours per sample without autograd, samples in parallel; then one gather per
    // term over the whole batch (same value and gradient as a chamfer per matched pair).
    const auto predicted_rows = output.points.detach().to(torch::kFloat).contiguous();  // (B, M, P, 3)
    const auto gt_rows = truth.points.detach().to(torch::kFloat).contiguous();          // (B, N, 3)
    const auto labels = truth.labels.to(torch::kLong).contiguous();
    const int64_t N = gt_rows.size(1);
    std::vector<ChamferPairs> plane_pairs(static_cast<std::size_t>(B)), overall_pairs(static_cast<std::size_t>(B));
    at::parallel_for(0, B, 1, [&](int64_t begin, int64_t end) {
      for (int64_t b = begin; b < end; ++b) {
        const auto& columns = result.matching[b];
        const float* gt = gt_rows.data_ptr<float>() + b * N * 3;
        const int64_t* label = labels.data_ptr<int64_t>() + b * N;
        const float* predicted = predicted_rows.data_ptr<float>() + b * M * P * 3;
        const int64_t gt_base = b * N, predicted_base = b * M * P;
        if (config.plane_chamfer) {
          std::vector<std::vector<int64_t>> members(columns.size());  // GT points of each plane
          for (int64_t q = 0; q < N; ++q)
            if (label[q] >= 0 && label[q] < static_cast<int64_t>(columns.size())) members[label[q]].push_back(q);
          std::vector<float> group;
          for (std::size_t g = 0; g < columns.size(); ++g) {
            if (columns[g] < 0 || members[g].empty()) continue;  // no GT points: no chamfer term
            const int64_t n = static_cast<int64_t>(members[g].size());
            group.resize(static_cast<std::size_t>(n * 3));
            for (int64_t i = 0; i < n; ++i) std::copy_n(gt + members[g][i] * 3, 3, group.data() + i * 3);
            std::vector<int64_t> nearest_in_group(static_cast<std::size_t>(P)), nearest_in_plane(static_cast<std::size_t>(n));
            detail::mutualNearest(predicted + columns[g] * P * 3, P, group.data(), n, nearest_in_group.data(),
                                  nearest_in_plane.data());
            const int64_t plane_base = predicted_base + columns[g] * P;
            for (int64_t p = 0; p < P; ++p)
              plane_pairs[b].add(plane_base + p, gt_base + members[g][nearest_in_group[p]], 1.0 / P);
            for (int64_t i = 0; i < n; ++i)
              plane_pairs[b].add(plane_base + nearest_in_plane[i], gt_base + members[g][i], 1.0 / n);
          }
        }
        if (config.overall_chamfer) {
          std::vector<int64_t> matched;
          for (int column : columns)
            if (column >= 0) matched.push_back(column);
          if (matched.empty()) continue;
          const int64_t n = static_cast<int64_t>(matched.size()) * P;
          std::vector<float> all(static_cast<std::size_t>(n * 3));
          for (std::size_t i = 0; i < matched.size(); ++i)
            std::copy_n(predicted + matched[i] * P * 3, P * 3, all.data() + i * P * 3);
          std::vector<int64_t> nearest_gt(static_cast<std::size_t>(n)), nearest_predicted(static_cast<std::size_t>(N));
          detail::mutualNearest(all.data(), n, gt, N, nearest_gt.data(), nearest_predicted.data());
          auto flat = [&](int64_t i) { return predicted_base + matched[i / P] * P + i % P; };
          for (int64_t i = 0; i < n; ++i) overall_pairs[b].add(flat(i), gt_base + nearest_gt[i], 1.0 / n);
          for (int64_t q = 0; q < N; ++q) overall_pairs[b].add(flat(nearest_predicted[q]), gt_base + q, 1.0 / N);
        }
      }
    });
    const auto predicted_flat = output.points.reshape({B * M * P, 3});
    const auto gt_flat = truth.points.reshape({B * N, 3}).to(output.points.scalar_type());
    ChamferPairs plane_all, overall_all;
    for (int64_t b = 0; b < B; ++b) {
      plane_all.append(plane_pairs[b]);
      overall_all.append(overall_pairs[b]);
    }
    if (config.plane_chamfer)
      add("plane_chamfer", config.plane_chamfer_weight * batch_norm * pairedSquaredSum(predicted_flat, gt_flat, plane_all));
    if (config.overall_chamfer)
      add("overall_chamfer",
          config.overall_chamfer_weight * batch_norm * pairedSquaredSum(predicted_flat, gt_flat, overall_all));
  }
  if (any_match && config.repulsion && P > config.repulsion_k) {
    const auto x = output.points.reshape({B * M, P, 3}).index_select(0, pred_index);
    const auto rep = repulsionLoss(x, config.repulsion_k, config.repulsion_h, config.repulsion_radius);
    add("repulsion", config.repulsion_weight * plane_norm * rep.sum());
  }
  if (config.ranking && output.candidate_scores.defined() && output.candidate_scores.numel() > 0) {
    const auto target = rankingTargets(output.candidate_normals, output.candidate_offsets, truth, config);
    // Padded input slots are never kept; they take no part in the ranking loss.
    torch::Tensor weight;
    if (output.candidate_valid.defined()) weight = output.candidate_valid.to(output.candidate_scores.dtype());
    else weight = torch::ones_like(output.candidate_scores);
    const auto bce = torch::binary_cross_entropy_with_logits(output.candidate_scores,
                                                             target.to(output.candidate_scores.dtype()), weight,
                                                             {}, at::Reduction::Sum) /
                     weight.sum().clamp_min(1.0);
    add("ranking", config.ranking_weight * bce);
  }
  result.total = total;
  return result;
}

void PlaneMetrics::accumulate(const PlaneMetrics& other) {
  gt_planes += other.gt_planes;
  confident += other.confident;
  recalled += other.recalled;
  precise += other.precise;
  nc_sum += other.nc_sum;
  recall = gt_planes ? static_cast<double>(recalled) / gt_planes : 0.0;
  precision = confident ? static_cast<double>(precise) / confident : 0.0;
  nc_prim = gt_planes ? nc_sum / gt_planes : 0.0;
}

PlaneMetrics planeMetrics(const NetworkOutput& output, const GroundTruthBatch& truth, const Matching& matching,
                          const LossConfig& config, double confidence_threshold) {
  torch::NoGradGuard no_grad;
  PlaneMetrics total;
  const double min_cosine = std::cos(degreesToRadians(config.ranking_angle_deg));
  for (int b = 0; b < truth.batchSize(); ++b) {
    PlaneMetrics m;
    const int planes = truth.planeCount(b);
    const auto confident = torch::sigmoid(output.logits[b].to(torch::kFloat)) > confidence_threshold;  // (M)
    m.gt_planes = planes;
    m.confident = static_cast<int>(confident.sum().item<int64_t>());
    if (planes > 0) {
      const auto n = output.normals[b].to(torch::kFloat);
      const auto gt_n = truth.normals[b].slice(0, 0, planes).to(torch::kFloat);
      const auto cosine = torch::matmul(gt_n, n.transpose(0, 1));  // (G, M)
      const auto dr = (truth.offsets[b].slice(0, 0, planes).to(torch::kFloat).unsqueeze(1) -
                       output.offsets[b].to(torch::kFloat).unsqueeze(0)).abs();
      const auto near = (cosine > min_cosine).logical_and(dr < config.ranking_offset).logical_and(confident.unsqueeze(0));
      m.recalled = static_cast<int>(near.any(1).sum().item<int64_t>());
      m.precise = static_cast<int>(near.any(0).sum().item<int64_t>());
      const auto& columns = matching.at(b);
      for (int g = 0; g < planes && g < static_cast<int>(columns.size()); ++g)
        if (columns[g] >= 0) m.nc_sum += std::abs(cosine[g][columns[g]].item<double>());
    }
    total.accumulate(m);
  }
  return total;
}

}  // namespace paco::completion
