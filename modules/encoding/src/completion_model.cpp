#include <paco/common/blas.h>
#include <paco/common/error.h>
#include <paco/encoding/completion_model.h>
#include <paco/encoding/completion_model_impl.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <thread>

namespace paco {
namespace {

std::atomic<bool> threads_chosen{false};

void applyDefaultThreads() {
  if (!threads_chosen.exchange(true)) {
    const unsigned hardware = std::thread::hardware_concurrency();
    at::set_num_threads(static_cast<int>(std::max(1u, hardware)));
  }
}

std::string firstModelIn(const std::filesystem::path& folder) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return "";
  if (fs::is_regular_file(folder / "paco_cpu.pt", ec)) return (folder / "paco_cpu.pt").string();
  std::vector<std::string> models;
  for (const auto& entry : fs::directory_iterator(folder, ec))
    if (entry.is_regular_file() && entry.path().extension() == ".pt")
      models.push_back(entry.path().string());
  std::sort(models.begin(), models.end());
  return models.empty() ? "" : models.front();
}

}  // namespace

CompletionModel::CompletionModel(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

CompletionModel::ConstPtr CompletionModel::load(const std::string& path) {
  warnIfSlowBlas();
  applyDefaultThreads();
  auto impl = std::make_shared<Impl>();
  impl->file = readModelFile(path);
  torch::serialize::InputArchive encoder_archive;
  try {
    if (!impl->file.model->try_read("encoder", encoder_archive))
      throw ModelError("model file '" + path +
                       "' has no encoder weights: the file is damaged; train it again");
  } catch (const c10::Error& e) {
    throw ModelError("model file '" + path + "' is corrupt (" + e.what_without_backtrace() +
                     "): download or train it again");
  }
  impl->encoder = PlaneProxyNetwork(impl->file.config);
  loadModuleWeights(*impl->encoder, encoder_archive, impl->file, "encoder.", "encoder");
  impl->encoder->eval();
  return std::make_shared<const CompletionModel>(std::move(impl));
}

std::string CompletionModel::findShippedModel() {
  if (const char* env = std::getenv("PACO_MODEL"); env && *env) return env;
  for (const char* folder : {PACO_SOURCE_MODELS_DIR, PACO_INSTALL_MODELS_DIR}) {
    const std::string found = firstModelIn(folder);
    if (!found.empty()) return found;
  }
  return "";
}

void CompletionModel::setThreads(int threads) {
  threads_chosen = true;
  const unsigned hardware = std::max(1u, std::thread::hardware_concurrency());
  at::set_num_threads(threads > 0 ? threads : static_cast<int>(hardware));
}

const ModelConfig& CompletionModel::config() const { return impl_->file.config; }
const std::string& CompletionModel::path() const { return impl_->file.path; }
std::int64_t CompletionModel::parameterCount() const { return impl_->file.parameter_count; }

}  // namespace paco
