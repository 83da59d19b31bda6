// Can the hidden extent be read off the network's global feature? A feasibility probe.
// Usage: paco_extent_probe DATASET_DIR MODEL TRAIN_SAMPLES EPOCHS ORIENTATION [EVAL_DATASET_DIR]
// Runs MODEL (no gradient) on TRAIN_SAMPLES training samples of DATASET_DIR in the own frame,
// turned as ORIENTATION says ("as-is", or "seen-planes": the dominant seen faces on the axes, as
// the fusion's box fill takes its box), and collects the decoder's global feature with, per side
// of the input's axis-aligned box, how far the GT reaches beyond it. Fits a small MLP (L1 loss)
// from the feature and the box's shape to those six extensions, and prints the L1 against
// predicting zero (the fill at the seen box) on 1,500 samples of DATASET_DIR's validation split
// and on 1,200 of EVAL_DATASET_DIR's if given (doc/results.md, eighteenth and thirty-second
// sessions). The head the tools use grew out of it: paco::HiddenExtentModel, trained by paco_train
// --extent-head-for; this probe stays as the quick way to try an orientation or a dataset.
#include <paco/completion/batch.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/trainer.h>
#include <paco/data/dataset.h>

#include <torch/torch.h>

#include <cstdio>
#include <exception>
#include <numeric>
#include <string>
#include <vector>

namespace {

struct Features {
  torch::Tensor x;  // (N, W + 3)
  torch::Tensor y;  // (N, 6): -x -y -z +x +y +z extensions beyond the input's box
};

Features collect(paco::PacoNetwork& net, const paco::completion::BatchSource& source, std::size_t count) {
  torch::NoGradGuard no_grad;
  std::vector<torch::Tensor> xs, ys;
  const std::size_t n = std::min(count, source.size), batch = 32;
  for (std::size_t begin = 0; begin < n; begin += batch) {
    std::vector<std::size_t> idx;
    for (std::size_t i = begin; i < std::min(n, begin + batch); ++i) idx.push_back(i * source.size / n);
    auto b = source.load(idx, 7);
    auto out = net->forward(b.input);
    auto in_min = std::get<0>(b.input.points.min(1)), in_max = std::get<0>(b.input.points.max(1));
    auto gt_min = std::get<0>(b.truth.points.min(1)), gt_max = std::get<0>(b.truth.points.max(1));
    xs.push_back(torch::cat({out.global_feature, in_max - in_min}, 1));
    ys.push_back(torch::cat({in_min - gt_min, gt_max - in_max}, 1).clamp_min(0.0));
    std::fprintf(stderr, "\r%zu / %zu", std::min(n, begin + batch), n);
  }
  std::fprintf(stderr, "\n");
  return {torch::cat(xs, 0), torch::cat(ys, 0)};
}

void report(const char* name, const torch::Tensor& pred, const torch::Tensor& y) {
  const double zero = y.abs().mean().item<double>();
  const double head = (pred - y).abs().mean().item<double>();
  auto is_short = y > 0.03;
  const double n_short = is_short.sum().item<double>();
  const double mean_gap = n_short > 0 ? y.masked_select(is_short).mean().item<double>() : 0.0;
  const double pred_on_short = n_short > 0 ? pred.masked_select(is_short).mean().item<double>() : 0.0;
  const double pred_elsewhere = pred.masked_select(is_short.logical_not()).mean().item<double>();
  const double gap_elsewhere = y.masked_select(is_short.logical_not()).mean().item<double>();
  std::printf("%s: %lld samples; L1 zero %.4f, head %.4f (%.0f %% of zero); short sides %.0f "
              "(gap %.3f, predicted %.3f); other sides gap %.4f, predicted %.4f\n",
              name, static_cast<long long>(y.size(0)), zero, head, 100.0 * head / zero, n_short,
              mean_gap, pred_on_short, gap_elsewhere, pred_elsewhere);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 6 || argc > 7) {
    std::fprintf(stderr, "usage: %s DATASET_DIR MODEL TRAIN_SAMPLES EPOCHS as-is|seen-planes [EVAL_DATASET_DIR]\n",
                 argv[0]);
    return 2;
  }
  try {
    torch::manual_seed(1);
    auto checkpoint = paco::loadCheckpoint(argv[2]);
    auto net = checkpoint.network;
    net->eval();
    paco::completion::CollateOptions collate;
    collate.input_frame = "own";
    collate.input_orientation = argv[5];
    auto dataset = std::make_shared<const paco::data::Dataset>(argv[1]);
    auto train_source = paco::completion::datasetSource(dataset, paco::data::Split::Train, collate);
    auto val_source = paco::completion::datasetSource(dataset, paco::data::Split::Val, collate);
    const std::size_t count = std::stoul(argv[3]);
    const int epochs = std::stoi(argv[4]);
    Features train = collect(net, train_source, count);
    Features val = collect(net, val_source, 1500);
    Features other;
    if (argc > 6) {
      auto other_set = std::make_shared<const paco::data::Dataset>(argv[6]);
      other = collect(net, paco::completion::datasetSource(other_set, paco::data::Split::Val, collate),
                      1200);
    }
    const auto mean = train.x.mean(0), stdev = train.x.std(0).clamp_min(1e-6);
    auto normalise = [&](const torch::Tensor& x) { return (x - mean) / stdev; };
    const int64_t in = train.x.size(1);
    torch::nn::Sequential head(torch::nn::Linear(in, 256), torch::nn::GELU(),
                               torch::nn::Dropout(0.2), torch::nn::Linear(256, 6),
                               torch::nn::Softplus());
    torch::optim::AdamW opt(head->parameters(), torch::optim::AdamWOptions(1e-3).weight_decay(1e-2));
    const auto xs = normalise(train.x);
    const int64_t N = xs.size(0), mb = 256;
    for (int epoch = 1; epoch <= epochs; ++epoch) {
      head->train();
      auto perm = torch::randperm(N, torch::kLong);
      double sum = 0.0;
      for (int64_t b = 0; b < N; b += mb) {
        auto idx = perm.slice(0, b, std::min(N, b + mb));
        auto loss = (head->forward(xs.index_select(0, idx)) - train.y.index_select(0, idx)).abs().mean();
        opt.zero_grad();
        loss.backward();
        opt.step();
        sum += loss.item<double>() * idx.size(0);
      }
      if (epoch % 20 == 0 || epoch == epochs) {
        head->eval();
        torch::NoGradGuard no_grad;
        std::printf("epoch %d: train L1 %.4f\n", epoch, sum / N);
        report("  val", head->forward(normalise(val.x)), val.y);
        if (other.x.defined()) report("  eval set", head->forward(normalise(other.x)), other.y);
        std::fflush(stdout);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "paco_extent_probe: %s\n", e.what());
    return 1;
  }
  return 0;
}
