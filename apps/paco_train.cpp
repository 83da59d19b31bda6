// paco_train: trains the PaCo network (plane proxy encoder + parametric completer) on a dataset
// written by paco_dataset, with checkpoints, validation every epoch and a CSV log of the curves.
//   paco_train data/mfcad -o runs/cpu --preset cpu --epochs 50 --threads 2
//   paco_train data/mfcad -o runs/cpu --resume            # continue after Ctrl-C
#include "app_support.h"

#include <torch/torch.h>  // before PCL-using headers (see doc/training.md)

#include <paco/common/blas.h>
#include <paco/common/error.h>
#include <paco/common/hash.h>
#include <paco/common/progress.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/hidden_extent.h>
#include <paco/completion/trainer.h>
#include <paco/data/dataset.h>
#include <paco/encoding/model_config.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

const char kTool[] = "paco_train";

struct Options {
  std::vector<std::string> datasets;
  std::string output;
  std::string preset = "cpu";
  std::string config_file;
  int epochs = 100;
  int batch = 16;
  double lr = 1e-4;
  int threads = 2;
  std::size_t limit_train = 0, limit_val = 0;
  bool resume = false;
  std::uint64_t seed = 1;
  std::vector<std::string> disabled_losses;
  bool quality_classification = false;
  std::string input_frame = "complete";
  std::string input_orientation = "as-is";
  double augment_scale = 0.0, augment_offset = 0.0, augment_jitter = 0.0;
  int input_points = 2048, gt_points = 8192;
  int prefetch = 3;
  int checkpoint_every = 200;
  bool quiet = false;
  std::string export_from;
  std::string init_from;
  std::string extent_head_for;
  std::string feature_cache;
};

// Writes the network of a training checkpoint without its training state: the file a user loads
// (a third of the size; the optimizer's moments are not needed for inference).
int exportModel(const Options& o) {
  if (fs::exists(o.output) && fs::is_directory(o.output))
    throw paco::app::UsageError("--export writes a model file; -o '" + o.output + "' is a folder");
  paco::app::checkOutputsAreNotInputs({{"--export", o.export_from}}, {{"-o", o.output}});
  paco::LoadedCheckpoint checkpoint = paco::loadCheckpoint(o.export_from);
  paco::saveCheckpoint(o.output, checkpoint.network);
  std::int64_t parameters = 0;
  for (const auto& p : checkpoint.network->parameters()) parameters += p.numel();
  std::printf("exported '%s' (network '%s', %.2f M parameters) to '%s' (%.1f MB)\n", o.export_from.c_str(),
              checkpoint.config.name.c_str(), parameters / 1e6, o.output.c_str(),
              static_cast<double>(fs::file_size(o.output)) / 1e6);
  return 0;
}

// One split's extent examples on disk (--feature-cache), so that an interrupted feature pass (about
// an hour on MFCAD's 48 k training samples) goes on where it stopped, and a head can be trained
// again with other settings without one. A header ties the file to the network and to the samples
// picked; then one fixed-size record per pick, in order: a byte (1: an example, 0: the sample has
// no labelled plane), the features, the six targets. A record cut short by a kill is computed again.
// Format 02: the features are observed in the box fill's frame (paco::closingBoxRotation); format
// 01's were in the dominant seen planes' frame, and are refused.
class ExtentFeatureCache {
 public:
  using Record = std::optional<paco::ExtentExample>;

  ExtentFeatureCache(fs::path file, std::uint64_t fingerprint, std::uint64_t picks_key, int width)
      : file_(std::move(file)), fingerprint_(fingerprint), picks_key_(picks_key), width_(width) {}

  // The records already in the file (none when there is no file), which is then opened to append
  // the others. Throws InvalidInputError for a file of another kind or made for other inputs.
  std::vector<Record> open() {
    std::vector<Record> records;
    std::error_code ec;
    if (fs::exists(file_, ec)) records = read();
    const std::uintmax_t whole = kHeaderBytes + records.size() * recordBytes();
    if (records.empty()) {
      std::ofstream out(file_, std::ios::binary | std::ios::trunc);
      writeHeader(out);
      if (!out) throw paco::IoError("cannot write the feature cache '" + file_.string() + "'");
    } else {
      fs::resize_file(file_, whole, ec);  // drops a record cut short
      if (ec) throw paco::IoError("cannot resize the feature cache '" + file_.string() + "': " + ec.message());
    }
    out_.open(file_, std::ios::binary | std::ios::app);
    if (!out_) throw paco::IoError("cannot append to the feature cache '" + file_.string() + "'");
    return records;
  }

  void append(const Record& record) {
    const char present = record ? 1 : 0;
    out_.write(&present, 1);
    std::vector<float> values(static_cast<std::size_t>(width_ + paco::kBoxSides), 0.0f);
    if (record) {
      if (static_cast<int>(record->features.size()) != width_)
        throw paco::InvalidInputError("feature cache: an example has " + std::to_string(record->features.size()) +
                                      " features, the cache " + std::to_string(width_));
      std::copy(record->features.begin(), record->features.end(), values.begin());
      std::copy(record->beyond.begin(), record->beyond.end(), values.begin() + width_);
    }
    out_.write(reinterpret_cast<const char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float)));
    out_.flush();  // a record costs a forward pass; writing it at once loses nothing to a kill
    if (!out_) throw paco::IoError("cannot append to the feature cache '" + file_.string() + "'");
  }

 private:
  static constexpr char kMagic[8] = {'P', 'A', 'C', 'O', 'X', 'F', '0', '2'};
  static constexpr char kMagicBeforeTheFillsFrame[8] = {'P', 'A', 'C', 'O', 'X', 'F', '0', '1'};
  static constexpr std::uintmax_t kHeaderBytes = sizeof kMagic + 2 * sizeof(std::uint64_t) + sizeof(std::int32_t);

  std::uintmax_t recordBytes() const { return 1 + sizeof(float) * static_cast<std::uintmax_t>(width_ + paco::kBoxSides); }

  void writeHeader(std::ofstream& out) const {
    const std::int32_t width = width_;
    out.write(kMagic, sizeof kMagic);
    out.write(reinterpret_cast<const char*>(&fingerprint_), sizeof fingerprint_);
    out.write(reinterpret_cast<const char*>(&picks_key_), sizeof picks_key_);
    out.write(reinterpret_cast<const char*>(&width), sizeof width);
  }

  std::vector<Record> read() const {
    const std::string what = "the feature cache '" + file_.string() + "'";
    std::ifstream in(file_, std::ios::binary);
    char magic[sizeof kMagic] = {};
    std::uint64_t fingerprint = 0, picks_key = 0;
    std::int32_t width = 0;
    in.read(magic, sizeof magic);
    in.read(reinterpret_cast<char*>(&fingerprint), sizeof fingerprint);
    in.read(reinterpret_cast<char*>(&picks_key), sizeof picks_key);
    in.read(reinterpret_cast<char*>(&width), sizeof width);
    if (in && std::equal(magic, magic + sizeof magic, kMagicBeforeTheFillsFrame))
      throw paco::InvalidInputError(what + " holds features observed in the dominant seen planes' frame, which the "
                                           "head no longer uses (it takes the box fill's since 2026-12-07); delete it "
                                           "or give another --feature-cache folder");
    if (!in || !std::equal(magic, magic + sizeof magic, kMagic))
      throw paco::InvalidInputError(what + " is not one (unreadable or truncated header); delete it or give another "
                                           "--feature-cache folder");
    if (fingerprint != fingerprint_ || width != width_)
      throw paco::InvalidInputError(what + " holds the features of another network; delete it or give another "
                                           "--feature-cache folder");
    if (picks_key != picks_key_)
      throw paco::InvalidInputError(what + " was made for other samples (other datasets, --limit-train or "
                                           "--limit-val); delete it or give another --feature-cache folder");
    std::vector<Record> records;
    std::vector<float> values(static_cast<std::size_t>(width_ + paco::kBoxSides));
    for (;;) {
      char present = 0;
      if (!in.read(&present, 1)) break;
      if (!in.read(reinterpret_cast<char*>(values.data()), static_cast<std::streamsize>(values.size() * sizeof(float))))
        break;  // cut short
      if (present != 0 && present != 1) throw paco::InvalidInputError(what + " is corrupt; delete it");
      if (!present) {
        records.emplace_back();
        continue;
      }
      paco::ExtentExample example;
      example.features.assign(values.begin(), values.begin() + width_);
      std::copy(values.begin() + width_, values.end(), example.beyond.begin());
      records.emplace_back(std::move(example));
    }
    return records;
  }

  fs::path file_;
  std::uint64_t fingerprint_, picks_key_;
  int width_;
  std::ofstream out_;
};

// What a feature cache is made for: the datasets' folders and the samples picked from them.
std::uint64_t picksKey(const std::vector<std::string>& folders, paco::data::Split split,
                       const std::vector<std::pair<std::size_t, std::size_t>>& picks) {
  std::uint64_t hash = paco::kFnv1aOffsetBasis;
  const auto mix = [&](const std::string& text) {
    hash = paco::fnv1a("\xff", paco::fnv1a(text, hash));  // a separator, so that "ab","c" differs from "a","bc"
  };
  for (const auto& folder : folders) mix(fs::weakly_canonical(folder).string());
  mix(split == paco::data::Split::Train ? "train" : "val");
  for (const auto& [dataset, index] : picks) mix(std::to_string(dataset) + ":" + std::to_string(index));
  return hash;
}

// The examples of one split of the datasets for a hidden-extent head: each sample's input with its
// stored labels, seen by the model's network, and how far its complete part reaches beyond it.
// With `cache_folder`, taken from and added to its feature cache. Empty when interrupted.
std::vector<paco::ExtentExample> extentExamples(const paco::CompletionModel::ConstPtr& model,
                                                const std::vector<std::string>& folders,
                                                const std::vector<std::shared_ptr<const paco::data::Dataset>>& datasets,
                                                paco::data::Split split, std::size_t limit, bool quiet,
                                                const std::string& cache_folder) {
  const auto picks = paco::completion::evenlySpacedSamples(datasets, split, limit);
  const char* name = split == paco::data::Split::Train ? "training" : "validation";
  std::vector<ExtentFeatureCache::Record> records;
  std::optional<ExtentFeatureCache> cache;
  if (!cache_folder.empty()) {
    cache.emplace(fs::path(cache_folder) / (std::string(name) + ".features"), paco::networkFingerprint(*model),
                  picksKey(folders, split, picks), model->config().global_width + 3);
    records = cache->open();
    if (records.size() > picks.size())
      throw paco::InvalidInputError("the feature cache in '" + cache_folder + "' holds more " + name +
                                    " samples than this command picks; delete it");
    if (!quiet && !records.empty())
      std::printf("%s samples: %zu of %zu from the feature cache in '%s'\n", name, records.size(), picks.size(),
                  cache_folder.c_str());
  }
  std::optional<paco::ProgressBar> bar;
  if (!quiet && records.size() < picks.size())
    bar.emplace(std::string(name) + " samples", picks.size() - records.size());
  for (std::size_t k = records.size(); k < picks.size(); ++k) {
    if (paco::interruptRequested()) return {};
    const auto [dataset, index] = picks[k];
    const paco::data::Sample sample = datasets[dataset]->load(split, index);
    const auto segmentation = paco::PlanarSegmentation::fromLabels(sample.input, sample.input_labels);
    ExtentFeatureCache::Record record;
    if (!segmentation.empty()) {
      const auto observation = paco::observeExtent(model, sample.input.makeShared(), segmentation);
      std::vector<Eigen::Vector3d> complete;
      for (const auto& p : sample.gt_points) complete.push_back(p.getVector3fMap().cast<double>());
      record = paco::ExtentExample{observation.features, paco::extentBeyond(observation, complete)};
    }
    if (cache) cache->append(record);
    records.push_back(std::move(record));
    if (bar) bar->advance();
  }
  if (bar) bar->finish();
  std::vector<paco::ExtentExample> examples;
  for (auto& record : records)
    if (record) examples.push_back(std::move(*record));
  return examples;
}

// How a head does on examples against the box fill's guess (nothing beyond the seen box), and
// on the sides where the part goes on by more than 0.03 of the scan's diagonal.
void reportExtent(const char* name, const paco::HiddenExtentModel& head, const std::vector<paco::ExtentExample>& examples) {
  std::size_t short_sides = 0, other_sides = 0;
  double gap = 0.0, predicted_short = 0.0, predicted_other = 0.0;
  for (const auto& example : examples) {
    const auto predicted = head.predict(example.features);
    for (int s = 0; s < paco::kBoxSides; ++s) {
      const auto side = static_cast<std::size_t>(s);
      if (example.beyond[side] > 0.03) {
        ++short_sides;
        gap += example.beyond[side];
        predicted_short += predicted[side];
      } else {
        ++other_sides;
        predicted_other += predicted[side];
      }
    }
  }
  const double zero = paco::meanAbsoluteExtentError(nullptr, examples);
  const double learnt = paco::meanAbsoluteExtentError(&head, examples);
  std::printf("%s: %zu samples; mean error beyond the seen box %.4f (the box fill's, nothing beyond: %.4f, %.0f %%); "
              "%zu sides short by > 0.03: gap %.3f, predicted %.3f; other sides predicted %.4f\n",
              name, examples.size(), learnt, zero, zero > 0.0 ? 100.0 * learnt / zero : 0.0, short_sides,
              short_sides ? gap / short_sides : 0.0, short_sides ? predicted_short / short_sides : 0.0,
              other_sides ? predicted_other / other_sides : 0.0);
}

// paco_train DATASET... --extent-head-for MODEL -o HEAD.pt
int trainExtentHead(const Options& o, const po::variables_map& vm) {
  if (o.datasets.empty()) throw paco::app::UsageError("--extent-head-for needs DATASET_DIR (a folder written by paco_dataset)");
  if (o.output.empty()) throw paco::app::UsageError("--extent-head-for needs -o HEAD.pt");
  if (o.epochs < 1) throw paco::app::UsageError("--epochs must be at least 1 for a head, got " + std::to_string(o.epochs));
  if (!(o.lr > 0.0)) throw paco::app::UsageError("--lr must be more than 0, got " + paco::app::shortNumber(o.lr));
  paco::app::validateThreads("--threads", o.threads);
  paco::app::checkOutputPath(o.output, "-o", {".pt"});
  paco::app::checkOutputsAreNotInputs({{"--extent-head-for", o.extent_head_for}}, {{"-o", o.output}});
  torch::set_num_threads(o.threads);
  paco::warnIfSlowBlas();
  const auto model = paco::CompletionModel::load(o.extent_head_for);
  std::vector<std::shared_ptr<const paco::data::Dataset>> datasets;
  for (const auto& folder : o.datasets) datasets.push_back(std::make_shared<const paco::data::Dataset>(folder));
  paco::app::PendingOutput output(o.output);
  paco::InterruptGuard guard;
  const auto interrupted = [] {
    std::printf("interrupted: no head written\n");
    return 130;
  };
  if (!o.feature_cache.empty()) {
    std::error_code ec;
    fs::create_directories(o.feature_cache, ec);
    if (!fs::is_directory(o.feature_cache))
      throw paco::IoError("cannot create the --feature-cache folder '" + o.feature_cache + "'" +
                          (ec ? ": " + ec.message() : std::string()));
  }
  const auto train =
      extentExamples(model, o.datasets, datasets, paco::data::Split::Train, o.limit_train, o.quiet, o.feature_cache);
  if (paco::interruptRequested()) return interrupted();
  if (train.empty())
    throw paco::InvalidInputError("no training sample with a labelled plane in the datasets; build them with "
                                  "paco_dataset (--segment labels them as paco_reconstruct does)");
  const auto val = extentExamples(model, o.datasets, datasets, paco::data::Split::Val,
                                  o.limit_val == 0 ? 1500 : o.limit_val, o.quiet, o.feature_cache);
  if (paco::interruptRequested()) return interrupted();
  paco::ExtentTrainingOptions options;
  options.epochs = o.epochs;
  options.learning_rate = vm["lr"].defaulted() ? 1e-3 : o.lr;  // the network's default suits a 4 M network, not a head
  options.seed = o.seed;
  std::optional<paco::ProgressBar> bar;
  if (!o.quiet) bar.emplace("epochs", static_cast<std::size_t>(o.epochs));
  options.after_epoch = [&](int, double l1) {
    if (bar) {
      char status[48];
      std::snprintf(status, sizeof status, "train L1 %.4f", l1);
      bar->setStatus(status);
      bar->advance();
    }
    return !paco::interruptRequested();
  };
  const auto head = paco::trainHiddenExtentModel(paco::networkFingerprint(*model), train, options);
  if (bar) bar->finish();
  if (paco::interruptRequested()) return interrupted();
  reportExtent("training", *head, train);
  if (!val.empty()) reportExtent("validation", *head, val);
  head->save(output.writePath());
  output.commit();
  std::printf("wrote the hidden-extent head '%s' for '%s' (%zu training samples, %d epochs, lr %g)\n", o.output.c_str(),
              o.extent_head_for.c_str(), train.size(), o.epochs, options.learning_rate);
  return 0;
}

// Removes the checkpoint folder when this run created it and wrote nothing into it (a failed
// run), so that a rerun is not taken for one to resume and no empty folder is left behind.
class NewFolderCleanup {
 public:
  explicit NewFolderCleanup(fs::path folder) : folder_(std::move(folder)), existed_(fs::exists(folder_)) {}
  ~NewFolderCleanup() {
    std::error_code ec;
    if (!existed_ && fs::is_directory(folder_, ec) && fs::is_empty(folder_, ec)) fs::remove(folder_, ec);
  }
  NewFolderCleanup(const NewFolderCleanup&) = delete;
  NewFolderCleanup& operator=(const NewFolderCleanup&) = delete;

 private:
  fs::path folder_;
  bool existed_;
};

void printHelp(const po::options_description& visible) {
  std::cout << "Usage: " << kTool << " DATASET_DIR... -o CHECKPOINT_DIR [options]\n"
            << "       " << kTool << " --export CHECKPOINT -o MODEL.pt   (the network alone, for paco_reconstruct)\n"
            << "       " << kTool << " DATASET_DIR... --extent-head-for MODEL.pt -o HEAD.pt   (a hidden-extent head)\n\n"
            << "Trains the PaCo network on dataset folders written by paco_dataset (several: their\n"
            << "samples are used together, e.g. inputs cut by distance and inputs seen by one scanner). Writes\n"
            << "CHECKPOINT_DIR/last.pt (every epoch, and on Ctrl-C), CHECKPOINT_DIR/best.pt (lowest\n"
            << "validation loss) and CHECKPOINT_DIR/training_log.csv (one row per epoch). Ctrl-C saves\n"
            << "the state and stops; run again with --resume to continue exactly where it stopped.\n"
            << "Loss terms (for --disable-loss): classification, normal, offset, plane_chamfer,\n"
            << "overall_chamfer, repulsion, ranking. See doc/training.md.\n\n"
            << visible << std::endl;
}

std::string readFile(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw paco::IoError("cannot read the model configuration '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string formatValue(double v) {
  if (!std::isfinite(v)) return "-";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.4g", v);
  return buffer;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("output,o", po::value(&o.output), "checkpoint folder (created)")
      ("preset", po::value(&o.preset)->default_value(o.preset), "network size: cpu or paper")
      ("config", po::value(&o.config_file), "ModelConfig JSON file (overrides --preset)")
      ("epochs", po::value(&o.epochs)->default_value(o.epochs), "train until this many epochs are done")
      ("batch", po::value(&o.batch)->default_value(o.batch), "samples per step")
      ("lr", po::value(&o.lr)->default_value(o.lr), "base learning rate (AdamW); schedule max(0.9^(epoch/21), 0.02)")
      ("threads", po::value(&o.threads)->default_value(o.threads), "LibTorch intra-op threads")
      ("limit-train", po::value(&o.limit_train), "use at most N training samples (evenly spaced; 0 = all)")
      ("limit-val", po::value(&o.limit_val), "use at most N validation samples (0 = all)")
      ("resume", po::bool_switch(&o.resume), "continue the run in CHECKPOINT_DIR (last.pt)")
      ("init-from", po::value(&o.init_from),
       "start a new run from the weights (and network configuration) of this model, e.g. models/paco_cpu.pt")
      ("seed", po::value(&o.seed)->default_value(o.seed), "seed of weight init, data order and re-sampling")
      ("disable-loss", po::value(&o.disabled_losses)->multitoken(), "switch loss terms off (ablations)")
      ("quality-classification", po::bool_switch(&o.quality_classification),
       "a matched prediction learns confidence 1 only when its plane is within 10 deg and 0.05 of its GT "
       "plane (paco::completion::LossConfig::quality_classification); default: every matched one, as the paper")
      ("input-frame", po::value(&o.input_frame)->default_value(o.input_frame),
       "complete: the dataset's complete-shape frame (paper); own: re-normalise each input by its own box")
      ("input-orientation", po::value(&o.input_orientation)->default_value(o.input_orientation),
       "as-is, or seen-planes: also turn each input so that its largest segments' planes lie on the axes "
       "(needs --input-frame own; stored with the model, so inference does the same)")
      ("augment-scale", po::value(&o.augment_scale)->default_value(o.augment_scale),
       "random frame scale in [1-s, 1+s] for training samples (0 = off)")
      ("augment-offset", po::value(&o.augment_offset)->default_value(o.augment_offset),
       "random frame shift in [-t, t]^3 for training samples (0 = off)")
      ("augment-jitter", po::value(&o.augment_jitter)->default_value(o.augment_jitter),
       "Gaussian noise on training inputs, sigma drawn per sample in [0, j] (normalised units; 0 = off)")
      ("input-points", po::value(&o.input_points)->default_value(o.input_points), "points per input cloud")
      ("gt-points", po::value(&o.gt_points)->default_value(o.gt_points), "GT points per sample")
      ("prefetch", po::value(&o.prefetch)->default_value(o.prefetch), "batches loaded ahead by the background thread")
      ("export", po::value(&o.export_from), "write the network of this checkpoint (e.g. best.pt) without its training state to -o FILE")
      ("extent-head-for", po::value(&o.extent_head_for),
       "instead of the network, train a hidden-extent head for this model on the datasets' samples and their "
       "stored labels (-o HEAD.pt; --epochs, --lr (default here 1e-3), --limit-train, --limit-val (default 1500), "
       "--seed, --threads apply; doc/training.md)")
      ("feature-cache", po::value(&o.feature_cache),
       "with --extent-head-for: keep the network's features of each sample in this folder (created), so that an "
       "interrupted run goes on where it stopped and a head can be trained again without the feature pass")
      ("checkpoint-every", po::value(&o.checkpoint_every)->default_value(o.checkpoint_every),
       "also save last.pt every N steps inside an epoch (0 = only at epoch ends), so a killed run loses little")
      ("quiet", po::bool_switch(&o.quiet), "no progress bars");
  po::options_description all;
  all.add(visible).add_options()("dataset", po::value(&o.datasets)->multitoken());
  po::positional_options_description positional;
  positional.add("dataset", -1);
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, all, positional);
  if (vm.count("help")) {
    printHelp(visible);
    return 0;
  }
  if (!o.export_from.empty()) {
    if (o.output.empty()) throw paco::app::UsageError("--export needs -o MODEL.pt");
    return exportModel(o);
  }
  if (!o.feature_cache.empty() && o.extent_head_for.empty())
    throw paco::app::UsageError("--feature-cache needs --extent-head-for (the network's own training resumes with --resume)");
  if (!o.extent_head_for.empty()) return trainExtentHead(o, vm);
  if (o.datasets.empty()) throw paco::app::UsageError("expected DATASET_DIR (a folder written by paco_dataset)");
  if (o.output.empty()) throw paco::app::UsageError("expected -o CHECKPOINT_DIR");
  paco::app::validateThreads("--threads", o.threads);
  if (o.epochs < 0) throw paco::app::UsageError("--epochs must be >= 0, got " + std::to_string(o.epochs));
  // A new run of 0 epochs writes nothing (it said "checkpoints in" a folder it never made).
  if (o.epochs == 0 && !o.resume) throw paco::app::UsageError("--epochs must be at least 1 for a new run");
  if (o.batch < 1) throw paco::app::UsageError("--batch must be at least 1, got " + std::to_string(o.batch));
  if (!(o.lr > 0.0)) throw paco::app::UsageError("--lr must be more than 0, got " + paco::app::shortNumber(o.lr));
  if (o.input_points < 1 || o.gt_points < 1)
    throw paco::app::UsageError("--input-points and --gt-points must be at least 1, got " +
                                std::to_string(o.input_points) + " and " + std::to_string(o.gt_points));
  if (o.prefetch < 1) throw paco::app::UsageError("--prefetch must be at least 1, got " + std::to_string(o.prefetch));
  if (o.checkpoint_every < 0)
    throw paco::app::UsageError("--checkpoint-every must be >= 0 (0: only at epoch ends), got " +
                                std::to_string(o.checkpoint_every));
  if (o.input_frame != "complete" && o.input_frame != "own")
    throw paco::app::UsageError("--input-frame must be 'complete' or 'own'");
  if (o.input_orientation != "as-is" && o.input_orientation != "seen-planes")
    throw paco::app::UsageError("--input-orientation must be 'as-is' or 'seen-planes'");
  if (!(o.augment_scale >= 0.0 && o.augment_scale < 1.0) || !(o.augment_offset >= 0.0 && std::isfinite(o.augment_offset)))
    throw paco::app::UsageError("--augment-scale must be in [0, 1) and --augment-offset a number >= 0");
  if (!(o.augment_jitter >= 0.0 && o.augment_jitter < 0.2))
    throw paco::app::UsageError("--augment-jitter must be in [0, 0.2) (a fraction of the unit diagonal)");
  const fs::path last = fs::path(o.output) / "last.pt";
  if (o.resume && !fs::exists(last))
    throw paco::app::UsageError("--resume: '" + last.string() + "' does not exist; start without --resume");
  if (!o.resume && fs::exists(last))
    throw paco::app::UsageError("'" + o.output + "' already holds a run (last.pt); pass --resume to continue it "
                                "or choose another folder");

  if (o.resume && !o.init_from.empty())
    throw paco::app::UsageError("--resume and --init-from exclude each other: --resume continues a run, "
                                "--init-from starts a new one from a model's weights");

  torch::set_num_threads(o.threads);
  paco::warnIfSlowBlas();

  paco::completion::TrainerOptions options;
  if (!o.config_file.empty()) options.model = paco::ModelConfig::fromJson(readFile(o.config_file));
  else options.model = paco::app::usageErrorIfInvalid([&] { return paco::ModelConfig::preset(o.preset); }, "--preset: ");
  options.model.validate();
  for (const auto& name : o.disabled_losses)
    paco::app::usageErrorIfInvalid([&] { options.loss.disable(name); }, "--disable-loss: ");
  options.loss.quality_classification = o.quality_classification;
  options.epochs = o.epochs;
  options.batch_size = o.batch;
  options.learning_rate = o.lr;
  options.seed = o.seed;
  options.prefetch = o.prefetch;
  options.checkpoint_every = o.checkpoint_every;
  options.checkpoint_dir = o.output;
  options.show_progress = !o.quiet;

  // Read the starting model before anything is written, so a bad file leaves no run folder.
  std::optional<paco::LoadedCheckpoint> initial_model;
  if (!o.init_from.empty()) initial_model = paco::loadCheckpoint(o.init_from);

  // The orientation belongs to the model (inference must turn inputs the same way): a resumed
  // run keeps its own; --init-from keeps the model's unless --input-orientation is given.
  std::string orientation = o.input_orientation;
  if (o.resume) {
    orientation = paco::loadCheckpoint(last.string()).config.input_orientation;
    if (!vm["input-orientation"].defaulted() && orientation != o.input_orientation)
      std::printf("note: --resume keeps the run's input orientation '%s'; --input-orientation ignored\n",
                  orientation.c_str());
  } else if (initial_model) {
    if (vm["input-orientation"].defaulted()) orientation = initial_model->config.input_orientation;
    initial_model->config.input_orientation = orientation;
  }
  options.model.input_orientation = orientation;
  if (orientation != "as-is" && o.input_frame != "own")
    throw paco::app::UsageError("input orientation '" + orientation + "' needs --input-frame own");

  std::vector<std::shared_ptr<const paco::data::Dataset>> datasets;
  for (const auto& folder : o.datasets) datasets.push_back(std::make_shared<const paco::data::Dataset>(folder));
  paco::completion::CollateOptions collate;
  collate.input_points = o.input_points;
  collate.gt_points = o.gt_points;
  collate.input_frame = o.input_frame;
  collate.input_orientation = orientation;
  paco::completion::CollateOptions train_collate = collate;
  train_collate.augment_scale = o.augment_scale;
  train_collate.augment_offset = o.augment_offset;
  train_collate.augment_jitter = o.augment_jitter;
  const auto train = paco::completion::datasetSource(datasets, paco::data::Split::Train, train_collate, o.limit_train);
  const auto val = paco::completion::datasetSource(datasets, paco::data::Split::Val, collate, o.limit_val);
  if (train.size == 0)
    throw paco::InvalidInputError(std::string(o.datasets.size() == 1 ? "dataset '" + o.datasets[0] + "' has" : "the datasets have") +
                                  " no training samples; build a larger one with paco_dataset");

  const NewFolderCleanup cleanup(o.output);  // the trainer creates the folder
  paco::completion::Trainer trainer(options);
  if (o.resume) {
    if (vm.count("config") || !vm["preset"].defaulted())
      std::printf("note: --resume uses the network configuration stored in last.pt; --preset/--config ignored\n");
    trainer.resume(last.string());
    std::printf("resumed '%s': epoch %d, step %lld\n", last.string().c_str(), trainer.epoch(),
                static_cast<long long>(trainer.globalStep()));
    if (trainer.trainSamples() != 0 && trainer.trainSamples() != train.size)
      std::printf("note: the run had %zu training samples per epoch and this command gives %zu, so its data order "
                  "changes from here; to continue exactly, pass the run's datasets and --limit-train\n",
                  trainer.trainSamples(), train.size);
  } else if (initial_model) {
    if (vm.count("config") || !vm["preset"].defaulted())
      std::printf("note: --init-from uses the network configuration stored in '%s'; --preset/--config ignored\n",
                  o.init_from.c_str());
    trainer.startFrom(*initial_model);
    std::printf("starting from the weights of '%s'\n", o.init_from.c_str());
  }
  std::int64_t parameters = 0;
  for (const auto& p : trainer.network()->parameters()) parameters += p.numel();
  for (const auto& dataset : datasets)
    std::printf("dataset '%s': %zu training, %zu validation samples\n", dataset->folder().c_str(),
                dataset->size(paco::data::Split::Train), dataset->size(paco::data::Split::Val));
  std::printf("used: %zu training, %zu validation samples\n", train.size, val.size);
  std::printf("network '%s': %.2f M parameters; batch %d, lr %g, %d threads, input frame %s, orientation %s\n",
              trainer.options().model.name.c_str(), parameters / 1e6, trainer.options().batch_size, o.lr, o.threads,
              o.input_frame.c_str(), trainer.options().model.input_orientation.c_str());

  paco::InterruptGuard guard;
  const auto records = trainer.fit(train, val);
  for (const auto& r : records)
    std::printf("epoch %d: step %lld, lr %.3g, train loss %s, val loss %s, val recall %s, NC_prim %s, %s samples/s (%s)\n",
                r.epoch, static_cast<long long>(r.step), r.learning_rate, formatValue(r.train_loss).c_str(),
                formatValue(r.val_loss).c_str(), formatValue(r.val_metrics.recall).c_str(),
                formatValue(r.val_metrics.nc_prim).c_str(), formatValue(r.samples_per_second).c_str(),
                r.step_times.summary().c_str());
  if (trainer.interrupted()) {
    std::printf("interrupted: state saved to '%s' (epoch %d, step %lld); continue with --resume\n",
                last.string().c_str(), trainer.epoch(), static_cast<long long>(trainer.globalStep()));
    return 130;
  }
  std::printf("done: %d epochs, %lld steps; checkpoints in '%s'\n", trainer.epoch(),
              static_cast<long long>(trainer.globalStep()), o.output.c_str());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
