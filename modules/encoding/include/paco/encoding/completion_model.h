#pragma once
// Usage:
//   auto model = paco::CompletionModel::load(paco::CompletionModel::findShippedModel());
//   encoder.setModel(model); completer.setModel(model);   // one model file serves both stages
//   std::cout << model->config().name << " " << model->parameterCount();
#include <paco/encoding/model_config.h>
#include <cstdint>
#include <memory>
#include <string>

namespace paco {

/// A trained PaCo model file, shared by PlaneProxyEncoder (stage 2) and ParametricCompleter
/// (stage 3). No LibTorch in this header. Loading is thread-safe; running the stages with one
/// model from several threads at once is not supported.
class CompletionModel {
 public:
  using Ptr = std::shared_ptr<CompletionModel>;
  using ConstPtr = std::shared_ptr<const CompletionModel>;

  /// Reads a model file written by paco_train (or saveCheckpoint). Throws paco::ModelError for a
  /// missing, corrupt, truncated or other-format file. Warns once on stderr if the BLAS is slow.
  static ConstPtr load(const std::string& path);
  /// The model shipped with paco: $PACO_MODEL if set, else `models/paco_cpu.pt` (then any
  /// `*.pt`) in the source tree, then `<prefix>/share/paco/models`. Empty string when none.
  static std::string findShippedModel();
  /// Threads LibTorch uses for all models (0: one per hardware thread, the default applied at
  /// the first load unless this was called before).
  static void setThreads(int threads);

  const ModelConfig& config() const;
  const std::string& path() const;
  /// Number of trainable scalars in the whole network.
  std::int64_t parameterCount() const;

  struct Impl;  ///< LibTorch state (paco/encoding/completion_model_impl.h, internal)
  const std::shared_ptr<Impl>& impl() const { return impl_; }
  explicit CompletionModel(std::shared_ptr<Impl> impl);

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace paco
