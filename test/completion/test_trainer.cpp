#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/common/surface_mesh.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/hidden_extent.h>
#include <paco/completion/trainer.h>

#include <gtest/gtest.h>
#include <shapes.h>
#include <test_support.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <csignal>
#include <limits>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numeric>

using namespace paco::completion;

namespace {

// A network small enough to train in seconds on one core.
paco::ModelConfig tinyConfig() {
  paco::ModelConfig c = paco::ModelConfig::preset("cpu");
  c.name = "tiny";
  c.num_centres = 32;
  c.knn_k = 8;
  c.input_embedding = 8;
  c.edge_conv_widths = {16, 32};
  c.group_norm_groups = 4;
  c.width = 32;
  c.heads = 2;
  c.mlp_ratio = 2.0;
  c.position_hidden = 16;
  c.encoder_depth = 0;
  c.encoder_graph_k = 0;
  c.normal_hidden = 16;
  c.plane_slots = 8;
  c.global_width = 64;
  c.generated_queries = 10;
  c.kept_queries = 10;
  c.decoder_depth = 1;
  c.points_per_plane = 32;
  c.distributor_hidden = 64;
  return c;
}

// Test shapes centred at the origin with a bounding-box diagonal near 1; one plane per face.
paco::SurfaceMesh shape(int which) {
  if (which % 2 == 0) return paco::test::makeBox({-0.4, -0.3, -0.2}, {0.4, 0.3, 0.2});
  paco::SurfaceMesh bracket = paco::test::makeLBracket(0.6, 0.25, 0.4);
  paco::test::transformMesh(bracket, Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.3, -0.3, -0.2));
  return bracket;
}

struct SyntheticSample {
  torch::Tensor points, normals, labels;           // input
  torch::Tensor gt_points, gt_labels, plane_normals, plane_offsets;
};

// GT: `gt_count` surface points; input: `input_count` points of the part with x < 0.15 (the
// rest is "missing"), labelled with their face.
SyntheticSample makeSample(int which, std::uint64_t seed, int input_count = 384, int gt_count = 768) {
  const paco::SurfaceMesh mesh = shape(which);
  SyntheticSample s;
  const auto gt = paco::sampleSurface(mesh, static_cast<std::size_t>(gt_count), seed);
  s.gt_points = torch::empty({gt_count, 3});
  s.gt_labels = torch::empty({gt_count}, torch::kLong);
  for (int i = 0; i < gt_count; ++i) {
    for (int k = 0; k < 3; ++k) s.gt_points[i][k] = gt.points[i][k];
    s.gt_labels[i] = static_cast<std::int64_t>(gt.faces[i]);
  }
  const auto faces = static_cast<std::int64_t>(mesh.faces.size());
  s.plane_normals = torch::empty({faces, 3});
  s.plane_offsets = torch::empty({faces});
  for (std::int64_t f = 0; f < faces; ++f) {
    const Eigen::Vector3d n = paco::faceNormal(mesh, static_cast<std::size_t>(f));
    for (int k = 0; k < 3; ++k) s.plane_normals[f][k] = n[k];
    s.plane_offsets[f] = n.dot(mesh.vertices[mesh.faces[f][0]]);
  }
  const auto dense = paco::sampleSurface(mesh, 4 * static_cast<std::size_t>(input_count), seed + 1);
  std::vector<std::size_t> kept;
  for (std::size_t i = 0; i < dense.points.size(); ++i)
    if (dense.points[i].x() < 0.15) kept.push_back(i);
  const auto pick = resampleIndices(static_cast<std::int64_t>(kept.size()), input_count, seed + 2);
  s.points = torch::empty({input_count, 3});
  s.normals = torch::empty({input_count, 3});
  s.labels = torch::empty({input_count}, torch::kLong);
  for (int i = 0; i < input_count; ++i) {
    const std::size_t j = kept[static_cast<std::size_t>(pick[i])];
    for (int k = 0; k < 3; ++k) {
      s.points[i][k] = dense.points[j][k];
      s.normals[i][k] = dense.normals[j][k];
    }
    s.labels[i] = static_cast<std::int64_t>(dense.faces[j]);
  }
  return s;
}

TrainingBatch makeBatch(const std::vector<SyntheticSample>& samples) {
  std::int64_t max_planes = 0;
  for (const auto& s : samples) max_planes = std::max(max_planes, s.plane_normals.size(0));
  std::vector<torch::Tensor> p, n, l, gp, gl, pn, po, pm;
  for (const auto& s : samples) {
    p.push_back(s.points);
    n.push_back(s.normals);
    l.push_back(s.labels);
    gp.push_back(s.gt_points);
    gl.push_back(s.gt_labels);
    const auto count = s.plane_normals.size(0);
    pn.push_back(torch::cat({s.plane_normals, torch::zeros({max_planes - count, 3})}));
    po.push_back(torch::cat({s.plane_offsets, torch::zeros({max_planes - count})}));
    pm.push_back(torch::arange(max_planes) < count);
  }
  TrainingBatch batch;
  batch.input.points = torch::stack(p);
  batch.input.normals = torch::stack(n);
  batch.input.labels = torch::stack(l);
  batch.truth.points = torch::stack(gp);
  batch.truth.labels = torch::stack(gl);
  batch.truth.normals = torch::stack(pn);
  batch.truth.offsets = torch::stack(po);
  batch.truth.mask = torch::stack(pm);
  return batch;
}

// A source of `count` synthetic samples (box and bracket, different samplings).
BatchSource syntheticSource(std::size_t count) {
  BatchSource source;
  source.size = count;
  source.load = [](const std::vector<std::size_t>& indices, std::uint64_t) {
    std::vector<SyntheticSample> samples;
    for (std::size_t i : indices) samples.push_back(makeSample(static_cast<int>(i), 100 + i));
    return makeBatch(samples);
  };
  return source;
}

TrainerOptions tinyOptions(const std::string& folder) {
  TrainerOptions options;
  options.model = tinyConfig();
  options.batch_size = 2;
  options.learning_rate = 1e-3;
  options.seed = 5;
  options.show_progress = false;
  options.checkpoint_dir = folder;
  return options;
}

struct ThreadsGuard {  // deterministic arithmetic for the comparisons below
  int previous = torch::get_num_threads();
  ThreadsGuard() { torch::set_num_threads(1); }
  ~ThreadsGuard() { torch::set_num_threads(previous); }
};

// Largest absolute difference between the weights of two trainers' networks (infinite when
// their parameter lists differ).
double maxWeightDifference(Trainer& a, Trainer& b) {
  const auto x = a.network()->parameters();
  const auto y = b.network()->parameters();
  if (x.size() != y.size()) return std::numeric_limits<double>::infinity();
  double largest = 0.0;
  for (std::size_t i = 0; i < x.size(); ++i) largest = std::max(largest, (x[i] - y[i]).abs().max().item<double>());
  return largest;
}

}  // namespace

TEST(Trainer, TinyModelOverfitsOneBatch) {
  ThreadsGuard threads;
  const auto start = std::chrono::steady_clock::now();
  TrainerOptions options = tinyOptions("");
  options.learning_rate = 2e-3;
  Trainer trainer(options);
  const TrainingBatch batch = makeBatch({makeSample(0, 1), makeSample(1, 2)});
  const double initial = trainer.step(batch).total.item<double>();
  double recent = initial;
  std::vector<double> history;
  // A fixed budget (not "until 5x"), so the test also shows the loss keeps falling.
  for (int i = 0; i < 150; ++i) history.push_back(trainer.step(batch).total.item<double>());
  recent = 0.0;
  for (std::size_t k = history.size() - 10; k < history.size(); ++k) recent += history[k] / 10.0;
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  RecordProperty("initial_loss", std::to_string(initial));
  RecordProperty("final_loss", std::to_string(recent));
  RecordProperty("steps", static_cast<int>(history.size()));
  EXPECT_LT(recent * 5.0, initial) << "initial " << initial << ", last-10 mean " << recent << " after "
                                   << history.size() << " steps";
  RecordProperty("seconds", std::to_string(seconds));
  // The trained selector recognises the GT planes of the batch.
  const auto [loss, metrics] = trainer.evaluate(batch);
  RecordProperty("recall", std::to_string(metrics.recall));
  RecordProperty("nc_prim", std::to_string(metrics.nc_prim));
  EXPECT_GT(metrics.nc_prim, 0.9);
  EXPECT_LT(loss.total.item<double>() * 5.0, initial);
}

TEST(Trainer, LearningRateScheduleAndParameterGroups) {
  Trainer trainer(tinyOptions(""));
  EXPECT_DOUBLE_EQ(trainer.learningRateAt(0), 1e-3);
  EXPECT_NEAR(trainer.learningRateAt(21), 1e-3 * 0.9, 1e-15);
  EXPECT_NEAR(trainer.learningRateAt(42), 1e-3 * 0.81, 1e-15);
  EXPECT_NEAR(trainer.learningRateAt(100000), 1e-3 * 0.02, 1e-15);  // floor
  auto& groups = trainer.optimizer().param_groups();
  ASSERT_EQ(groups.size(), 2u);
  const auto& decay = static_cast<torch::optim::AdamWOptions&>(groups[0].options());
  const auto& no_decay = static_cast<torch::optim::AdamWOptions&>(groups[1].options());
  EXPECT_DOUBLE_EQ(decay.weight_decay(), 5e-4);
  EXPECT_DOUBLE_EQ(no_decay.weight_decay(), 0.0);
  for (const auto& p : groups[0].params()) EXPECT_GE(p.dim(), 2);
  for (const auto& p : groups[1].params()) EXPECT_LE(p.dim(), 1);
  EXPECT_FALSE(groups[1].params().empty());
}

TEST(Trainer, ResumeContinuesExactlyAsAnUninterruptedRun) {
  ThreadsGuard threads;
  paco::test::TempDir dir;
  const BatchSource train = syntheticSource(6);  // 3 batches of 2 per epoch
  const BatchSource val = syntheticSource(2);

  TrainerOptions straight_options = tinyOptions(dir.file("straight"));
  straight_options.epochs = 2;
  Trainer straight(straight_options);
  const auto straight_records = straight.fit(train, val);
  ASSERT_EQ(straight_records.size(), 2u);
  EXPECT_FALSE(straight.interrupted());
  EXPECT_EQ(straight.globalStep(), 6);

  // Same run, interrupted after step 4 (inside epoch 2), after step 6 (epoch 2's last batch, before
  // its validation), or in epoch 2's validation (step 7: none), then resumed by a new trainer. The
  // second must neither train epoch 2 again nor log it without its validation loss.
  for (const std::int64_t interrupt_at : {4, 6, 7}) {
    SCOPED_TRACE(interrupt_at);
    const std::string folder = dir.file("broken" + std::to_string(interrupt_at));
    TrainerOptions broken_options = tinyOptions(folder);
    broken_options.epochs = 2;
    broken_options.on_step = [interrupt_at](std::int64_t step) {
      if (step == interrupt_at) paco::setInterruptRequested(true);
    };
    BatchSource interrupted_val = val;  // one batch per validation; the second is epoch 2's
    auto val_batches = std::make_shared<int>(0);
    interrupted_val.load = [&val, val_batches, interrupt_at](const std::vector<std::size_t>& indices,
                                                             std::uint64_t seed) {
      if (++*val_batches == 2 && interrupt_at == 7) paco::setInterruptRequested(true);
      return val.load(indices, seed);
    };
    {
      Trainer first(broken_options);
      const auto records = first.fit(train, interrupted_val);
      paco::setInterruptRequested(false);
      EXPECT_TRUE(first.interrupted());
      EXPECT_EQ(records.size(), 1u);
      EXPECT_EQ(first.globalStep(), std::min<std::int64_t>(interrupt_at, 6));
    }
    broken_options.on_step = nullptr;
    broken_options.seed = 999;  // ignored: the checkpoint's seed drives the data order
    Trainer second(broken_options);
    second.resume(folder + "/last.pt");
    EXPECT_EQ(second.epoch(), 1);
    EXPECT_EQ(second.epochBatch(), static_cast<std::size_t>(std::min<std::int64_t>(interrupt_at, 6) - 3));
    EXPECT_EQ(second.globalStep(), std::min<std::int64_t>(interrupt_at, 6));
    EXPECT_EQ(second.trainSamples(), 6u);
    const auto records = second.fit(train, val);
    ASSERT_EQ(records.size(), 1u);
    EXPECT_EQ(second.globalStep(), 6);
    EXPECT_NEAR(records[0].train_loss, straight_records[1].train_loss, 1e-6 * std::abs(straight_records[1].train_loss));
    EXPECT_NEAR(records[0].val_loss, straight_records[1].val_loss, 1e-6 * std::abs(straight_records[1].val_loss));
    // Resumed at the validation, no sample was trained in this run: the rate is unknown, not 0.
    EXPECT_EQ(std::isnan(records[0].samples_per_second), interrupt_at >= 6) << records[0].samples_per_second;

    EXPECT_LT(maxWeightDifference(straight, second), 1e-6);

    // Files: last + best checkpoints and a CSV with a header and one row per finished epoch.
    for (const char* name : {"last.pt", "best.pt", "training_log.csv"})
      EXPECT_TRUE(std::filesystem::exists(folder + "/" + name)) << name;
    std::ifstream csv(folder + "/training_log.csv");
    std::string header, line;
    std::getline(csv, header);
    EXPECT_EQ(header.rfind("epoch,step,lr,train_loss,train_classification", 0), 0u);
    int rows = 0;
    while (std::getline(csv, line)) ++rows;
    EXPECT_EQ(rows, 2);
  }
}

TEST(Trainer, PeriodicCheckpointSurvivesAKilledRun) {
  ThreadsGuard threads;
  paco::test::TempDir dir;
  const BatchSource train = syntheticSource(6);  // 3 batches of 2 per epoch
  const BatchSource val = syntheticSource(2);
  TrainerOptions straight_options = tinyOptions(dir.file("straight"));
  straight_options.epochs = 1;
  Trainer straight(straight_options);
  straight.fit(train, val);

  // The process "dies" in step 3 (an exception, so nothing is saved on the way out); the
  // checkpoint written after step 2 is what remains.
  TrainerOptions killed_options = tinyOptions(dir.file("killed"));
  killed_options.epochs = 1;
  killed_options.checkpoint_every = 2;
  killed_options.on_step = [](std::int64_t step) {
    if (step == 3) throw std::runtime_error("killed");
  };
  {
    Trainer first(killed_options);
    EXPECT_THROW(first.fit(train, val), std::runtime_error);
  }
  killed_options.on_step = nullptr;
  Trainer second(killed_options);
  second.resume(dir.file("killed") + "/last.pt");
  EXPECT_EQ(second.globalStep(), 2);
  EXPECT_EQ(second.epochBatch(), 2u);
  second.fit(train, val);
  EXPECT_EQ(second.globalStep(), 3);
  EXPECT_LT(maxWeightDifference(straight, second), 1e-6);
  TrainerOptions bad = tinyOptions("");
  bad.checkpoint_every = -1;
  EXPECT_THROW(Trainer{bad}, paco::InvalidInputError);
}

TEST(Trainer, ResumeNeedsATrainingCheckpoint) {
  paco::test::TempDir dir;
  Trainer trainer(tinyOptions(""));
  paco::saveCheckpoint(dir.file("model.pt"), trainer.network());
  EXPECT_THROW(trainer.resume(dir.file("model.pt")), paco::ModelError);
  paco::test::writeBytes(dir.file("junk.pt"), "not a checkpoint");
  EXPECT_THROW(trainer.resume(dir.file("junk.pt")), paco::ModelError);
}

TEST(Trainer, StartFromTakesTheWeightsAndConfigOfAModelAndRestartsTheCount) {
  paco::test::TempDir dir;
  TrainerOptions source_options = tinyOptions("");
  source_options.seed = 7;
  Trainer source(source_options);
  paco::saveCheckpoint(dir.file("model.pt"), source.network());
  // A different seed gives different initial weights; startFrom replaces them with the model's.
  TrainerOptions options = tinyOptions("");
  options.seed = 8;
  Trainer trainer(options);
  ASSERT_GT(maxWeightDifference(source, trainer), 1e-3);
  trainer.startFrom(dir.file("model.pt"));
  EXPECT_LT(maxWeightDifference(source, trainer), 1e-9);
  EXPECT_EQ(trainer.epoch(), 0);
  EXPECT_EQ(trainer.globalStep(), 0);
  // The optimizer now drives the loaded parameters: one step moves them.
  trainer.step(makeBatch({makeSample(0, 1), makeSample(1, 2)}));
  EXPECT_GT(maxWeightDifference(source, trainer), 0.0);
  paco::test::writeBytes(dir.file("junk.pt"), "not a model");
  EXPECT_THROW(trainer.startFrom(dir.file("junk.pt")), paco::ModelError);
}

TEST(Trainer, RejectsBadOptionsAndEmptyData) {
  TrainerOptions options = tinyOptions("");
  options.batch_size = 0;
  EXPECT_THROW(Trainer{options}, paco::InvalidInputError);
  Trainer trainer(tinyOptions(""));
  EXPECT_THROW(trainer.fit(BatchSource{}, BatchSource{}), paco::InvalidInputError);
}

TEST(Trainer, LoaderErrorsReachTheCaller) {
  Trainer trainer(tinyOptions(""));
  BatchSource broken;
  broken.size = 4;
  broken.load = [](const std::vector<std::size_t>&, std::uint64_t) -> TrainingBatch {
    throw paco::IoError("part file damaged");
  };
  EXPECT_THROW(trainer.fit(broken, BatchSource{}), paco::IoError);
}

TEST(Trainer, EpochOrderIsASeededPermutation) {
  const auto a = epochOrder(50, 3, 0);
  EXPECT_EQ(a, epochOrder(50, 3, 0));
  EXPECT_NE(a, epochOrder(50, 3, 1));
  EXPECT_NE(a, epochOrder(50, 4, 0));
  auto sorted = a;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) EXPECT_EQ(sorted[i], i);
}

#if PACO_HAVE_DATA
#include <paco/data/builder.h>

namespace {

// A tiny dataset of test shapes named PREFIX-i: `train_parts` training parts and one validation
// part (split by name hash), 2 views of one level each.
void writeTinyDataset(const std::string& folder, const std::string& prefix, int train_parts) {
  paco::data::BuildOptions build;
  build.info.levels = {0};
  build.info.views = 2;
  build.info.input_points = 256;
  build.info.gt_points = 512;
  build.info.dense_points = 2048;
  build.info.source = "test shapes";
  paco::data::DatasetWriter writer(folder, build.info);
  int trained = 0, validated = 0;
  for (int i = 0; i < 200 && (trained < train_parts || validated < 1); ++i) {
    const std::string name = prefix + "-" + std::to_string(i);
    const auto split = paco::data::splitOf(name);
    if (split == paco::data::Split::Test || (split == paco::data::Split::Train && trained >= train_parts) ||
        (split == paco::data::Split::Val && validated >= 1))
      continue;
    (split == paco::data::Split::Train ? trained : validated)++;
    writer.write(paco::data::buildPart(name, shape(i), build));
  }
  ASSERT_EQ(trained, train_parts);
  ASSERT_EQ(validated, 1);
}

}  // namespace

TEST(Trainer, ADatasetSourceOverSeveralDatasetsTakesEachDatasetsSamplesAndSpreadsALimit) {
  paco::test::TempDir dir;
  writeTinyDataset(dir.file("a"), "a", 2);
  writeTinyDataset(dir.file("b"), "b", 3);
  const std::vector<std::shared_ptr<const paco::data::Dataset>> datasets{
      std::make_shared<const paco::data::Dataset>(dir.file("a")),
      std::make_shared<const paco::data::Dataset>(dir.file("b"))};
  CollateOptions options;
  options.input_points = 256;
  options.gt_points = 512;
  const BatchSource both = datasetSource(datasets, paco::data::Split::Train, options);
  ASSERT_EQ(both.size, 10u);  // 2 views of 2 parts, then of 3 parts
  std::vector<std::size_t> all(both.size);
  std::iota(all.begin(), all.end(), 0);
  const TrainingBatch batch = both.load(all, 1);
  ASSERT_EQ(batch.size(), 10);
  for (int i = 0; i < 10; ++i)
    EXPECT_EQ(batch.parts[i].substr(0, 2), i < 4 ? "a-" : "b-") << i << ": " << batch.parts[i];
  // A limit of 2 takes samples 0 and 5: one from each dataset.
  const BatchSource limited = datasetSource(datasets, paco::data::Split::Train, options, 2);
  ASSERT_EQ(limited.size, 2u);
  const TrainingBatch two = limited.load({0, 1}, 1);
  EXPECT_EQ(two.parts[0].substr(0, 2), "a-");
  EXPECT_EQ(two.parts[1].substr(0, 2), "b-");
  // Validation: one part with 2 views in each.
  EXPECT_EQ(datasetSource(datasets, paco::data::Split::Val, options).size, 4u);
  // One dataset alone is the same as the single-dataset source.
  EXPECT_EQ(datasetSource(datasets[1], paco::data::Split::Train, options).size, 6u);
}

TEST(PacoTrainTool, TrainsOneEpochResumesAndRefusesToOverwrite) {
  const std::string tool = paco::test::toolPath("paco_train");
  if (!std::filesystem::exists(tool)) GTEST_SKIP() << "paco_train is not built";
  paco::test::TempDir dir;
  // 3 training parts and 1 validation part.
  writeTinyDataset(dir.file("data"), "shape", 3);
  {
    std::ofstream config(dir.file("tiny.json"));
    config << tinyConfig().toJson();
  }
  const std::string base = tool + " " + dir.file("data") + " -o " + dir.file("run") + " --config " +
                           dir.file("tiny.json") + " --batch 2 --threads 1 --input-points 256 --gt-points 512 --quiet";
  std::string output;
  ASSERT_EQ(paco::test::runCommand(base + " --epochs 1", &output), 0) << output;
  for (const char* name : {"last.pt", "best.pt", "training_log.csv"})
    EXPECT_TRUE(std::filesystem::exists(dir.file("run") + "/" + name)) << name << "\n" << output;
  EXPECT_NE(output.find("6 training, 2 validation samples"), std::string::npos) << output;
  // The folder holds a run: starting again without --resume is refused.
  EXPECT_NE(paco::test::runCommand(base + " --epochs 1", &output), 0);
  EXPECT_NE(output.find("--resume"), std::string::npos) << output;
  ASSERT_EQ(paco::test::runCommand(base + " --epochs 2 --resume", &output), 0) << output;
  EXPECT_NE(output.find("resumed"), std::string::npos) << output;
  EXPECT_EQ(output.find("training samples per epoch"), std::string::npos) << output;  // the same data
  std::ifstream csv(dir.file("run") + "/training_log.csv");
  std::string line;
  int rows = -1;  // header
  while (std::getline(csv, line)) ++rows;
  EXPECT_EQ(rows, 2);
  // --export: the network alone, smaller than the training checkpoint, and loadable as a model.
  ASSERT_EQ(paco::test::runCommand(tool + " --export " + dir.file("run") + "/best.pt -o " + dir.file("model.pt"), &output), 0)
      << output;
  EXPECT_LT(std::filesystem::file_size(dir.file("model.pt")), std::filesystem::file_size(dir.file("run") + "/best.pt"));
  const paco::LoadedCheckpoint exported = paco::loadCheckpoint(dir.file("model.pt"));
  EXPECT_FALSE(exported.training_state);
  EXPECT_EQ(exported.config.toJson(), tinyConfig().toJson());
  EXPECT_NE(paco::test::runCommand(tool + " --export " + dir.file("missing.pt") + " -o " + dir.file("m2.pt"), &output), 0);
  EXPECT_FALSE(std::filesystem::exists(dir.file("m2.pt")));
  // --extent-head-for: a hidden-extent head for the exported model, from the same data.
  const std::string head_base = tool + " " + dir.file("data") + " --threads 1 --quiet --epochs 3 --extent-head-for ";
  ASSERT_EQ(paco::test::runCommand(head_base + dir.file("model.pt") + " -o " + dir.file("head.pt"), &output), 0) << output;
  EXPECT_NE(output.find("training: 6 samples"), std::string::npos) << output;
  EXPECT_NE(output.find("validation: 2 samples"), std::string::npos) << output;
  const auto head = paco::HiddenExtentModel::load(dir.file("head.pt"));
  EXPECT_NO_THROW(head->checkMatches(*paco::CompletionModel::load(dir.file("model.pt"))));
  EXPECT_NE(paco::test::runCommand(head_base + dir.file("model.pt") + " -o " + dir.file("model.pt"), &output), 0);
  EXPECT_NE(output.find("would replace that input"), std::string::npos) << output;
  EXPECT_NE(paco::test::runCommand(head_base + dir.file("missing.pt") + " -o " + dir.file("h2.pt"), &output), 0);
  EXPECT_NE(output.find("missing.pt"), std::string::npos) << output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("h2.pt")));
  // --feature-cache: a second run takes every sample's features from the cache; a record cut short
  // by a kill is computed again; a cache of another network is refused.
  const std::string cached = head_base + dir.file("model.pt") + " --feature-cache " + dir.file("cache") + " -o ";
  ASSERT_EQ(paco::test::runCommand(cached + dir.file("head_c1.pt"), &output), 0) << output;
  const std::string train_cache = dir.file("cache") + "/training.features";
  ASSERT_TRUE(std::filesystem::exists(train_cache));
  EXPECT_TRUE(std::filesystem::exists(dir.file("cache") + "/validation.features"));
  const auto verbose = [](std::string command) { return command.replace(command.find(" --quiet"), 8, ""); };
  ASSERT_EQ(paco::test::runCommand(verbose(cached) + dir.file("head_c2.pt"), &output), 0) << output;
  EXPECT_NE(output.find("training samples: 6 of 6 from the feature cache"), std::string::npos) << output;
  EXPECT_NE(output.find("training: 6 samples"), std::string::npos) << output;
  std::filesystem::resize_file(train_cache, std::filesystem::file_size(train_cache) - 5);
  ASSERT_EQ(paco::test::runCommand(verbose(cached) + dir.file("head_c3.pt"), &output), 0) << output;
  EXPECT_NE(output.find("training samples: 5 of 6 from the feature cache"), std::string::npos) << output;
  EXPECT_NE(output.find("training: 6 samples"), std::string::npos) << output;
  // The same examples and seed give the same head, from the cache or not.
  const std::vector<float> probe(static_cast<std::size_t>(head->featureWidth()), 0.25f);
  const auto first = head->predict(probe);
  for (const char* name : {"head_c1.pt", "head_c3.pt"}) {
    const auto again = paco::HiddenExtentModel::load(dir.file(name))->predict(probe);
    for (int s = 0; s < paco::kBoxSides; ++s) EXPECT_NEAR(again[s], first[s], 1e-5) << name << " side " << s;
  }
  paco::PacoNetwork untrained(tinyConfig());  // other weights than the exported model's
  paco::saveCheckpoint(dir.file("tiny_other.pt"), untrained);
  EXPECT_NE(paco::test::runCommand(head_base + dir.file("tiny_other.pt") + " --feature-cache " + dir.file("cache") +
                                       " -o " + dir.file("h3.pt"),
                                   &output),
            0);
  EXPECT_NE(output.find("another network"), std::string::npos) << output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("h3.pt")));
  // A cache of the first format holds features observed in another frame: refused too.
  {
    std::fstream header(train_cache, std::ios::in | std::ios::out | std::ios::binary);
    header.seekp(7);
    header.put('1');
  }
  EXPECT_NE(paco::test::runCommand(cached + dir.file("h4.pt"), &output), 0);
  EXPECT_NE(output.find("dominant seen planes' frame"), std::string::npos) << output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("h4.pt")));
  // --init-from: a new run from the exported weights; not together with --resume.
  const std::string init_base = tool + " " + dir.file("data") + " -o " + dir.file("run2") +
                                " --batch 2 --threads 1 --input-points 256 --gt-points 512 --quiet --init-from ";
  ASSERT_EQ(paco::test::runCommand(init_base + dir.file("model.pt") + " --epochs 1", &output), 0) << output;
  EXPECT_NE(output.find("starting from the weights"), std::string::npos) << output;
  EXPECT_EQ(paco::loadCheckpoint(dir.file("run2") + "/last.pt").config.toJson(), tinyConfig().toJson());
  EXPECT_NE(paco::test::runCommand(init_base + dir.file("model.pt") + " --epochs 2 --resume", &output), 0);
  EXPECT_NE(output.find("exclude each other"), std::string::npos) << output;
  EXPECT_NE(paco::test::runCommand(tool + " " + dir.file("data") + " -o " + dir.file("run3") + " --init-from " +
                                   dir.file("missing.pt"), &output), 0);
  EXPECT_FALSE(std::filesystem::exists(dir.file("run3")));
  // A bad loss name is a usage error.
  EXPECT_EQ(paco::test::runCommand(tool + " " + dir.file("data") + " -o " + dir.file("other") +
                                   " --disable-loss chamfer", &output), 2);
  EXPECT_NE(output.find("known terms"), std::string::npos) << output;
  // So are an unknown preset, a NaN augmentation (which switched it off without a word) and a new
  // run of no epoch (which said "checkpoints in" a folder it never made).
  for (const char* bad : {" --preset huge", " --augment-scale nan", " --augment-offset nan", " --epochs 0"}) {
    EXPECT_EQ(paco::test::runCommand(tool + " " + dir.file("data") + " -o " + dir.file("other") + bad, &output), 2)
        << bad << "\n" << output;
  }
  EXPECT_FALSE(std::filesystem::exists(dir.file("other")));
  // Several datasets are trained on together.
  writeTinyDataset(dir.file("more"), "more", 2);
  ASSERT_EQ(paco::test::runCommand(tool + " " + dir.file("data") + " " + dir.file("more") + " -o " + dir.file("run4") +
                                       " --config " + dir.file("tiny.json") +
                                       " --batch 2 --threads 1 --input-points 256 --gt-points 512 --quiet --epochs 1",
                                   &output),
            0)
      << output;
  EXPECT_NE(output.find("used: 10 training, 4 validation samples"), std::string::npos) << output;
  // Resuming that run with one of its datasets left out says the data order changes.
  ASSERT_EQ(paco::test::runCommand(tool + " " + dir.file("data") + " -o " + dir.file("run4") +
                                       " --batch 2 --threads 1 --input-points 256 --gt-points 512 --quiet --epochs 2 --resume",
                                   &output),
            0)
      << output;
  EXPECT_NE(output.find("the run had 10 training samples per epoch and this command gives 6"), std::string::npos)
      << output;
}

// The rows of a paco_train run's training_log.csv (its header left out; 0 while it does not exist).
int loggedEpochs(const std::string& run) {
  std::ifstream csv(run + "/training_log.csv");
  std::string line;
  int rows = -1;
  while (std::getline(csv, line)) ++rows;
  return std::max(rows, 0);
}

// A real Ctrl-C, not the flag set in-process: SIGINT reaches paco_train while it trains (once its
// first epoch is logged, with a thousand to go, so the signal cannot come too late), the run stops
// with exit code 130 and its state saved, and --resume finishes it with every step of every epoch.
TEST(PacoTrainTool, ASignalStopsTrainingAndTheRunResumes) {
  const std::string tool = paco::test::toolPath("paco_train");
  if (!std::filesystem::exists(tool)) GTEST_SKIP() << "paco_train is not built";
  paco::test::TempDir dir;
  writeTinyDataset(dir.file("data"), "shape", 3);  // 6 training samples: 3 steps of 2 per epoch
  {
    std::ofstream config(dir.file("tiny.json"));
    config << tinyConfig().toJson();
  }
  const std::string run = dir.file("run");
  const std::string log = dir.file("log.txt");
  int code = 0;
  {
    paco::test::BackgroundTool training({tool, dir.file("data"), "-o", run, "--config", dir.file("tiny.json"), "--batch",
                                         "2", "--threads", "1", "--input-points", "256", "--gt-points", "512", "--quiet",
                                         "--epochs", "1000"},
                                        log);
    ASSERT_TRUE(training.waitUntil([&] { return loggedEpochs(run) >= 1; }, 180.0))
        << "no epoch logged in 3 minutes\n" << paco::test::readBytes(log);
    code = training.signalAndWait(SIGINT);
  }
  const std::string text = paco::test::readBytes(log);
  EXPECT_EQ(code, 130) << text;
  const std::string saved = "interrupted: state saved to '" + run + "/last.pt' (epoch ";
  const std::size_t at = text.find(saved);
  ASSERT_NE(at, std::string::npos) << text;
  const int epochs_done = std::stoi(text.substr(at + saved.size()));
  EXPECT_GE(epochs_done, 1) << text;
  EXPECT_EQ(loggedEpochs(run), epochs_done) << text;

  std::string resumed;
  const std::string resume = tool + " " + dir.file("data") + " -o " + run +
                             " --batch 2 --threads 1 --input-points 256 --gt-points 512 --quiet --resume --epochs " +
                             std::to_string(epochs_done + 1);
  ASSERT_EQ(paco::test::runCommand(resume, &resumed), 0) << resumed;
  const int epochs = epochs_done + 1;
  EXPECT_NE(resumed.find("done: " + std::to_string(epochs) + " epochs, " + std::to_string(3 * epochs) + " steps"),
            std::string::npos)
      << resumed;
  EXPECT_EQ(loggedEpochs(run), epochs) << resumed;
}
#endif
