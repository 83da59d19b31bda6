#pragma once
// Internal (LibTorch): what a paco::CompletionModel holds. Used by the encoding and completion
// modules; users never need it.
//   auto& impl = *model->impl();
//   std::lock_guard<std::mutex> lock(impl.mutex); impl.encoder->forward(...);
#include <paco/encoding/completion_model.h>
#include <paco/encoding/model_file.h>
#include <paco/encoding/plane_proxy_network.h>
#include <torch/torch.h>
#include <memory>
#include <mutex>

namespace paco {

struct CompletionModel::Impl {
  ModelFile file;                     ///< config, format version and the "model" archive
  PlaneProxyNetwork encoder{nullptr};  ///< built and loaded by CompletionModel::load (eval mode)
  /// Stage 3's network, built from `file` on first use by the completion module (type-erased
  /// here because the encoding module does not know it).
  std::shared_ptr<torch::nn::Module> decoder;
  std::mutex mutex;  ///< guards `decoder` creation and forward passes
};

}  // namespace paco
