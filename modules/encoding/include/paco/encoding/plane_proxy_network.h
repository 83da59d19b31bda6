#pragma once
// Usage (LibTorch; users of the pipeline use paco::PlaneProxyEncoder instead):
//   paco::PlaneProxyNetwork encoder(paco::ModelConfig::preset("cpu"));
//   paco::PlaneProxyOutput out = encoder->forward(points, normals, labels);  // (B,N,3) (B,N,3) (B,N)
//   out.proxies;  // (B,K,C), zero where !out.mask
#include <paco/encoding/model_config.h>
#include <torch/torch.h>

namespace paco {

/// Plane proxies of a batch, in the normalised frame.
struct PlaneProxyOutput {
  torch::Tensor proxies;        ///< (B,K,C) float; padded slots are exactly zero
  torch::Tensor mask;           ///< (B,K) bool; true for a slot holding a real segment
  torch::Tensor slot_normals;   ///< (B,K,3) unit normal of each slot's segment (0 for padding)
  torch::Tensor slot_offsets;   ///< (B,K) r with n.x = r for each slot's plane (0 for padding)
  torch::Tensor slot_segments;  ///< (B,K) int64 input segment label of each slot (-1: padding)
  torch::Tensor centres;        ///< (B,G,3) FPS centres
  torch::Tensor centre_labels;  ///< (B,G) int64 segment label of each centre (-1: none)
  torch::Tensor point_proxies;  ///< (B,G,C) point proxy features after the encoder blocks
};

/// Stage 2 network: point proxies (FPS + kNN groups + edge convs + positional embedding +
/// optional transformer blocks) pooled through the point -> patch -> plane lookup table into K
/// plane proxies (sum of the point proxies on each plane + MLP of its normal), keeping the K
/// largest segments and masking the padding.
class PlaneProxyNetworkImpl : public torch::nn::Module {
 public:
  explicit PlaneProxyNetworkImpl(const ModelConfig& config);
  /// points, normals: (B,N,3) float; labels: (B,N) int64 segment labels (-1: none). `normals`
  /// holds each point's segment plane normal (any point of a segment can be used).
  PlaneProxyOutput forward(const torch::Tensor& points, const torch::Tensor& normals,
                           const torch::Tensor& labels);
  const ModelConfig& config() const { return config_; }

 private:
  struct Layers;
  ModelConfig config_;
  std::shared_ptr<Layers> layers_;
};
TORCH_MODULE(PlaneProxyNetwork);

/// A pre-LayerNorm transformer block: self-attention (+ optional cross-attention to a memory)
/// and an MLP. Shared by the encoder and the completion decoder.
class TransformerBlockImpl : public torch::nn::Module {
 public:
  /// graph_k > 0 adds DGCNN-style kNN graph features over positions (the first encoder block).
  TransformerBlockImpl(int width, int heads, double mlp_ratio, bool cross_attention,
                       int graph_k = 0);
  /// x: (B,L,C). key_mask (B,L) bool true = valid (undefined: all valid). memory (B,S,C) and
  /// memory_mask (B,S) for cross-attention. positions (B,L,3) for the graph features.
  torch::Tensor forward(const torch::Tensor& x, const torch::Tensor& key_mask = {},
                        const torch::Tensor& memory = {}, const torch::Tensor& memory_mask = {},
                        const torch::Tensor& positions = {});

 private:
  torch::Tensor attention(torch::nn::Linear& q, torch::nn::Linear& kv, torch::nn::Linear& out,
                          const torch::Tensor& x, const torch::Tensor& memory,
                          const torch::Tensor& mask);
  int heads_, graph_k_;
  torch::nn::LayerNorm norm1_{nullptr}, norm_cross_{nullptr}, norm_memory_{nullptr},
      norm2_{nullptr};
  torch::nn::Linear q_{nullptr}, kv_{nullptr}, proj_{nullptr};
  torch::nn::Linear cross_q_{nullptr}, cross_kv_{nullptr}, cross_proj_{nullptr};
  torch::nn::Linear graph_{nullptr}, merge_{nullptr};
  torch::nn::Linear fc1_{nullptr}, fc2_{nullptr};
};
TORCH_MODULE(TransformerBlock);

/// Number of trainable scalars of a module.
std::int64_t parameterCount(const torch::nn::Module& module);

/// Unit normal (sin t cos p, sin t sin p, cos t) from polar angles; theta, phi (...) -> (...,3).
torch::Tensor polarToNormal(const torch::Tensor& theta, const torch::Tensor& phi);

}  // namespace paco
