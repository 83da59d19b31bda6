#pragma once
// Usage (LibTorch; low level, shared by the encoder, the completer and the trainer):
//   paco::ModelFile file = paco::readModelFile("model.pt");   // throws paco::ModelError
//   file.config; file.model->read("encoder", encoder_archive);
//   paco::writeModelFile("model.pt", config, model_archive, nullptr);
#include <paco/encoding/model_config.h>
#include <torch/torch.h>
#include <memory>
#include <string>

namespace paco {

/// Format of the model files this build writes and reads. A file stores: "format_version"
/// (int), "config" (ModelConfig::toJson()), "model" (network weights: nested "encoder" and
/// "decoder" archives) and optionally "training_state" (opaque to the network code).
constexpr int kModelFormatVersion = 1;

/// The parts of a model file, checked for format and config validity.
struct ModelFile {
  std::string path;
  int format_version = 0;
  ModelConfig config;
  std::int64_t parameter_count = 0;                                 ///< trainable scalars
  std::shared_ptr<torch::serialize::InputArchive> model;           ///< the "model" archive
  std::shared_ptr<torch::serialize::InputArchive> training_state;  ///< null when absent
};

/// Reads and checks a model file. Throws paco::ModelError for a missing, corrupt or truncated
/// file, another format version, or an invalid config, with what to do next.
ModelFile readModelFile(const std::string& path);

/// Writes a model file atomically (a temporary file renamed into place); IoError on failure.
void writeModelFile(const std::string& path, const ModelConfig& config,
                    torch::serialize::OutputArchive& model, std::int64_t parameter_count,
                    torch::serialize::OutputArchive* training_state = nullptr);

/// Loads `module`'s parameters and buffers from `archive`; converts LibTorch's errors (missing
/// or mis-shaped tensors) to paco::ModelError mentioning `path` and `what` (e.g. "encoder").
void loadModuleWeights(torch::nn::Module& module, torch::serialize::InputArchive& archive,
                       const std::string& path, const std::string& what);

}  // namespace paco
