#pragma once
// Usage (LibTorch; low level, shared by the encoder, the completer and the trainer):
//   paco::ModelFile file = paco::readModelFile("model.pt");   // throws paco::ModelError
//   file.config; file.model->read("encoder", encoder_archive);
//   paco::writeModelFile("model.pt", config, model_archive, nullptr);
#include <paco/encoding/model_config.h>
#include <torch/torch.h>
#include <cstdint>
#include <map>
#include <memory>
#include <string>

namespace paco {

/// Format of the model files this build writes and reads. A file stores: "format_version"
/// (int), "config" (ModelConfig::toJson()), "model" (network weights: nested "encoder" and
/// "decoder" archives), optionally "training_state" (opaque to the network code) and
/// "weight_checksums" (WeightChecksums as text lines "<name> <crc32 hex>"; files written before
/// it existed, such as the shipped model of 2026-11, load without the check).
constexpr int kModelFormatVersion = 1;

/// The CRC-32 of each parameter and buffer of a network, by full name ("decoder.norm.weight").
/// Stored with the weights, it catches a file damaged after it was written (disk, copy,
/// download), which LibTorch's reader does not notice inside a tensor.
using WeightChecksums = std::map<std::string, std::uint32_t>;
WeightChecksums weightChecksums(const torch::nn::Module& module);

/// The parts of a model file, checked for format and config validity.
struct ModelFile {
  std::string path;
  int format_version = 0;
  ModelConfig config;
  std::int64_t parameter_count = 0;                                 ///< trainable scalars
  std::shared_ptr<torch::serialize::InputArchive> model;           ///< the "model" archive
  std::shared_ptr<torch::serialize::InputArchive> training_state;  ///< null when absent
  WeightChecksums weight_checksums;                                 ///< empty when the file has none
};

/// Reads and checks a model file. Throws paco::ModelError for a missing, corrupt or truncated
/// file, another format version, or an invalid config, with what to do next.
ModelFile readModelFile(const std::string& path);

/// Writes a model file atomically (a temporary file renamed into place); IoError on failure.
/// `checksums` (weightChecksums of the network in `model`) are stored when given.
void writeModelFile(const std::string& path, const ModelConfig& config,
                    torch::serialize::OutputArchive& model, std::int64_t parameter_count,
                    torch::serialize::OutputArchive* training_state = nullptr,
                    const WeightChecksums& checksums = {});

/// Saves `archive` to `path` atomically: beside it first, then renamed, so that a crash or Ctrl-C
/// never leaves a truncated file. IoError ("cannot write <what> '<path>': ...") on failure.
/// writeModelFile and the hidden-extent head (paco::HiddenExtentModel::save) write through it.
void saveArchiveAtomically(torch::serialize::OutputArchive& archive, const std::string& path, const std::string& what);

/// Throws paco::ModelError naming `description` (e.g. "model file 'a.pt': the encoder") when a
/// parameter or buffer of `module` holds fewer values than its shape needs (a record cut short
/// inside a file that is otherwise whole: reading it would run past its end) or a floating-point
/// value that is NaN or infinite (damaged bytes, or a diverged training run). Files written before
/// weight checksums were stored (the shipped model among them) have only this check.
void checkWeightsReadable(const torch::nn::Module& module, const std::string& description);

/// Loads `module`'s parameters and buffers from `archive`; converts LibTorch's errors (missing
/// or mis-shaped tensors) to paco::ModelError mentioning `file.path` and `what` (e.g.
/// "encoder"), and checks them with checkWeightsReadable. When the file stores weight checksums,
/// every tensor must match its own, named
/// `name_prefix` + its name in `module` ("encoder." for the encoder alone); a mismatch is a
/// ModelError that says the file was damaged.
void loadModuleWeights(torch::nn::Module& module, torch::serialize::InputArchive& archive, const ModelFile& file,
                       const std::string& name_prefix, const std::string& what);

}  // namespace paco
