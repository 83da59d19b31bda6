#include <paco/common/error.h>
#include <paco/completion/network.h>

#include <cmath>

namespace paco {
namespace nn = torch::nn;

namespace {

// The "polar" distributor casts rays from an origin this far from the plane (normalised units,
// one bounding-box diagonal) and keeps |u.n| at least this large.
constexpr double kPolarOriginDistance = 1.0;
constexpr double kPolarMinCosine = 0.1;

torch::Tensor gatherRows(const torch::Tensor& x, const torch::Tensor& index) {
  const auto B = x.size(0), L = x.size(1);
  auto flat = (index + torch::arange(B, index.options()).mul(L).unsqueeze(1)).reshape({-1});
  auto rows = x.reshape({B * L, -1}).index_select(0, flat);
  auto shape = index.sizes().vec();
  for (int64_t d = 2; d < x.dim(); ++d) shape.push_back(x.size(d));
  return rows.view(shape);
}

nn::Sequential mlp(int in, int hidden, int out) {
  return nn::Sequential(nn::Linear(in, hidden), nn::GELU(), nn::Linear(hidden, out));
}

}  // namespace

torch::Tensor distributePoints(const std::string& mode, const torch::Tensor& raw,
                               const torch::Tensor& normals, const torch::Tensor& offsets) {
  auto n = normals.unsqueeze(-2);               // ...,1,3
  auto r = offsets.unsqueeze(-1).unsqueeze(-1);  // ...,1,1
  torch::Tensor points;
  if (mode == "projected") {
    points = raw;
  } else if (mode == "polar") {
    // The paper's r_ij = r / (u_ij . n) degenerates for r -> 0 (every point on the origin) and
    // blows up for u.n -> 0. Rays start instead from o = (r - h) n, at distance h from the plane
    // whatever r is, and |u.n| is clamped away from 0 (keeping its sign).
    auto u = polarToNormal(raw.select(-1, 0), raw.select(-1, 1));  // ...,P,3
    auto cosine = (u * n).sum(-1, true);
    auto sign = torch::where(cosine >= 0, torch::ones_like(cosine), -torch::ones_like(cosine));
    auto denominator = sign * cosine.abs().clamp_min(kPolarMinCosine);
    auto origin = (r - kPolarOriginDistance) * n;
    points = origin + u * (kPolarOriginDistance / denominator);
  } else {
    throw InvalidInputError("distributePoints: unknown distributor '" + mode +
                            "'; use 'projected' or 'polar'");
  }
  // Orthogonal projection: exactly on n.x = r (for "polar" it only corrects clamped rays).
  return points - ((points * n).sum(-1, true) - r) * n;
}

// ---------------------------------------------------------------- decoder

struct CompletionDecoderImpl::Layers {
  torch::Tensor null_token;
  nn::Linear increase{nullptr};
  nn::Sequential coarse{nullptr};
  nn::Sequential generated_query{nullptr};
  nn::Sequential input_query{nullptr};
  nn::Sequential plane_embedding{nullptr};
  nn::Sequential score{nullptr};
  std::vector<TransformerBlock> blocks;
  nn::LayerNorm norm{nullptr};
  nn::Sequential parameters{nullptr};
  nn::Sequential distributor{nullptr};
  nn::Sequential selector{nullptr};
};

CompletionDecoderImpl::CompletionDecoderImpl(const ModelConfig& config)
    : config_(config), layers_(std::make_shared<Layers>()) {
  config_.validate();
  auto& L = *layers_;
  const int C = config_.width, W = config_.global_width, Gq = config_.generated_queries;
  // A learned always-valid memory token: cross-attention and the global max never see an
  // all-padding input, even for a cloud without segments.
  L.null_token = register_parameter("null_token", torch::randn({1, 1, C}) * 0.02);
  L.increase = register_module("increase", nn::Linear(C, W));
  L.coarse = register_module("coarse", mlp(W, W, 3 * Gq));
  L.generated_query = register_module(
      "generated_query", nn::Sequential(nn::Linear(W + 4, W), nn::GELU(), nn::Linear(W, W),
                                        nn::GELU(), nn::Linear(W, C)));
  L.input_query = register_module("input_query", mlp(C, C, C));
  L.plane_embedding = register_module("plane_embedding", mlp(4, C, C));
  L.score = register_module(
      "score", nn::Sequential(nn::LayerNorm(nn::LayerNormOptions({C})), nn::Linear(C, C / 2),
                              nn::GELU(), nn::Linear(C / 2, 1)));
  for (int i = 0; i < config_.decoder_depth; ++i)
    L.blocks.push_back(register_module("block" + std::to_string(i),
                                       TransformerBlock(C, config_.heads, config_.mlp_ratio, true)));
  L.norm = register_module("norm", nn::LayerNorm(nn::LayerNormOptions({C})));
  L.parameters = register_module("parameters", mlp(C, C, 3));
  const int per_point = config_.distributor == "polar" ? 2 : 3;
  L.distributor = register_module(
      "distributor", mlp(C, config_.distributor_hidden, config_.points_per_plane * per_point));
  L.selector = register_module("selector", mlp(C, C / 2, 1));
}

NetworkOutput CompletionDecoderImpl::forward(const PlaneProxyOutput& in) {
  auto& L = *layers_;
  const int64_t C = config_.width, K = config_.plane_slots, Gq = config_.generated_queries,
                M = config_.kept_queries, P = config_.points_per_plane;
  if (in.proxies.dim() != 3 || in.proxies.size(1) != K || in.proxies.size(2) != C)
    throw InvalidInputError("CompletionDecoder: plane proxies must be (B," + std::to_string(K) +
                            "," + std::to_string(C) + "), got " + c10::str(in.proxies.sizes()));
  const int64_t B = in.proxies.size(0);
  auto mask = in.mask.to(torch::kBool);

  // Memory for cross-attention: the null token then the K plane proxies.
  auto memory = torch::cat({L.null_token.expand({B, 1, C}), in.proxies}, 1);
  auto memory_mask = torch::cat({torch::ones({B, 1}, torch::kBool), mask}, 1);

  // Generated candidates: a global feature (max over valid proxies) predicts coarse planes
  // (theta, phi, r) and one query per coarse plane.
  auto lifted = L.increase(memory).masked_fill(memory_mask.logical_not().unsqueeze(-1), -1e9);
  auto global = std::get<0>(lifted.max(1));                                    // B,W
  auto coarse = L.coarse->forward(global).view({B, Gq, 3});
  auto gen_theta = coarse.select(2, 0), gen_phi = coarse.select(2, 1),
       gen_offset = coarse.select(2, 2);
  auto gen_normals = polarToNormal(gen_theta, gen_phi);
  auto gen_queries = L.generated_query->forward(torch::cat(
      {global.unsqueeze(1).expand({B, Gq, global.size(1)}), gen_normals, gen_offset.unsqueeze(-1)},
      -1));

  // Input candidates: one per plane proxy, with the input segment's plane.
  auto in_normals = in.slot_normals.to(torch::kFloat);
  auto in_offsets = in.slot_offsets.to(torch::kFloat);
  torch::Tensor in_theta, in_phi;
  {
    torch::NoGradGuard no_grad;  // inputs: no gradient through acos at the poles
    in_theta = torch::acos(in_normals.select(2, 2).clamp(-1.0, 1.0));
    in_phi = torch::atan2(in_normals.select(2, 1), in_normals.select(2, 0));
  }
  auto in_queries = L.input_query->forward(in.proxies);

  auto candidate_queries = torch::cat({in_queries, gen_queries}, 1);         // B,Q,C
  auto candidate_normals = torch::cat({in_normals, gen_normals}, 1);         // B,Q,3
  auto candidate_offsets = torch::cat({in_offsets, gen_offset}, 1);          // B,Q
  auto candidate_theta = torch::cat({in_theta, gen_theta}, 1);
  auto candidate_phi = torch::cat({in_phi, gen_phi}, 1);
  auto candidate_valid = torch::cat({mask, torch::ones({B, Gq}, torch::kBool)}, 1);
  candidate_queries = candidate_queries +
                      L.plane_embedding->forward(torch::cat({candidate_normals,
                                                    candidate_offsets.unsqueeze(-1)}, -1));

  // Query ranking: a trained score; the M HIGHEST valid scores are kept.
  auto scores = L.score->forward(candidate_queries).squeeze(-1);                      // B,Q
  auto ranking = scores.detach().masked_fill(candidate_valid.logical_not(),
                                             -std::numeric_limits<float>::infinity());
  auto selected = std::get<1>(ranking.topk(M, 1, /*largest=*/true, /*sorted=*/true));
  auto x = gatherRows(candidate_queries, selected);                          // B,M,C

  for (auto& block : L.blocks) x = block->forward(x, torch::Tensor(), memory, memory_mask);
  x = L.norm(x);

  // Heads. Plane parameters are predicted as a residual on the candidate's coarse plane.
  auto delta = L.parameters->forward(x);                                              // B,M,3
  auto theta = gatherRows(candidate_theta, selected) + delta.select(2, 0);
  auto phi = gatherRows(candidate_phi, selected) + delta.select(2, 1);
  auto offsets = gatherRows(candidate_offsets, selected) + delta.select(2, 2);
  auto normals = polarToNormal(theta, phi);
  const int64_t per_point = config_.distributor == "polar" ? 2 : 3;
  auto raw = L.distributor->forward(x).view({B, M, P, per_point});

  NetworkOutput out;
  out.normals = normals;
  out.offsets = offsets;
  out.points = distributePoints(config_.distributor, raw, normals, offsets);
  out.logits = L.selector->forward(x).squeeze(-1);
  out.candidate_normals = candidate_normals;
  out.candidate_offsets = candidate_offsets;
  out.candidate_scores = scores;
  out.candidate_valid = candidate_valid;
  out.selected = selected;
  out.global_feature = global;
  return out;
}

// ---------------------------------------------------------------- whole network

PacoNetworkImpl::PacoNetworkImpl(const ModelConfig& config) : config_(config) {
  config_.validate();
  encoder_ = register_module("encoder", PlaneProxyNetwork(config_));
  decoder_ = register_module("decoder", CompletionDecoder(config_));
}

NetworkOutput PacoNetworkImpl::forward(const NetworkInput& input) {
  return decoder_->forward(encoder_->forward(input.points, input.normals, input.labels));
}

}  // namespace paco
