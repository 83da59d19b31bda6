#include <paco/completion/losses.h>

#include <paco/common/error.h>
#include <paco/completion/matching.h>

#include <flann/flann.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace paco::completion {

torch::Tensor pairwiseSquaredDistances(const torch::Tensor& a, const torch::Tensor& b) {
  const auto a2 = a.pow(2).sum(-1).unsqueeze(1);
  const auto b2 = b.pow(2).sum(-1).unsqueeze(0);
  return (a2 + b2 - 2.0 * torch::matmul(a, b.transpose(0, 1))).clamp_min(0.0);
}

namespace {

constexpr double kPi = 3.14159265358979323846;

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

// Per-plane GT point indices of one sample (planes 0..count-1).
std::vector<torch::Tensor> pointsOfPlanes(const torch::Tensor& labels, int count) {
  std::vector<torch::Tensor> result;
  result.reserve(count);
  for (int g = 0; g < count; ++g) result.push_back(torch::nonzero(labels == g).view({-1}));
  return result;
}

// Elements of a temporary distance block: keeps no-grad distance matrices near 64 MB.
constexpr int64_t kBlockElements = int64_t{1} << 24;
// Above this many pairs, nearest neighbours come from kd-trees instead of a distance matrix.
constexpr int64_t kBruteForceElements = int64_t{1} << 21;

// Nearest neighbour (squared L2) of every row of `queries` among the rows of `points`, with an
// exact FLANN kd-tree: O((n + m) log m) instead of the O(n·m) distance matrix.
torch::Tensor kdTreeNearest(const torch::Tensor& points, const torch::Tensor& queries) {
  const auto data = points.detach().to(torch::kFloat).contiguous();
  const auto query = queries.detach().to(torch::kFloat).contiguous();
  flann::Matrix<float> data_matrix(data.data_ptr<float>(), static_cast<std::size_t>(data.size(0)), 3);
  flann::Matrix<float> query_matrix(query.data_ptr<float>(), static_cast<std::size_t>(query.size(0)), 3);
  flann::Index<flann::L2_Simple<float>> index(data_matrix, flann::KDTreeSingleIndexParams(15));
  index.buildIndex();
  std::vector<int> nearest(static_cast<std::size_t>(query.size(0)));
  std::vector<float> distances(nearest.size());
  flann::Matrix<int> nearest_matrix(nearest.data(), nearest.size(), 1);
  flann::Matrix<float> distance_matrix(distances.data(), distances.size(), 1);
  index.knnSearch(query_matrix, nearest_matrix, distance_matrix, 1, flann::SearchParams(-1));
  return torch::tensor(std::vector<int64_t>(nearest.begin(), nearest.end()), torch::kLong);
}

// Nearest neighbour of every row of a in b and of every row of b in a (squared L2). Small sets:
// brute force in chunks of a's rows; large ones (paper sizes: 40 x 1280 points vs 8192): kd-trees.
std::pair<torch::Tensor, torch::Tensor> nearestNeighbours(const torch::Tensor& a, const torch::Tensor& b) {
  torch::NoGradGuard no_grad;
  const int64_t n = a.size(0), m = b.size(0);
  if (n * m > kBruteForceElements) return {kdTreeNearest(b, a), kdTreeNearest(a, b)};
  const int64_t chunk = std::max<int64_t>(1, kBlockElements / std::max<int64_t>(m, 1));
  auto nearest_in_b = torch::empty({n}, torch::kLong);
  auto best_for_b = torch::full({m}, std::numeric_limits<float>::infinity(), a.options());
  auto nearest_in_a = torch::zeros({m}, torch::kLong);
  for (int64_t start = 0; start < n; start += chunk) {
    const int64_t end = std::min(n, start + chunk);
    const auto d = pairwiseSquaredDistances(a.slice(0, start, end), b);
    nearest_in_b.slice(0, start, end).copy_(d.argmin(1));
    const auto column_min = d.min(0);
    const auto better = std::get<0>(column_min) < best_for_b;
    best_for_b = torch::where(better, std::get<0>(column_min), best_for_b);
    nearest_in_a = torch::where(better, std::get<1>(column_min) + start, nearest_in_a);
  }
  return {nearest_in_b, nearest_in_a};
}

// Indices (T, P, k) of the k nearest other points of each point inside its own set.
torch::Tensor neighbourIndices(const torch::Tensor& points, int k) {
  torch::NoGradGuard no_grad;
  const int64_t T = points.size(0), P = points.size(1);
  const int64_t chunk = std::max<int64_t>(1, kBlockElements / (P * P));
  auto result = torch::empty({T, P, k}, torch::kLong);
  const auto eye = torch::eye(P, points.options().dtype(torch::kBool)).unsqueeze(0);
  for (int64_t start = 0; start < T; start += chunk) {
    const int64_t end = std::min(T, start + chunk);
    const auto x = points.slice(0, start, end);
    const auto sq = (x.pow(2).sum(-1).unsqueeze(2) + x.pow(2).sum(-1).unsqueeze(1) -
                     2.0 * torch::matmul(x, x.transpose(1, 2))).masked_fill(eye, 1e10);
    result.slice(0, start, end).copy_(std::get<1>(torch::topk(sq, k, -1, /*largest=*/false)));
  }
  return result;
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
  const auto [nearest_in_b, nearest_in_a] = nearestNeighbours(a, b);
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
  const double min_cosine = std::cos(config.ranking_angle_deg * kPi / 180.0);
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
  result.matching = matchPredictions(output, truth, config);
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

  if (config.classification) {
    auto target = torch::zeros({B * M}, output.logits.options());
    if (any_match) target.index_fill_(0, pred_index, 1.0);
    const auto weight = target + config.empty_weight * (1.0 - target);
    const auto ce = torch::binary_cross_entropy_with_logits(output.logits.reshape({B * M}), target, weight,
                                                            {}, at::Reduction::Sum);
    add("classification", config.classification_weight * plane_norm * ce);
  }
  if (any_match && config.normal) {
    const auto n = output.normals.reshape({B * M, 3}).index_select(0, pred_index);
    const auto gt_n = truth.normals.reshape({B * Pmax, 3}).index_select(0, gt_index);
    add("normal", config.normal_weight * plane_norm * normalLoss(n, gt_n, config.cosine_weight).sum());
  }
  if (any_match && config.offset) {
    const auto r = output.offsets.reshape({B * M}).index_select(0, pred_index);
    const auto gt_r = truth.offsets.reshape({B * Pmax}).index_select(0, gt_index);
    add("offset", config.offset_weight * plane_norm * (r - gt_r).abs().sum());
  }
  if (any_match && (config.plane_chamfer || config.overall_chamfer)) {
    auto plane_sum = torch::zeros({}, output.points.options());
    auto overall_sum = torch::zeros({}, output.points.options());
    for (int64_t b = 0; b < B; ++b) {
      const auto& columns = result.matching[b];
      const auto groups = pointsOfPlanes(truth.labels[b], static_cast<int>(columns.size()));
      std::vector<int64_t> matched;
      for (std::size_t g = 0; g < columns.size(); ++g) {
        if (columns[g] < 0) continue;
        matched.push_back(columns[g]);
        if (config.plane_chamfer && groups[g].size(0) > 0)
          plane_sum = plane_sum + chamferSquared(output.points[b][columns[g]],
                                                 truth.points[b].index_select(0, groups[g]));
      }
      if (config.overall_chamfer && !matched.empty()) {
        const auto x = output.points[b].index_select(0, torch::tensor(matched, long_options)).reshape({-1, 3});
        overall_sum = overall_sum + chamferSquared(x, truth.points[b]);
      }
    }
    if (config.plane_chamfer) add("plane_chamfer", config.plane_chamfer_weight * batch_norm * plane_sum);
    if (config.overall_chamfer) add("overall_chamfer", config.overall_chamfer_weight * batch_norm * overall_sum);
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
  const double min_cosine = std::cos(config.ranking_angle_deg * kPi / 180.0);
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
