#pragma once
// Usage (training code):
//   paco::saveCheckpoint("model.pt", net, &training_state);     // training_state: OutputArchive
//   paco::LoadedCheckpoint ckpt = paco::loadCheckpoint("model.pt");   // throws paco::ModelError
//   ckpt.network->eval(); if (ckpt.training_state) optimizer.load(*ckpt.training_state);
#include <paco/completion/network.h>
#include <paco/encoding/model_config.h>
#include <paco/encoding/model_file.h>
#include <torch/torch.h>
#include <memory>
#include <optional>
#include <string>

namespace paco {

/// Format of the checkpoint files this build writes and reads.
constexpr int kCheckpointFormatVersion = kModelFormatVersion;

/// A checkpoint read back from disk.
struct LoadedCheckpoint {
  ModelConfig config;
  int format_version = 0;
  PacoNetwork network{nullptr};  ///< built from `config`, weights loaded, in eval() mode
  /// The opaque training state saved with it (optimizer, epoch, step ...), if any.
  std::shared_ptr<torch::serialize::InputArchive> training_state;
};

/// Writes network weights + its ModelConfig + the format version (+ the training state, when
/// given) to `path` atomically (temporary file renamed into place). Throws paco::IoError when
/// the file cannot be written.
void saveCheckpoint(const std::string& path, PacoNetwork& network,
                    torch::serialize::OutputArchive* training_state = nullptr);

/// Reads a checkpoint. When `expected` is given, its config must match the file's (else
/// ModelError naming the first differing field). Missing, corrupt, truncated, other-format or
/// inconsistent files throw paco::ModelError saying what is wrong and what to do.
LoadedCheckpoint loadCheckpoint(const std::string& path,
                                const std::optional<ModelConfig>& expected = std::nullopt);

}  // namespace paco
