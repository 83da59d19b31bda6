#include "test_network_support.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/completion/network.h>

#include <gtest/gtest.h>

#include <cmath>

namespace paco {
namespace {

using test::boxBatch;
using test::tinyModelConfig;

void expectShapes(const NetworkOutput& out, const ModelConfig& c, int64_t B) {
  const int64_t M = c.kept_queries, Q = c.plane_slots + c.generated_queries, P = c.points_per_plane;
  EXPECT_EQ(out.normals.sizes(), (std::vector<int64_t>{B, M, 3}));
  EXPECT_EQ(out.offsets.sizes(), (std::vector<int64_t>{B, M}));
  EXPECT_EQ(out.points.sizes(), (std::vector<int64_t>{B, M, P, 3}));
  EXPECT_EQ(out.logits.sizes(), (std::vector<int64_t>{B, M}));
  EXPECT_EQ(out.candidate_normals.sizes(), (std::vector<int64_t>{B, Q, 3}));
  EXPECT_EQ(out.candidate_offsets.sizes(), (std::vector<int64_t>{B, Q}));
  EXPECT_EQ(out.candidate_scores.sizes(), (std::vector<int64_t>{B, Q}));
  EXPECT_EQ(out.candidate_valid.sizes(), (std::vector<int64_t>{B, Q}));
  EXPECT_EQ(out.selected.sizes(), (std::vector<int64_t>{B, M}));
  EXPECT_EQ(out.selected.scalar_type(), torch::kLong);
  EXPECT_EQ(out.global_feature.sizes(), (std::vector<int64_t>{B, c.global_width}));
  for (const auto* t : {&out.normals, &out.offsets, &out.points, &out.logits, &out.global_feature})
    EXPECT_TRUE(torch::isfinite(*t).all().item<bool>());
  EXPECT_LT((out.normals.norm(2, -1) - 1).abs().max().item<float>(), 1e-5);
}

TEST(PacoNetwork, ShapesForTheCpuPreset) {
  const ModelConfig config = ModelConfig::preset("cpu");
  PacoNetwork net(config);
  net->eval();
  torch::NoGradGuard no_grad;
  expectShapes(net->forward(boxBatch(2, 2048)), config, 2);
}

TEST(PacoNetwork, ShapesAndSizeOfThePaperPresetAtBatchOne) {
  const ModelConfig config = ModelConfig::preset("paper");
  PacoNetwork net(config);
  const double millions = parameterCount(*net) / 1e6;
  EXPECT_GT(millions, 37.0);  // the reference network has about 41 M parameters
  EXPECT_LT(millions, 45.0);
  net->eval();
  torch::NoGradGuard no_grad;
  expectShapes(net->forward(boxBatch(1, 2048)), config, 1);
}

TEST(PacoNetwork, CpuPresetIsMuchSmallerThanThePaperOne) {
  PacoNetwork cpu(ModelConfig::preset("cpu"));
  EXPECT_LT(parameterCount(*cpu), 10'000'000);
}

TEST(PacoNetwork, PredictedPointsLieOnTheirPlanesForBothDistributors) {
  for (const std::string mode : {"projected", "polar"}) {
    PacoNetwork net(tinyModelConfig(mode));
    torch::NoGradGuard no_grad;
    const auto out = net->forward(boxBatch(2, 300));
    auto distance = (out.points * out.normals.unsqueeze(2)).sum(-1) - out.offsets.unsqueeze(-1);
    EXPECT_LT(distance.abs().max().item<float>(), 1e-5) << mode;
  }
}

TEST(PointDistributor, PointsAreOnThePlaneIncludingDegenerateCases) {
  torch::manual_seed(11);
  const int64_t planes = 6, P = 200;
  // Random unit normals, and offsets that include planes through the origin (r = 0).
  auto normals = torch::randn({planes, 3});
  normals = normals / normals.norm(2, -1, true);
  auto offsets = torch::tensor({0.0f, 0.0f, 0.3f, -0.45f, 1e-8f, 0.8f});
  for (const std::string mode : {"projected", "polar"}) {
    torch::Tensor raw;
    if (mode == "projected") {
      raw = torch::randn({planes, P, 3}) * 3;
    } else {
      // Half of the rays nearly parallel to the plane (u.n -> 0), half random.
      auto theta_n = torch::acos(normals.select(1, 2)).unsqueeze(1);
      auto phi_n = torch::atan2(normals.select(1, 1), normals.select(1, 0)).unsqueeze(1);
      auto theta = torch::cat({(theta_n + paco::kPi / 2 + 1e-7).expand({planes, P / 2}),
                               torch::rand({planes, P / 2}) * paco::kPi}, 1);
      auto phi = torch::cat({phi_n.expand({planes, P / 2}), torch::rand({planes, P / 2}) * 6.28}, 1);
      raw = torch::stack({theta, phi}, -1);
    }
    auto points = distributePoints(mode, raw, normals, offsets);
    ASSERT_EQ(points.sizes(), (std::vector<int64_t>{planes, P, 3}));
    EXPECT_TRUE(torch::isfinite(points).all().item<bool>()) << mode;
    auto distance = (points * normals.unsqueeze(1)).sum(-1) - offsets.unsqueeze(-1);
    EXPECT_LT(distance.abs().max().item<float>(), 1e-5) << mode;
    // No collapse onto one point for planes through the origin: the points stay spread out.
    for (int p : {0, 1, 4}) EXPECT_GT(points[p].std(0).norm().item<float>(), 0.05f) << mode;
  }
  EXPECT_THROW(distributePoints("spherical", torch::zeros({1, 1, 3}), normals.slice(0, 0, 1),
                                offsets.slice(0, 0, 1)),
               InvalidInputError);
}

TEST(PacoNetwork, RankingKeepsTheHighestValidScores) {
  const ModelConfig config = tinyModelConfig();
  PacoNetwork net(config);
  torch::NoGradGuard no_grad;
  const auto out = net->forward(boxBatch(3, 300, /*faces=*/3));  // 3 of K = 6 slots valid
  const int64_t M = config.kept_queries;
  for (int64_t b = 0; b < 3; ++b) {
    auto valid = out.candidate_valid[b];
    EXPECT_EQ(valid.sum().item<int64_t>(), 3 + config.generated_queries);
    auto scores = out.candidate_scores[b].masked_fill(valid.logical_not(), -1e30);
    auto best = std::get<1>(scores.topk(M));
    auto chosen = std::get<0>(out.selected[b].sort());
    EXPECT_TRUE(chosen.equal(std::get<0>(best.sort()))) << b;
    EXPECT_TRUE(valid.index_select(0, out.selected[b]).all().item<bool>());
  }
}

TEST(PacoNetwork, RankingScoreIsTrainable) {
  PacoNetwork net(tinyModelConfig());
  const auto out = net->forward(boxBatch(2, 200));
  out.candidate_scores.sum().backward();
  float score_gradient = 0;
  for (const auto& p : net->named_parameters())
    if (p.key().find("decoder.score") == 0 && p.value().grad().defined())
      score_gradient += p.value().grad().abs().sum().item<float>();
  EXPECT_GT(score_gradient, 0.0f);
}

TEST(PacoNetwork, EveryParameterGetsAGradientFromTheOutputs) {
  PacoNetwork net(tinyModelConfig());
  const auto out = net->forward(boxBatch(2, 200));
  (out.points.pow(2).mean() + out.logits.pow(2).mean() + out.offsets.pow(2).mean() +
   out.candidate_scores.pow(2).mean() + out.candidate_offsets.pow(2).mean() +
   out.normals.sum())
      .backward();
  for (const auto& p : net->named_parameters()) {
    ASSERT_TRUE(p.value().grad().defined()) << p.key();
    EXPECT_GT(p.value().grad().abs().sum().item<float>(), 0.0f) << p.key();
  }
}

TEST(PacoNetwork, OutputIgnoresTheContentOfPaddedSlots) {
  const ModelConfig config = tinyModelConfig();
  PacoNetwork net(config);
  net->eval();
  torch::NoGradGuard no_grad;
  const auto input = boxBatch(1, 300, /*faces=*/2);
  auto proxies = net->encoder()->forward(input.points, input.normals, input.labels);
  ASSERT_EQ(proxies.mask.sum().item<int64_t>(), 2);
  const auto reference = net->decoder()->forward(proxies);
  // Fill the padded slots with garbage features and planes: nothing may change.
  auto garbage = proxies;
  auto padded = proxies.mask.logical_not().unsqueeze(-1);
  garbage.proxies = torch::where(padded, torch::randn_like(proxies.proxies) * 10, proxies.proxies);
  garbage.slot_normals = torch::where(padded, torch::randn_like(proxies.slot_normals), proxies.slot_normals);
  garbage.slot_offsets = torch::where(proxies.mask, proxies.slot_offsets, torch::randn_like(proxies.slot_offsets));
  const auto changed = net->decoder()->forward(garbage);
  EXPECT_TRUE(changed.selected.equal(reference.selected));
  EXPECT_LT((changed.points - reference.points).abs().max().item<float>(), 1e-5);
  EXPECT_LT((changed.logits - reference.logits).abs().max().item<float>(), 1e-5);
  EXPECT_LT((changed.normals - reference.normals).abs().max().item<float>(), 1e-5);
}

TEST(PacoNetwork, CloudWithoutSegmentsGivesFiniteOutputs) {
  const ModelConfig config = tinyModelConfig();
  PacoNetwork net(config);
  torch::NoGradGuard no_grad;
  expectShapes(net->forward(boxBatch(1, 200, /*faces=*/0)), config, 1);
}

TEST(PacoNetwork, InputPlanesSeedTheirCandidates) {
  PacoNetwork net(tinyModelConfig());
  torch::NoGradGuard no_grad;
  const auto input = boxBatch(1, 400);
  const auto out = net->forward(input);
  // The first K candidates carry the input segments' planes (box faces at distance 0.25).
  auto offsets = out.candidate_offsets[0].slice(0, 0, 6);
  EXPECT_LT((offsets.abs() - 0.25).abs().max().item<float>(), 1e-5);
  auto normals = out.candidate_normals[0].slice(0, 0, 6);
  EXPECT_LT((normals.abs().sum(-1) - 1).abs().max().item<float>(), 1e-5);
}

}  // namespace
}  // namespace paco
