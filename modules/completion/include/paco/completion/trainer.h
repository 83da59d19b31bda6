#pragma once
// Usage:
//   paco::completion::TrainerOptions options;  options.checkpoint_dir = "runs/cpu";  options.epochs = 50;
//   paco::completion::Trainer trainer(options);                 // or trainer.resume("runs/cpu/last.pt")
//   trainer.fit(train_source, val_source);                       // sources: datasetSource(...) or your own
#include <paco/completion/batch.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/losses.h>
#include <paco/completion/network.h>
#include <paco/encoding/model_config.h>

#include <torch/torch.h>

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace paco::completion {

/// Everything a training run needs besides the data.
struct TrainerOptions {
  ModelConfig model = ModelConfig::preset("cpu");  ///< network sizes (ignored by resume(): the checkpoint's)
  LossConfig loss;                                 ///< loss terms, weights and switches
  int epochs = 100;              ///< train until this many epochs are done (counting resumed ones)
  int batch_size = 16;           ///< samples per step (>= 1)
  double learning_rate = 1e-4;   ///< base AdamW learning rate
  double weight_decay = 5e-4;    ///< AdamW decay of weight matrices; none on biases and norms (1-D tensors)
  /// lr(epoch) = learning_rate · max(lr_decay^(epoch / lr_decay_epochs), lr_floor).
  double lr_decay = 0.9;
  double lr_decay_epochs = 21.0;
  double lr_floor = 0.02;
  double grad_clip = 10.0;       ///< gradient-norm clipping threshold (<= 0: off)
  std::uint64_t seed = 1;        ///< drives weight init, data order, re-sampling and augmentation
  int prefetch = 3;              ///< batches the background loader prepares ahead (>= 1)
  /// Also save last.pt every this many steps inside an epoch (0: only at epoch ends and on
  /// interrupt), so that a killed process loses at most that many steps.
  int checkpoint_every = 0;
  /// Folder for last.pt, best.pt and training_log.csv (created); empty: nothing is written.
  std::string checkpoint_dir;
  bool show_progress = true;     ///< a progress bar per epoch on stderr
  double confidence_threshold = 0.7;  ///< for the validation plane metrics
  /// Called after every optimisation step (tests use it to interrupt at a given step).
  std::function<void(std::int64_t step)> on_step;
};

/// Where batches come from: `size` samples, and a loader that collates the samples with the
/// given indices. The loader is called from a background thread; the same (indices, seed) must
/// give the same batch so that runs are repeatable.
struct BatchSource {
  std::size_t size = 0;
  std::function<TrainingBatch(const std::vector<std::size_t>& indices, std::uint64_t seed)> load;
};

/// Where the wall time of training steps went, summed over steps (seconds).
struct StepTimes {
  double load_wait = 0.0;  ///< waiting for the background loader (0 when it keeps up)
  double forward = 0.0;    ///< network forward pass
  double matching = 0.0;   ///< Hungarian matching (cost matrices + assignment)
  double losses = 0.0;     ///< loss terms after matching
  double backward = 0.0;   ///< backward pass, clipping and the AdamW update
  void add(const StepTimes& other);
  /// "fwd 38% match 12% ..." shares of the total, for progress lines.
  std::string summary() const;
};

/// Numbers of one finished epoch (also the rows of training_log.csv).
struct EpochRecord {
  int epoch = 0;                          ///< 1-based number of the finished epoch
  std::int64_t step = 0;                  ///< optimisation steps done so far
  double learning_rate = 0.0;
  double train_loss = 0.0;                ///< mean total loss over the epoch's steps
  std::map<std::string, double> train_terms;  ///< mean of each weighted term
  double val_loss = 0.0;                  ///< NaN without validation data
  PlaneMetrics val_metrics;
  double seconds = 0.0;                   ///< wall time of the epoch (training + validation)
  double samples_per_second = 0.0;        ///< training throughput in this run (NaN: no sample trained in it)
  StepTimes step_times;                   ///< where this call's training time went
};

/// AdamW training of a PacoNetwork with Hungarian-matched losses, background data loading,
/// validation every epoch, checkpoints (last + best by validation loss) that resume exactly, a
/// CSV log of the curves, and Ctrl-C handling (paco::interruptRequested(): the current state is
/// saved to last.pt and fit() returns).
class Trainer {
 public:
  /// A fresh network from options.model, initialised from options.seed. Throws
  /// InvalidInputError on bad options.
  explicit Trainer(TrainerOptions options);
  ~Trainer();

  /// Continues the run saved in `checkpoint_path`: network weights, optimizer state, epoch,
  /// position inside the epoch, step, best validation loss and the random generator state.
  /// Throws paco::ModelError when the file is not a training checkpoint.
  void resume(const std::string& checkpoint_path);

  /// Starts a new run from the weights of a model file (an exported model such as
  /// models/paco_cpu.pt, or any checkpoint): the network configuration and weights come from the
  /// file, the optimizer, epoch count and step start afresh. This is how training continues
  /// across machines that keep only the shipped model. Throws paco::ModelError on a bad file.
  void startFrom(const std::string& model_path);
  /// The same, from a model already loaded (e.g. checked before any output folder is made).
  void startFrom(const LoadedCheckpoint& model);

  /// One optimisation step on a batch (forward, matching, losses, backward, clipping, AdamW).
  LossResult step(const TrainingBatch& batch);
  /// Loss and plane metrics of a batch without gradients (network in eval mode).
  std::pair<LossResult, PlaneMetrics> evaluate(const TrainingBatch& batch);

  /// Trains until options.epochs are done or an interrupt is requested; validates after every
  /// epoch when `val.size > 0`. Returns the records of the epochs finished by this call.
  std::vector<EpochRecord> fit(const BatchSource& train, const BatchSource& val);
  /// True when the last fit() stopped on an interrupt (state saved when checkpoint_dir is set).
  bool interrupted() const { return interrupted_; }

  /// Writes network + config + training state to `path` (atomically, via paco::saveCheckpoint).
  void saveCheckpoint(const std::string& path);

  PacoNetwork& network() { return network_; }
  const TrainerOptions& options() const { return options_; }
  int epoch() const { return epoch_; }              ///< finished epochs
  std::int64_t globalStep() const { return step_; } ///< optimisation steps done
  std::size_t epochBatch() const { return epoch_batch_; }  ///< batches done in the current epoch
  /// Training samples per epoch of the run: set by fit(), read back by resume() (0 from a
  /// checkpoint older than this field). A resumed run continues exactly only with as many.
  std::size_t trainSamples() const { return train_samples_; }
  double bestValidationLoss() const { return best_val_; }
  /// The scheduled learning rate of an epoch (0-based epoch index).
  double learningRateAt(int epoch) const;
  torch::optim::AdamW& optimizer() { return *optimizer_; }
  /// Times of the last step() (load_wait is filled in by fit()).
  const StepTimes& lastStepTimes() const { return last_step_times_; }

 private:
  void makeOptimizer();
  void setLearningRate(double lr);
  void appendLog(const EpochRecord& record);

  TrainerOptions options_;
  PacoNetwork network_{nullptr};
  std::unique_ptr<torch::optim::AdamW> optimizer_;
  int epoch_ = 0;
  std::size_t epoch_batch_ = 0;
  std::size_t train_samples_ = 0;
  std::int64_t step_ = 0;
  double best_val_ = 0.0;
  bool has_best_ = false;
  bool interrupted_ = false;
  StepTimes last_step_times_;
  // Running sums of the current (possibly resumed) epoch, so an interrupted epoch reports right.
  double epoch_loss_sum_ = 0.0;
  std::map<std::string, double> epoch_term_sums_;
};

/// The order of the training samples in an epoch: a permutation of [0, n) from (seed, epoch).
std::vector<std::size_t> epochOrder(std::size_t n, std::uint64_t seed, int epoch);

#if PACO_HAVE_DATA
/// A BatchSource over one split of a dataset, collated with `options`. Validation sources
/// should pass augmentation-free options.
BatchSource datasetSource(std::shared_ptr<const paco::data::Dataset> dataset, paco::data::Split split,
                          const CollateOptions& options, std::size_t limit = 0);
/// The (dataset, sample) indices a source over one split of `datasets` uses: every sample, one
/// dataset after another, or `limit` (> 0) of them evenly spaced over the whole, so that they
/// still cover many parts and each dataset keeps its share. Throws InvalidInputError for a null
/// dataset.
std::vector<std::pair<std::size_t, std::size_t>> evenlySpacedSamples(
    const std::vector<std::shared_ptr<const paco::data::Dataset>>& datasets, paco::data::Split split,
    std::size_t limit = 0);
/// A BatchSource over one split of several datasets, one after another (e.g. inputs cut by
/// distance and inputs seen by one scanner, to train one model on both). A limit takes evenly
/// spaced samples of the whole, so each dataset keeps its share.
BatchSource datasetSource(std::vector<std::shared_ptr<const paco::data::Dataset>> datasets, paco::data::Split split,
                          const CollateOptions& options, std::size_t limit = 0);
#endif

}  // namespace paco::completion
