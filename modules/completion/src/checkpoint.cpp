#include <paco/common/error.h>
#include <paco/completion/checkpoint.h>

namespace paco {

void saveCheckpoint(const std::string& path, PacoNetwork& network,
                    torch::serialize::OutputArchive* training_state) {
  torch::serialize::OutputArchive model;
  network->save(model);
  writeModelFile(path, network->config(), model, parameterCount(*network), training_state, weightChecksums(*network));
}

LoadedCheckpoint loadCheckpoint(const std::string& path, const std::optional<ModelConfig>& expected) {
  ModelFile file = readModelFile(path);
  if (expected) {
    const std::string difference = expected->firstDifference(file.config);
    if (!difference.empty())
      throw ModelError("model file '" + path + "' was trained with another configuration (" +
                       difference + ", expected vs file): use the matching --preset/config or "
                       "start a new training run");
  }
  LoadedCheckpoint checkpoint;
  checkpoint.config = file.config;
  checkpoint.format_version = file.format_version;
  checkpoint.network = PacoNetwork(file.config);
  loadModuleWeights(*checkpoint.network, *file.model, file, "", "network");
  checkpoint.network->eval();
  checkpoint.training_state = file.training_state;
  return checkpoint;
}

}  // namespace paco
