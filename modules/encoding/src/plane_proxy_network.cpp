#include <paco/common/error.h>
#include <paco/common/plane.h>
#include <paco/encoding/plane_proxy_network.h>
#include <paco/encoding/point_grouping.h>

#include <cmath>

namespace paco {
namespace nn = torch::nn;

// ---------------------------------------------------------------- helpers

std::int64_t parameterCount(const torch::nn::Module& module) {
  std::int64_t count = 0;
  for (const auto& p : module.parameters())
    if (p.requires_grad()) count += p.numel();
  return count;
}

torch::Tensor polarToNormal(const torch::Tensor& theta, const torch::Tensor& phi) {
  const auto s = torch::sin(theta);
  return torch::stack({s * torch::cos(phi), s * torch::sin(phi), torch::cos(theta)}, -1);
}

namespace {

// Rows of `x` (B,L,C) picked per batch by `index` (B,...) -> (B,...,C).
torch::Tensor gatherRows(const torch::Tensor& x, const torch::Tensor& index) {
  const auto B = x.size(0), L = x.size(1);
  auto offsets = torch::arange(B, index.options()).mul(L);
  std::vector<int64_t> view(index.dim(), 1);
  view[0] = B;
  auto flat = (index + offsets.view(view)).reshape({-1});
  auto rows = x.reshape({B * L, -1}).index_select(0, flat);
  auto shape = index.sizes().vec();
  shape.push_back(x.size(-1));
  return rows.view(shape);
}

}  // namespace

// ---------------------------------------------------------------- transformer block

TransformerBlockImpl::TransformerBlockImpl(int width, int heads, double mlp_ratio,
                                           bool cross_attention, int graph_k)
    : heads_(heads), graph_k_(graph_k) {
  const int hidden = std::max(1, static_cast<int>(std::lround(mlp_ratio * width)));
  norm1_ = register_module("norm1", nn::LayerNorm(nn::LayerNormOptions({width})));
  q_ = register_module("q", nn::Linear(width, width));
  kv_ = register_module("kv", nn::Linear(width, 2 * width));
  proj_ = register_module("proj", nn::Linear(width, width));
  if (graph_k_ > 0) {
    // PoinTr-style: kNN graph features over the centres next to attention, merged by a linear.
    graph_ = register_module("graph", nn::Linear(2 * width, width));
    merge_ = register_module("merge", nn::Linear(2 * width, width));
  }
  if (cross_attention) {
    norm_cross_ = register_module("norm_cross", nn::LayerNorm(nn::LayerNormOptions({width})));
    norm_memory_ = register_module("norm_memory", nn::LayerNorm(nn::LayerNormOptions({width})));
    cross_q_ = register_module("cross_q", nn::Linear(width, width));
    cross_kv_ = register_module("cross_kv", nn::Linear(width, 2 * width));
    cross_proj_ = register_module("cross_proj", nn::Linear(width, width));
  }
  norm2_ = register_module("norm2", nn::LayerNorm(nn::LayerNormOptions({width})));
  fc1_ = register_module("fc1", nn::Linear(width, hidden));
  fc2_ = register_module("fc2", nn::Linear(hidden, width));
}

torch::Tensor TransformerBlockImpl::attention(nn::Linear& q, nn::Linear& kv, nn::Linear& out,
                                              const torch::Tensor& x, const torch::Tensor& memory,
                                              const torch::Tensor& mask) {
  const auto B = x.size(0), L = x.size(1), S = memory.size(1), C = x.size(2);
  const int64_t d = C / heads_;
  auto queries = q(x).view({B, L, heads_, d}).transpose(1, 2);            // B,h,L,d
  auto keys_values = kv(memory).view({B, S, 2, heads_, d}).permute({2, 0, 3, 1, 4});
  auto keys = keys_values[0], values = keys_values[1];                    // B,h,S,d
  auto scores = torch::matmul(queries, keys.transpose(-2, -1)) / std::sqrt(double(d));
  if (mask.defined()) scores = scores.masked_fill(mask.logical_not().view({B, 1, 1, S}), -1e9);
  auto attended = torch::matmul(torch::softmax(scores, -1), values);      // B,h,L,d
  return out(attended.transpose(1, 2).reshape({B, L, C}));
}

torch::Tensor TransformerBlockImpl::forward(const torch::Tensor& x, const torch::Tensor& key_mask,
                                            const torch::Tensor& memory,
                                            const torch::Tensor& memory_mask,
                                            const torch::Tensor& positions) {
  auto h = norm1_(x);
  auto update = attention(q_, kv_, proj_, h, h, key_mask);
  if (graph_k_ > 0) {
    if (!positions.defined())
      throw InvalidInputError("TransformerBlock: graph attention needs token positions");
    const int64_t k = std::min<int64_t>(graph_k_, positions.size(1));
    auto neighbours = std::get<1>(torch::cdist(positions, positions).topk(k, -1, /*largest=*/false));
    auto hj = gatherRows(h, neighbours);                                   // B,L,k,C
    auto hi = h.unsqueeze(2).expand_as(hj);
    auto edges = torch::leaky_relu(graph_(torch::cat({hj - hi, hi}, -1)), 0.2);
    update = merge_(torch::cat({update, std::get<0>(edges.max(2))}, -1));
  }
  auto y = x + update;
  if (cross_q_) {
    if (!memory.defined()) throw InvalidInputError("TransformerBlock: cross-attention needs memory");
    y = y + attention(cross_q_, cross_kv_, cross_proj_, norm_cross_(y), norm_memory_(memory),
                      memory_mask);
  }
  return y + fc2_(torch::gelu(fc1_(norm2_(y))));
}

// ---------------------------------------------------------------- plane proxy network

struct PlaneProxyNetworkImpl::Layers {
  nn::Conv2d input_embedding{nullptr};
  std::vector<nn::Conv2d> edge_convs;
  std::vector<nn::GroupNorm> edge_norms;
  nn::Linear projection{nullptr};
  nn::Sequential position{nullptr};
  std::vector<TransformerBlock> blocks;
  nn::LayerNorm encoder_norm{nullptr};
  nn::Sequential normal_embedding{nullptr};
  nn::Sequential proxy_mlp{nullptr};
};

PlaneProxyNetworkImpl::PlaneProxyNetworkImpl(const ModelConfig& config)
    : config_(config), layers_(std::make_shared<Layers>()) {
  config_.validate();
  auto& L = *layers_;
  const int C = config_.width;
  L.input_embedding = register_module(
      "input_embedding",
      nn::Conv2d(nn::Conv2dOptions(3, config_.input_embedding, 1).bias(false)));
  int in = config_.input_embedding, concatenated = 0;
  for (std::size_t i = 0; i < config_.edge_conv_widths.size(); ++i) {
    const int out = config_.edge_conv_widths[i];
    L.edge_convs.push_back(register_module("edge_conv" + std::to_string(i),
                                           nn::Conv2d(nn::Conv2dOptions(2 * in, out, 1).bias(false))));
    L.edge_norms.push_back(register_module(
        "edge_norm" + std::to_string(i), nn::GroupNorm(config_.group_norm_groups, out)));
    concatenated += out;
    in = out;
  }
  L.projection = register_module("projection", nn::Linear(concatenated, C));
  L.position = register_module(
      "position", nn::Sequential(nn::Linear(3, config_.position_hidden), nn::GELU(),
                                 nn::Linear(config_.position_hidden, C)));
  for (int i = 0; i < config_.encoder_depth; ++i)
    L.blocks.push_back(register_module(
        "block" + std::to_string(i),
        TransformerBlock(C, config_.heads, config_.mlp_ratio, false,
                         i == 0 ? config_.encoder_graph_k : 0)));
  L.encoder_norm = register_module("encoder_norm", nn::LayerNorm(nn::LayerNormOptions({C})));
  L.normal_embedding = register_module(
      "normal_embedding", nn::Sequential(nn::Linear(3, config_.normal_hidden), nn::GELU(),
                                         nn::Linear(config_.normal_hidden, C)));
  L.proxy_mlp = register_module(
      "proxy_mlp", nn::Sequential(nn::LayerNorm(nn::LayerNormOptions({C})), nn::Linear(C, C),
                                  nn::GELU(), nn::Linear(C, C)));
}

PlaneProxyOutput PlaneProxyNetworkImpl::forward(const torch::Tensor& points_in,
                                                const torch::Tensor& normals_in,
                                                const torch::Tensor& labels_in) {
  if (points_in.dim() != 3 || points_in.size(2) != 3 || points_in.size(1) < 1)
    throw InvalidInputError("PlaneProxyNetwork: points must be (B,N,3) with N >= 1, got " +
                            c10::str(points_in.sizes()));
  const int64_t B = points_in.size(0), N = points_in.size(1);
  if (normals_in.sizes() != points_in.sizes())
    throw InvalidInputError("PlaneProxyNetwork: normals must be (B,N,3) like the points, got " +
                            c10::str(normals_in.sizes()));
  if (labels_in.dim() != 2 || labels_in.size(0) != B || labels_in.size(1) != N)
    throw InvalidInputError("PlaneProxyNetwork: labels must be (B,N), got " +
                            c10::str(labels_in.sizes()));
  auto& L = *layers_;
  const int64_t G = config_.num_centres, k = config_.knn_k, K = config_.plane_slots;

  // --- non-differentiable bookkeeping in plain C++: FPS, kNN groups, lookup table, slot planes
  auto points = points_in.detach().to(torch::kFloat).contiguous();
  auto normals = normals_in.detach().to(torch::kFloat).contiguous();
  auto labels = labels_in.detach().to(torch::kLong).contiguous();
  auto centre_index = torch::empty({B, G}, torch::kLong);
  auto group_index = torch::empty({B, G, k}, torch::kLong);
  auto pooling = torch::zeros({B, K, G});
  auto slot_normals = torch::zeros({B, K, 3});
  auto slot_offsets = torch::zeros({B, K});
  auto slot_segments = torch::full({B, K}, -1, torch::kLong);
  auto centre_labels = torch::empty({B, G}, torch::kLong);
  auto mask = torch::zeros({B, K}, torch::kBool);
  for (int64_t b = 0; b < B; ++b) {
    const float* xyz = points[b].data_ptr<float>();
    const float* nrm = normals[b].data_ptr<float>();
    const int64_t* lab = labels[b].data_ptr<int64_t>();
    const auto centres = farthestPointSampling(xyz, N, G, 0);
    const auto groups = knnGroups(xyz, N, centres, k);
    const auto table = buildLookupTable(xyz, N, lab, centres, static_cast<int>(K));
    std::copy(centres.begin(), centres.end(), centre_index[b].data_ptr<int64_t>());
    std::copy(groups.begin(), groups.end(), group_index[b].data_ptr<int64_t>());
    std::copy(table.pooling.begin(), table.pooling.end(), pooling[b].data_ptr<float>());
    std::copy(table.centre_labels.begin(), table.centre_labels.end(),
              centre_labels[b].data_ptr<int64_t>());
    for (std::size_t s = 0; s < table.slot_segments.size(); ++s) {
      const int segment = table.slot_segments[s];
      Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
      std::vector<Eigen::Vector3d> members;
      for (int64_t p = 0; p < N; ++p) {
        if (lab[p] != segment) continue;
        normal_sum += Eigen::Vector3d(nrm[3 * p], nrm[3 * p + 1], nrm[3 * p + 2]);
        members.emplace_back(xyz[3 * p], xyz[3 * p + 1], xyz[3 * p + 2]);
      }
      Eigen::Vector3d normal = normal_sum / double(members.size());
      // The normals given are the segment plane's; fall back to a fit when they are missing.
      if (!normal.allFinite() || normal.norm() < 1e-6) {
        normal = Eigen::Vector3d::UnitZ();
        if (members.size() >= 3) {
          try {
            normal = Plane::fit(members).normal;
          } catch (const Error&) {
          }
        }
      }
      normal.normalize();
      double offset = 0.0;
      for (const auto& x : members) offset += normal.dot(x);
      offset /= double(members.size());
      for (int a = 0; a < 3; ++a) slot_normals[b][s][a] = float(normal[a]);
      slot_offsets[b][s] = float(offset);
      slot_segments[b][s] = segment;
      mask[b][s] = true;
    }
  }

  // --- point proxies: edge convs over each centre's kNN group (DGCNN-like, star graph about
  // the centre, which is the first point of its group)
  auto centres = gatherRows(points, centre_index);                           // B,G,3
  auto grouped = gatherRows(points, group_index) - centres.unsqueeze(2);     // B,G,k,3
  auto f = L.input_embedding(grouped.permute({0, 3, 1, 2}));                 // B,e,G,k
  std::vector<torch::Tensor> pooled_layers;
  for (std::size_t i = 0; i < L.edge_convs.size(); ++i) {
    auto centre_feature = f.narrow(3, 0, 1).expand_as(f);
    f = torch::leaky_relu(L.edge_norms[i](L.edge_convs[i](torch::cat({f - centre_feature,
                                                                       centre_feature}, 1))),
                          0.2);
    pooled_layers.push_back(std::get<0>(f.max(3)));                         // B,c,G
  }
  auto x = L.projection(torch::cat(pooled_layers, 1).transpose(1, 2));       // B,G,C
  x = x + L.position->forward(centres);
  for (auto& block : L.blocks) x = block->forward(x, torch::Tensor(), torch::Tensor(), torch::Tensor(), centres);
  x = L.encoder_norm(x);

  // --- plane proxies: v = sum of the point proxies on the plane + Phi(normal), then an MLP
  auto maskf = mask.to(torch::kFloat).unsqueeze(-1);
  auto v = torch::bmm(pooling, x) + L.normal_embedding->forward(slot_normals);
  auto proxies = L.proxy_mlp->forward(v) * maskf;  // padded slots exactly zero

  PlaneProxyOutput out;
  out.proxies = proxies;
  out.mask = mask;
  out.slot_normals = slot_normals;
  out.slot_offsets = slot_offsets;
  out.slot_segments = slot_segments;
  out.centres = centres;
  out.centre_labels = centre_labels;
  out.point_proxies = x;
  return out;
}

}  // namespace paco
