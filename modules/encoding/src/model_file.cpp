#include <paco/common/error.h>
#include <paco/encoding/model_file.h>

#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>
#include <unistd.h>

namespace paco {
namespace {

std::string quoted(const std::string& path) { return "'" + path + "'"; }

// LibTorch messages carry C++ backtraces; keep the first line, which says what went wrong.
std::string firstLine(const c10::Error& e) {
  std::string message = e.what_without_backtrace();
  const auto newline = message.find('\n');
  if (newline != std::string::npos) message.resize(newline);
  return message;
}

std::uint32_t crc32Of(const torch::Tensor& tensor) {
  const torch::Tensor bytes = tensor.detach().to(torch::kCPU).contiguous();
  // zlib's crc32 takes at most 4 GiB per call; a weight tensor is far smaller, but go in pieces.
  const auto* data = static_cast<const Bytef*>(bytes.data_ptr());
  uLong crc = crc32(0L, Z_NULL, 0);
  for (std::size_t done = 0, total = bytes.nbytes(); done < total;) {
    const auto piece = static_cast<uInt>(std::min<std::size_t>(total - done, 1u << 30));
    crc = crc32(crc, data + done, piece);
    done += piece;
  }
  return static_cast<std::uint32_t>(crc);
}

std::string checksumsText(const WeightChecksums& checksums) {
  std::string text;
  char hex[16];
  for (const auto& [name, crc] : checksums) {
    std::snprintf(hex, sizeof hex, "%08x", static_cast<unsigned>(crc));
    text += name + " " + hex + "\n";
  }
  return text;
}

/// Parses checksumsText; false when a line is not "<name> <8 hex digits>".
bool parseChecksums(const std::string& text, WeightChecksums& checksums) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const auto blank = line.rfind(' ');
    if (blank == std::string::npos || blank == 0 || line.size() - blank - 1 != 8) return false;
    const std::string hex = line.substr(blank + 1);
    if (hex.find_first_not_of("0123456789abcdef") != std::string::npos) return false;
    checksums[line.substr(0, blank)] = static_cast<std::uint32_t>(std::stoul(hex, nullptr, 16));
  }
  return true;
}

}  // namespace

WeightChecksums weightChecksums(const torch::nn::Module& module) {
  WeightChecksums checksums;
  for (const auto& item : module.named_parameters()) checksums[item.key()] = crc32Of(item.value());
  for (const auto& item : module.named_buffers()) checksums[item.key()] = crc32Of(item.value());
  return checksums;
}

ModelFile readModelFile(const std::string& path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (path.empty())
    throw ModelError("no model file given: pass --model FILE or set PACO_MODEL to a model "
                     "written by paco_train");
  if (!fs::is_regular_file(path, ec))
    throw ModelError("model file " + quoted(path) +
                     " does not exist or is not a file: give the path of a model written by "
                     "paco_train (or set PACO_MODEL)");
  ModelFile file;
  file.path = path;
  torch::serialize::InputArchive archive;
  try {
    archive.load_from(path);
  } catch (const c10::Error& e) {
    throw ModelError("model file " + quoted(path) +
                     " is corrupt or truncated (cannot be read as a LibTorch archive: " +
                     firstLine(e) + "): download or train it again");
  }
  c10::IValue value;
  if (!archive.try_read("format_version", value) || !value.isInt())
    throw ModelError("model file " + quoted(path) +
                     " has no paco format version: it was not written by paco_train (or by "
                     "paco::saveCheckpoint); use a paco model file");
  file.format_version = static_cast<int>(value.toInt());
  if (file.format_version != kModelFormatVersion)
    throw ModelError("model file " + quoted(path) + " was written by format v" +
                     std::to_string(file.format_version) + "; this build reads v" +
                     std::to_string(kModelFormatVersion) +
                     ": retrain it with this build's paco_train, or use a paco build of the "
                     "same format");
  if (!archive.try_read("config", value) || !value.isString())
    throw ModelError("model file " + quoted(path) +
                     " has no model configuration: the file is damaged; train it again");
  try {
    file.config = ModelConfig::fromJson(value.toStringRef());
    file.config.validate();
  } catch (const InvalidInputError& e) {
    throw ModelError("model file " + quoted(path) + " has an invalid configuration (" +
                     e.what() + "): the file is damaged; train it again");
  }
  if (archive.try_read("parameter_count", value) && value.isInt())
    file.parameter_count = value.toInt();
  if (archive.try_read("weight_checksums", value) &&
      (!value.isString() || !parseChecksums(value.toStringRef(), file.weight_checksums)))
    throw ModelError("model file " + quoted(path) +
                     " has a malformed list of weight checksums: the file is damaged; copy or train it again");
  file.model = std::make_shared<torch::serialize::InputArchive>();
  try {
    if (!archive.try_read("model", *file.model))
      throw ModelError("model file " + quoted(path) +
                       " holds no network weights: the file is damaged; train it again");
    auto state = std::make_shared<torch::serialize::InputArchive>();
    if (archive.try_read("training_state", *state)) file.training_state = state;
  } catch (const c10::Error& e) {
    throw ModelError("model file " + quoted(path) + " is corrupt (" + firstLine(e) +
                     "): download or train it again");
  }
  return file;
}

void writeModelFile(const std::string& path, const ModelConfig& config,
                    torch::serialize::OutputArchive& model, std::int64_t parameter_count,
                    torch::serialize::OutputArchive* training_state, const WeightChecksums& checksums) {
  config.validate();
  torch::serialize::OutputArchive root;
  root.write("format_version", c10::IValue(static_cast<int64_t>(kModelFormatVersion)));
  root.write("config", c10::IValue(config.toJson()));
  root.write("parameter_count", c10::IValue(static_cast<int64_t>(parameter_count)));
  if (!checksums.empty()) root.write("weight_checksums", c10::IValue(checksumsText(checksums)));
  root.write("model", model);
  if (training_state) root.write("training_state", *training_state);
  saveArchiveAtomically(root, path, "model file");
}

void saveArchiveAtomically(torch::serialize::OutputArchive& archive, const std::string& path, const std::string& what) {
  // Write beside the target and rename, so a crash or Ctrl-C never leaves a truncated file.
  const std::string temporary = path + ".partial." + std::to_string(::getpid());
  try {
    archive.save_to(temporary);
  } catch (const c10::Error& e) {
    std::error_code ignored;
    std::filesystem::remove(temporary, ignored);
    throw IoError("cannot write " + what + " " + quoted(path) + ": " + firstLine(e) +
                  " (check that the folder exists and is writable)");
  }
  std::error_code ec;
  std::filesystem::rename(temporary, path, ec);
  if (ec) {
    std::filesystem::remove(temporary, ec);
    throw IoError("cannot write " + what + " " + quoted(path) + ": " + ec.message());
  }
}

void checkWeightsReadable(const torch::nn::Module& module, const std::string& description) {
  auto check = [&](const std::string& name, const torch::Tensor& t) {
    if (!t.defined() || t.numel() == 0) return;
    // The last element the view reaches, in the storage's elements: offset + sum (size - 1) * stride.
    std::int64_t last = t.storage_offset();
    for (std::int64_t d = 0; d < t.dim(); ++d) last += (t.size(d) - 1) * t.stride(d);
    const auto needed = static_cast<std::size_t>(last + 1) * t.element_size();
    if (!t.has_storage() || t.storage().nbytes() < needed)
      throw ModelError(description + " tensor '" + name + "' holds " +
                       std::to_string(t.has_storage() ? t.storage().nbytes() : 0) + " bytes but its shape " +
                       c10::str(t.sizes()) + " needs " + std::to_string(needed) +
                       ": the file is truncated or damaged; copy or train it again");
    if (t.is_floating_point() && !torch::isfinite(t).all().item<bool>())
      throw ModelError(description + " tensor '" + name +
                       "' holds NaN or infinite values: the file is damaged, or the training that wrote it "
                       "diverged; copy it again or train a new one");
  };
  for (const auto& item : module.named_parameters()) check(item.key(), item.value());
  for (const auto& item : module.named_buffers()) check(item.key(), item.value());
}

void loadModuleWeights(torch::nn::Module& module, torch::serialize::InputArchive& archive, const ModelFile& file,
                       const std::string& name_prefix, const std::string& what) {
  const std::string& path = file.path;
  // InputArchive replaces tensors whatever their shape, so the shapes are checked here.
  std::map<std::string, std::vector<int64_t>> expected;
  for (const auto& item : module.named_parameters()) expected[item.key()] = item.value().sizes().vec();
  for (const auto& item : module.named_buffers()) expected[item.key()] = item.value().sizes().vec();
  try {
    module.load(archive);
  } catch (const c10::Error& e) {
    throw ModelError("model file " + quoted(path) + ": the " + what +
                     " weights do not match its configuration (" + firstLine(e) +
                     "): the file is damaged or was written by another network version; "
                     "train it again");
  }
  auto check = [&](const std::string& name, const torch::Tensor& t) {
    auto it = expected.find(name);
    if (it != expected.end() && t.sizes().vec() != it->second)
      throw ModelError("model file " + quoted(path) + ": the " + what + " tensor '" + name +
                       "' has shape " + c10::str(t.sizes()) + " but its configuration needs " +
                       c10::str(c10::IntArrayRef(it->second)) +
                       ": the file is damaged or was edited; train it again");
  };
  for (const auto& item : module.named_parameters()) check(item.key(), item.value());
  for (const auto& item : module.named_buffers()) check(item.key(), item.value());
  checkWeightsReadable(module, "model file " + quoted(path) + ": the " + what);
  if (file.weight_checksums.empty()) return;
  for (const auto& [name, crc] : weightChecksums(module)) {
    const auto stored = file.weight_checksums.find(name_prefix + name);
    if (stored == file.weight_checksums.end())
      throw ModelError("model file " + quoted(path) + " stores no checksum for the " + what + " tensor '" + name +
                       "': the file is damaged or was edited; copy or train it again");
    if (stored->second != crc)
      throw ModelError("model file " + quoted(path) + ": the " + what + " tensor '" + name +
                       "' does not match the checksum stored with it: the file was damaged after it was "
                       "written (disk, copy or download); copy or train it again");
  }
}

}  // namespace paco
