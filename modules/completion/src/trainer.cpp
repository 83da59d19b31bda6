#include <paco/completion/trainer.h>

#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/completion/checkpoint.h>

#include <ATen/CPUGeneratorImpl.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <deque>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <mutex>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <thread>
#include <utility>

namespace paco::completion {
namespace {

std::uint64_t mix(std::uint64_t x) {  // splitmix64 finaliser: decorrelates nearby seeds
  x += 0x9E3779B97F4A7C15ULL;
  x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ULL;
  x = (x ^ (x >> 27)) * 0x94D049BB133111EBULL;
  return x ^ (x >> 31);
}

std::uint64_t batchSeed(std::uint64_t seed, std::uint64_t stream, std::uint64_t epoch, std::uint64_t batch) {
  return mix(mix(mix(seed ^ stream) + epoch) + batch);
}

constexpr std::uint64_t kTrainStream = 0x7472616e;  // "tran"
constexpr std::uint64_t kValStream = 0x76616c;      // "val"

// Loads batches on a background thread, `capacity` ahead of the consumer. Errors thrown by the
// loader are handed to the consumer by next().
class Prefetcher {
 public:
  Prefetcher(const BatchSource& source, std::vector<std::vector<std::size_t>> batches,
             std::vector<std::uint64_t> seeds, std::size_t capacity)
      : source_(source), batches_(std::move(batches)), seeds_(std::move(seeds)), capacity_(capacity) {
    thread_ = std::thread([this] { run(); });
  }
  ~Prefetcher() { stop(); }
  Prefetcher(const Prefetcher&) = delete;
  Prefetcher& operator=(const Prefetcher&) = delete;

  /// The next batch in order, or nothing at the end.
  std::optional<TrainingBatch> next() {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [this] { return !queue_.empty() || finished_ || error_; });
    if (!queue_.empty()) {
      TrainingBatch batch = std::move(queue_.front());
      queue_.pop_front();
      space_.notify_one();
      return batch;
    }
    if (error_) std::rethrow_exception(error_);
    return std::nullopt;
  }

  void stop() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stopping_ = true;
    }
    space_.notify_all();
    if (thread_.joinable()) thread_.join();
  }

 private:
  void run() {
    try {
      for (std::size_t i = 0; i < batches_.size(); ++i) {
        {
          std::unique_lock<std::mutex> lock(mutex_);
          space_.wait(lock, [this] { return queue_.size() < capacity_ || stopping_; });
          if (stopping_) break;
        }
        TrainingBatch batch = source_.load(batches_[i], seeds_[i]);
        std::lock_guard<std::mutex> lock(mutex_);
        queue_.push_back(std::move(batch));
        ready_.notify_one();
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    finished_ = true;
    ready_.notify_all();
  }

  const BatchSource& source_;
  std::vector<std::vector<std::size_t>> batches_;
  std::vector<std::uint64_t> seeds_;
  std::size_t capacity_;
  std::deque<TrainingBatch> queue_;
  std::mutex mutex_;
  std::condition_variable ready_, space_;
  bool finished_ = false, stopping_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

torch::Tensor scalarTensor(double value) { return torch::tensor(value, torch::kDouble); }
torch::Tensor scalarTensor(std::int64_t value) { return torch::tensor(value, torch::kLong); }

std::string shortName(const std::string& term) {
  static const std::map<std::string, std::string> names{
      {"classification", "cls"}, {"normal", "nrm"}, {"offset", "off"}, {"plane_chamfer", "pcd"},
      {"overall_chamfer", "ocd"}, {"repulsion", "rep"}, {"ranking", "rank"}};
  const auto it = names.find(term);
  return it == names.end() ? term : it->second;
}

std::string formatNumber(double value, int precision = 4) {
  std::ostringstream out;
  out << std::setprecision(precision) << value;
  return out.str();
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

void StepTimes::add(const StepTimes& other) {
  load_wait += other.load_wait;
  forward += other.forward;
  matching += other.matching;
  losses += other.losses;
  backward += other.backward;
}

std::string StepTimes::summary() const {
  const double total = load_wait + forward + matching + losses + backward;
  if (total <= 0.0) return "";
  auto share = [&](double part) { return std::to_string(static_cast<int>(std::lround(100.0 * part / total))) + "%"; };
  return "load " + share(load_wait) + " fwd " + share(forward) + " match " + share(matching) + " loss " +
         share(losses) + " bwd " + share(backward);
}

std::vector<std::size_t> epochOrder(std::size_t n, std::uint64_t seed, int epoch) {
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::mt19937_64 rng(batchSeed(seed, kTrainStream, static_cast<std::uint64_t>(epoch), 0xFFFFFFFFull));
  std::shuffle(order.begin(), order.end(), rng);
  return order;
}

Trainer::Trainer(TrainerOptions options) : options_(std::move(options)) {
  if (options_.batch_size < 1) throw InvalidInputError("Trainer: batch_size must be >= 1");
  if (options_.epochs < 0) throw InvalidInputError("Trainer: epochs must be >= 0");
  if (!(options_.learning_rate > 0.0)) throw InvalidInputError("Trainer: learning_rate must be > 0");
  if (options_.weight_decay < 0.0) throw InvalidInputError("Trainer: weight_decay must be >= 0");
  if (options_.prefetch < 1) throw InvalidInputError("Trainer: prefetch must be >= 1");
  if (options_.checkpoint_every < 0) throw InvalidInputError("Trainer: checkpoint_every must be >= 0");
  if (!(options_.lr_decay > 0.0) || !(options_.lr_decay_epochs > 0.0) || options_.lr_floor < 0.0)
    throw InvalidInputError("Trainer: the lr schedule needs lr_decay > 0, lr_decay_epochs > 0, lr_floor >= 0");
  options_.model.validate();
  torch::manual_seed(options_.seed);
  network_ = PacoNetwork(options_.model);
  network_->train();
  makeOptimizer();
  if (!options_.checkpoint_dir.empty()) std::filesystem::create_directories(options_.checkpoint_dir);
}

Trainer::~Trainer() = default;

void Trainer::makeOptimizer() {
  // Weight matrices decay; biases and normalisation scales/shifts (all 1-D) do not.
  std::vector<torch::Tensor> decay, no_decay;
  for (const auto& p : network_->parameters()) {
    if (!p.requires_grad()) continue;
    (p.dim() <= 1 ? no_decay : decay).push_back(p);
  }
  using torch::optim::AdamWOptions;
  std::vector<torch::optim::OptimizerParamGroup> groups;
  const double lr = learningRateAt(epoch_);
  groups.emplace_back(decay, std::make_unique<AdamWOptions>(AdamWOptions(lr).weight_decay(options_.weight_decay)));
  groups.emplace_back(no_decay, std::make_unique<AdamWOptions>(AdamWOptions(lr).weight_decay(0.0)));
  optimizer_ = std::make_unique<torch::optim::AdamW>(groups, AdamWOptions(lr).weight_decay(options_.weight_decay));
}

double Trainer::learningRateAt(int epoch) const {
  const double factor = std::max(std::pow(options_.lr_decay, epoch / options_.lr_decay_epochs), options_.lr_floor);
  return options_.learning_rate * factor;
}

void Trainer::setLearningRate(double lr) {
  for (auto& group : optimizer_->param_groups())
    static_cast<torch::optim::AdamWOptions&>(group.options()).lr(lr);
}

LossResult Trainer::step(const TrainingBatch& batch) {
  network_->train();
  optimizer_->zero_grad();
  StepTimes times;
  auto started = std::chrono::steady_clock::now();
  const NetworkOutput output = network_->forward(batch.input);
  times.forward = secondsSince(started);
  started = std::chrono::steady_clock::now();
  LossResult loss = computeLosses(output, batch.truth, options_.loss);
  times.matching = loss.matching_seconds;
  times.losses = secondsSince(started) - loss.matching_seconds;
  started = std::chrono::steady_clock::now();
  const double value = loss.total.item<double>();
  if (!std::isfinite(value))
    throw ModelError("training diverged at step " + std::to_string(step_) +
                     ": the loss is not finite; lower the learning rate or resume from an earlier checkpoint");
  loss.total.backward();
  if (options_.grad_clip > 0.0) torch::nn::utils::clip_grad_norm_(network_->parameters(), options_.grad_clip);
  optimizer_->step();
  times.backward = secondsSince(started);
  last_step_times_ = times;
  ++step_;
  return loss;
}

std::pair<LossResult, PlaneMetrics> Trainer::evaluate(const TrainingBatch& batch) {
  torch::NoGradGuard no_grad;
  network_->eval();
  const NetworkOutput output = network_->forward(batch.input);
  LossResult loss = computeLosses(output, batch.truth, options_.loss);
  PlaneMetrics metrics = planeMetrics(output, batch.truth, loss.matching, options_.loss, options_.confidence_threshold);
  network_->train();
  return {std::move(loss), metrics};
}

void Trainer::saveCheckpoint(const std::string& path) {
  torch::serialize::OutputArchive state;
  torch::serialize::OutputArchive optimizer_state;
  optimizer_->save(optimizer_state);
  state.write("optimizer", optimizer_state);
  state.write("trainer_epoch", scalarTensor(static_cast<std::int64_t>(epoch_)));
  state.write("trainer_epoch_batch", scalarTensor(static_cast<std::int64_t>(epoch_batch_)));
  state.write("trainer_step", scalarTensor(step_));
  state.write("trainer_train_samples", scalarTensor(static_cast<std::int64_t>(train_samples_)));
  state.write("trainer_seed", scalarTensor(static_cast<std::int64_t>(options_.seed)));
  state.write("trainer_batch_size", scalarTensor(static_cast<std::int64_t>(options_.batch_size)));
  state.write("trainer_best_val", scalarTensor(has_best_ ? best_val_ : std::numeric_limits<double>::quiet_NaN()));
  state.write("trainer_epoch_loss_sum", scalarTensor(epoch_loss_sum_));
  const auto& names = LossConfig::termNames();
  auto sums = torch::full({static_cast<std::int64_t>(names.size())}, std::numeric_limits<double>::quiet_NaN(), torch::kDouble);
  for (std::size_t i = 0; i < names.size(); ++i) {
    const auto it = epoch_term_sums_.find(names[i]);
    if (it != epoch_term_sums_.end()) sums[static_cast<std::int64_t>(i)] = it->second;
  }
  state.write("trainer_epoch_term_sums", sums);
  {
    auto generator = at::detail::getDefaultCPUGenerator();
    std::lock_guard<std::mutex> lock(generator.mutex());
    state.write("trainer_rng_state", generator.get_state());
  }
  paco::saveCheckpoint(path, network_, &state);
}

void Trainer::startFrom(const std::string& model_path) { startFrom(paco::loadCheckpoint(model_path)); }

void Trainer::startFrom(const LoadedCheckpoint& model) {
  options_.model = model.config;
  network_ = model.network;
  network_->train();
  epoch_ = 0;
  epoch_batch_ = 0;
  step_ = 0;
  best_val_ = 0.0;
  has_best_ = false;
  epoch_loss_sum_ = 0.0;
  epoch_term_sums_.clear();
  // The optimizer held the parameters of the network built in the constructor.
  makeOptimizer();
}

void Trainer::resume(const std::string& checkpoint_path) {
  LoadedCheckpoint checkpoint = paco::loadCheckpoint(checkpoint_path);
  if (!checkpoint.training_state)
    throw ModelError("'" + checkpoint_path + "' holds a model but no training state, so the run cannot be resumed; " +
                     "train from scratch, or pass last.pt of a paco_train run");
  options_.model = checkpoint.config;
  network_ = checkpoint.network;
  network_->train();
  auto& state = *checkpoint.training_state;
  try {
    torch::Tensor t;
    // A fresh tensor per key: read() into a defined tensor would resize its storage in place.
    auto read = [&](const char* key) {
      t = torch::Tensor();
      state.read(key, t);
    };
    read("trainer_epoch");
    epoch_ = static_cast<int>(t.item<std::int64_t>());
    read("trainer_epoch_batch");
    epoch_batch_ = static_cast<std::size_t>(t.item<std::int64_t>());
    read("trainer_step");
    step_ = t.item<std::int64_t>();
    t = torch::Tensor();
    train_samples_ = state.try_read("trainer_train_samples", t) ? static_cast<std::size_t>(t.item<std::int64_t>()) : 0;
    read("trainer_seed");
    options_.seed = static_cast<std::uint64_t>(t.item<std::int64_t>());
    read("trainer_batch_size");
    options_.batch_size = static_cast<int>(t.item<std::int64_t>());
    read("trainer_best_val");
    best_val_ = t.item<double>();
    has_best_ = std::isfinite(best_val_);
    read("trainer_epoch_loss_sum");
    epoch_loss_sum_ = t.item<double>();
    read("trainer_epoch_term_sums");
    epoch_term_sums_.clear();
    const auto& names = LossConfig::termNames();
    for (std::size_t i = 0; i < names.size() && i < static_cast<std::size_t>(t.numel()); ++i) {
      const double v = t[static_cast<std::int64_t>(i)].item<double>();
      if (std::isfinite(v)) epoch_term_sums_[names[i]] = v;
    }
    makeOptimizer();
    torch::serialize::InputArchive optimizer_state;
    state.read("optimizer", optimizer_state);
    optimizer_->load(optimizer_state);
    setLearningRate(learningRateAt(epoch_));
    read("trainer_rng_state");
    auto generator = at::detail::getDefaultCPUGenerator();
    std::lock_guard<std::mutex> lock(generator.mutex());
    generator.set_state(t);
  } catch (const c10::Error& e) {
    throw ModelError("'" + checkpoint_path + "' has an incomplete or incompatible training state (" +
                     std::string(e.what_without_backtrace()) + "); start a new run instead of --resume");
  }
}

void Trainer::appendLog(const EpochRecord& r) {
  if (options_.checkpoint_dir.empty()) return;
  const std::string path = (std::filesystem::path(options_.checkpoint_dir) / "training_log.csv").string();
  const bool fresh = !std::filesystem::exists(path);
  std::ofstream out(path, std::ios::app);
  if (!out) throw IoError("cannot append to the training log '" + path + "'; check the folder's permissions");
  const auto& names = LossConfig::termNames();
  if (fresh) {
    out << "epoch,step,lr,train_loss";
    for (const auto& n : names) out << ",train_" << n;
    out << ",val_loss,val_recall,val_precision,val_nc_prim,epoch_seconds,samples_per_second\n";
  }
  out << r.epoch << ',' << r.step << ',' << std::setprecision(8) << r.learning_rate << ',' << r.train_loss;
  for (const auto& n : names) {
    const auto it = r.train_terms.find(n);
    out << ',';
    if (it != r.train_terms.end()) out << it->second;
  }
  out << ',' << r.val_loss << ',' << r.val_metrics.recall << ',' << r.val_metrics.precision << ','
      << r.val_metrics.nc_prim << ',' << r.seconds << ',' << r.samples_per_second << '\n';
  if (!out) throw IoError("could not write the training log '" + path + "' (disk full?)");
}

std::vector<EpochRecord> Trainer::fit(const BatchSource& train, const BatchSource& val) {
  if (train.size == 0 || !train.load)
    throw InvalidInputError("Trainer::fit: no training samples; check the dataset folder and --limit-train");
  interrupted_ = false;
  const std::size_t resumed_train_samples = train_samples_;  // 0 unless resumed from a run that recorded it
  train_samples_ = train.size;
  const auto B = static_cast<std::size_t>(options_.batch_size);
  const std::size_t batches_per_epoch = (train.size + B - 1) / B;
  const std::string folder = options_.checkpoint_dir;
  auto save = [&](const std::string& name) {
    if (!folder.empty()) saveCheckpoint((std::filesystem::path(folder) / name).string());
  };
  std::vector<EpochRecord> records;
  while (epoch_ < options_.epochs) {
    const auto started = std::chrono::steady_clock::now();
    const double lr = learningRateAt(epoch_);
    setLearningRate(lr);
    // Resumed after the last batch of an epoch (stopped before its validation): the epoch goes on to
    // validation, rather than training every batch again. Past the end, or at it with other data
    // (fewer batches than the run had), the epoch starts over.
    if (epoch_batch_ > batches_per_epoch ||
        (epoch_batch_ == batches_per_epoch && resumed_train_samples != train.size))
      epoch_batch_ = 0;
    const auto order = epochOrder(train.size, options_.seed, epoch_);
    std::vector<std::vector<std::size_t>> batches;
    std::vector<std::uint64_t> seeds;
    std::size_t remaining_samples = 0;
    for (std::size_t b = epoch_batch_; b < batches_per_epoch; ++b) {
      const std::size_t begin = b * B, end = std::min(train.size, begin + B);
      batches.emplace_back(order.begin() + static_cast<std::ptrdiff_t>(begin), order.begin() + static_cast<std::ptrdiff_t>(end));
      seeds.push_back(batchSeed(options_.seed, kTrainStream, static_cast<std::uint64_t>(epoch_), b));
      remaining_samples += end - begin;
    }
    std::optional<ProgressBar> bar;
    if (options_.show_progress)
      bar.emplace("epoch " + std::to_string(epoch_ + 1) + "/" + std::to_string(options_.epochs), remaining_samples);
    std::size_t samples_done = 0;
    StepTimes epoch_times;
    {
      Prefetcher loader(train, std::move(batches), std::move(seeds), static_cast<std::size_t>(options_.prefetch));
      for (;;) {
        const auto wait_started = std::chrono::steady_clock::now();
        auto batch = loader.next();
        const double waited = secondsSince(wait_started);
        if (!batch) break;
        const LossResult loss = step(*batch);
        StepTimes times = last_step_times_;
        times.load_wait = waited;
        epoch_times.add(times);
        ++epoch_batch_;
        samples_done += static_cast<std::size_t>(batch->size());
        epoch_loss_sum_ += loss.total.item<double>();
        for (const auto& [name, value] : loss.terms) epoch_term_sums_[name] += value;
        if (bar) {
          std::string status = "loss " + formatNumber(loss.total.item<double>());
          for (const auto& [name, value] : loss.terms) status += " " + shortName(name) + " " + formatNumber(value, 3);
          status += " | " + epoch_times.summary();
          bar->setStatus(status);
          bar->advance(static_cast<std::size_t>(batch->size()));
        }
        if (options_.on_step) options_.on_step(step_);
        if (options_.checkpoint_every > 0 && step_ % options_.checkpoint_every == 0 && epoch_batch_ < batches_per_epoch)
          save("last.pt");
        if (interruptRequested()) {
          interrupted_ = true;
          break;
        }
      }
    }
    if (bar) bar->finish();
    const double train_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (interrupted_) {
      save("last.pt");
      return records;
    }
    EpochRecord record;
    record.epoch = epoch_ + 1;
    record.learning_rate = lr;
    const double batches_done = static_cast<double>(std::max<std::size_t>(epoch_batch_, 1));
    record.train_loss = epoch_loss_sum_ / batches_done;
    for (const auto& [name, sum] : epoch_term_sums_) record.train_terms[name] = sum / batches_done;
    // Resumed straight into the validation, the epoch trained nothing in this run: no rate.
    record.samples_per_second = samples_done > 0 && train_seconds > 0 ? samples_done / train_seconds
                                                                       : std::numeric_limits<double>::quiet_NaN();
    record.step_times = epoch_times;
    record.val_loss = std::numeric_limits<double>::quiet_NaN();
    if (val.size > 0 && val.load) {
      std::vector<std::vector<std::size_t>> val_batches;
      std::vector<std::uint64_t> val_seeds;
      for (std::size_t begin = 0; begin < val.size; begin += B) {
        std::vector<std::size_t> indices;
        for (std::size_t i = begin; i < std::min(val.size, begin + B); ++i) indices.push_back(i);
        val_seeds.push_back(batchSeed(options_.seed, kValStream, 0, val_batches.size()));
        val_batches.push_back(std::move(indices));
      }
      std::optional<ProgressBar> val_bar;
      if (options_.show_progress) val_bar.emplace("validate", val.size);
      Prefetcher loader(val, std::move(val_batches), std::move(val_seeds), static_cast<std::size_t>(options_.prefetch));
      double loss_sum = 0.0;
      std::size_t count = 0;
      PlaneMetrics metrics;
      while (auto batch = loader.next()) {
        const auto [loss, batch_metrics] = evaluate(*batch);
        loss_sum += loss.total.item<double>() * batch->size();
        count += static_cast<std::size_t>(batch->size());
        metrics.accumulate(batch_metrics);
        if (val_bar) val_bar->advance(static_cast<std::size_t>(batch->size()));
        if (interruptRequested()) {
          interrupted_ = true;
          break;
        }
      }
      if (val_bar) val_bar->finish();
      if (interrupted_) {
        // Every batch is trained, the validation is not done: the resumed run validates this
        // epoch (epoch_batch_ stays at the end), so that no epoch is logged without its loss and
        // best.pt is chosen as in an uninterrupted run.
        save("last.pt");
        return records;
      }
      if (count > 0) {
        record.val_loss = loss_sum / static_cast<double>(count);
        record.val_metrics = metrics;
      }
    }
    // The epoch is done: the next one starts from a clean slate.
    ++epoch_;
    epoch_batch_ = 0;
    epoch_loss_sum_ = 0.0;
    epoch_term_sums_.clear();
    record.step = step_;
    record.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (std::isfinite(record.val_loss) && (!has_best_ || record.val_loss < best_val_)) {
      best_val_ = record.val_loss;
      has_best_ = true;
      save("best.pt");
    }
    save("last.pt");
    appendLog(record);
    records.push_back(record);
  }
  return records;
}

#if PACO_HAVE_DATA
BatchSource datasetSource(std::shared_ptr<const paco::data::Dataset> dataset, paco::data::Split split,
                          const CollateOptions& options, std::size_t limit) {
  return datasetSource(std::vector<std::shared_ptr<const paco::data::Dataset>>{std::move(dataset)}, split, options,
                       limit);
}

std::vector<std::pair<std::size_t, std::size_t>> evenlySpacedSamples(
    const std::vector<std::shared_ptr<const paco::data::Dataset>>& datasets, paco::data::Split split,
    std::size_t limit) {
  // (dataset, sample) of each position of the concatenation.
  std::vector<std::pair<std::size_t, std::size_t>> all;
  for (std::size_t d = 0; d < datasets.size(); ++d) {
    if (!datasets[d]) throw paco::InvalidInputError("datasetSource: dataset " + std::to_string(d) + " is null");
    for (std::size_t i = 0; i < datasets[d]->size(split); ++i) all.emplace_back(d, i);
  }
  const std::size_t total = all.size();
  const std::size_t count = limit > 0 ? std::min(limit, total) : total;
  std::vector<std::pair<std::size_t, std::size_t>> chosen(count);
  for (std::size_t i = 0; i < count; ++i) chosen[i] = all[count == total ? i : i * total / count];
  return chosen;
}

BatchSource datasetSource(std::vector<std::shared_ptr<const paco::data::Dataset>> datasets, paco::data::Split split,
                          const CollateOptions& options, std::size_t limit) {
  std::vector<std::pair<std::size_t, std::size_t>> chosen = evenlySpacedSamples(datasets, split, limit);
  BatchSource source;
  source.size = chosen.size();
  source.load = [datasets = std::move(datasets), split, options, chosen = std::move(chosen)](
                    const std::vector<std::size_t>& indices, std::uint64_t seed) {
    std::vector<paco::data::Sample> samples;
    samples.reserve(indices.size());
    for (std::size_t i : indices) {
      const auto& [d, sample] = chosen.at(i);
      samples.push_back(datasets[d]->load(split, sample));
    }
    return collate(samples, options, seed);
  };
  return source;
}
#endif

}  // namespace paco::completion
