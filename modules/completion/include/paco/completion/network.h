#pragma once
// Usage (LibTorch; pipeline users use paco::ParametricCompleter instead):
//   paco::PacoNetwork net(paco::ModelConfig::preset("cpu"));
//   paco::NetworkOutput out = net->forward({points, normals, labels});   // (B,N,3) (B,N,3) (B,N)
//   auto confidence = torch::sigmoid(out.logits);                        // (B,M)
#include <paco/encoding/model_config.h>
#include <paco/encoding/plane_proxy_network.h>
#include <torch/torch.h>

namespace paco {

/// One batch of segmented input clouds in the normalised frame.
struct NetworkInput {
  torch::Tensor points;   ///< (B,N,3) float
  torch::Tensor normals;  ///< (B,N,3) float: each point's segment plane normal
  torch::Tensor labels;   ///< (B,N) int64 segment label, -1 for none
};

/// Everything the network predicts, in the normalised frame. Planes are n.x = r.
struct NetworkOutput {
  torch::Tensor normals;            ///< (B,M,3) unit normals of the kept queries' planes
  torch::Tensor offsets;            ///< (B,M) r with n.x = r
  torch::Tensor points;             ///< (B,M,P,3) exactly on their plane
  torch::Tensor logits;             ///< (B,M) plane-vs-empty logit; sigmoid = confidence
  torch::Tensor candidate_normals;  ///< (B,Q,3) coarse planes of all Q = K + G candidates
  torch::Tensor candidate_offsets;  ///< (B,Q)
  torch::Tensor candidate_scores;   ///< (B,Q) ranking logits of ALL candidates before top-M
  torch::Tensor candidate_valid;    ///< (B,Q) bool: false for padded input slots (never kept;
                                    ///< exclude them from the ranking loss)
  torch::Tensor selected;           ///< (B,M) int64 indices of the kept candidates (top scores)
  torch::Tensor global_feature;     ///< (B,W) max over the lifted proxies: what generates queries
};

/// Stage 3 on its own: plane proxies -> queries -> ranking -> decoder -> heads.
class CompletionDecoderImpl : public torch::nn::Module {
 public:
  explicit CompletionDecoderImpl(const ModelConfig& config);
  NetworkOutput forward(const PlaneProxyOutput& proxies);
  const ModelConfig& config() const { return config_; }

 private:
  struct Layers;
  ModelConfig config_;
  std::shared_ptr<Layers> layers_;
};
TORCH_MODULE(CompletionDecoder);

/// The whole network: PlaneProxyNetwork ("encoder") followed by CompletionDecoder ("decoder").
class PacoNetworkImpl : public torch::nn::Module {
 public:
  explicit PacoNetworkImpl(const ModelConfig& config);
  NetworkOutput forward(const NetworkInput& input);
  const ModelConfig& config() const { return config_; }
  PlaneProxyNetwork& encoder() { return encoder_; }
  CompletionDecoder& decoder() { return decoder_; }

 private:
  ModelConfig config_;
  PlaneProxyNetwork encoder_{nullptr};
  CompletionDecoder decoder_{nullptr};
};
TORCH_MODULE(PacoNetwork);

/// The point distributor on its own (used by the network; exposed for tests): places raw
/// per-point predictions exactly on the planes n.x = r. normals (...,3), offsets (...);
/// "projected": raw (...,P,3) points, orthogonally projected; "polar": raw (...,P,2) angles
/// (theta_ij, phi_ij) of rays from the origin shifted to distance 1 from the plane.
torch::Tensor distributePoints(const std::string& mode, const torch::Tensor& raw,
                               const torch::Tensor& normals, const torch::Tensor& offsets);

}  // namespace paco
