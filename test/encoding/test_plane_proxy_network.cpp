#include "tiny_model_config.h"
#include <paco/common/error.h>
#include <paco/encoding/plane_proxy_network.h>

#include <gtest/gtest.h>

namespace paco {
namespace {

ModelConfig tinyConfig() { return test::tinyModelConfig(); }

// Points on `segments` horizontal planes z = 0.1 s (labels s), largest segment first by count.
struct Batch {
  torch::Tensor points, normals, labels;
};
Batch layeredBatch(int64_t B, int64_t N, int segments) {
  torch::manual_seed(3);
  Batch b;
  b.points = torch::rand({B, N, 3}) - 0.5;
  // Segment s gets a share proportional to (segments - s): sizes strictly decrease with s.
  std::vector<int64_t> labels;
  for (int s = 0; s < segments; ++s)
    for (int i = 0; i < (segments - s) * 10; ++i) labels.push_back(s);
  labels.resize(N, -1);
  b.labels = torch::tensor(labels, torch::kLong).unsqueeze(0).repeat({B, 1});
  auto heights = b.labels.to(torch::kFloat) * 0.05 - 0.3;
  auto labelled = b.labels.ge(0);
  b.points.select(2, 2).copy_(torch::where(labelled, heights, b.points.select(2, 2)));
  b.normals = torch::zeros({B, N, 3});
  b.normals.select(2, 2).copy_(labelled.to(torch::kFloat));
  return b;
}

TEST(PlaneProxyNetwork, ShapesAndMaskForTheCpuPreset) {
  const ModelConfig config = ModelConfig::preset("cpu");
  PlaneProxyNetwork net(config);
  net->eval();
  torch::NoGradGuard no_grad;
  const auto b = layeredBatch(2, 600, 5);
  const auto out = net->forward(b.points, b.normals, b.labels);
  const int64_t K = config.plane_slots, C = config.width, G = config.num_centres;
  EXPECT_EQ(out.proxies.sizes(), (std::vector<int64_t>{2, K, C}));
  EXPECT_EQ(out.mask.sizes(), (std::vector<int64_t>{2, K}));
  EXPECT_EQ(out.slot_normals.sizes(), (std::vector<int64_t>{2, K, 3}));
  EXPECT_EQ(out.slot_offsets.sizes(), (std::vector<int64_t>{2, K}));
  EXPECT_EQ(out.centres.sizes(), (std::vector<int64_t>{2, G, 3}));
  EXPECT_EQ(out.point_proxies.sizes(), (std::vector<int64_t>{2, G, C}));
  EXPECT_EQ(out.mask.sum().item<int64_t>(), 2 * 5);
  EXPECT_TRUE(out.mask.slice(1, 0, 5).all().item<bool>());
  // Padded slots are exactly zero; real ones are not.
  EXPECT_EQ(out.proxies.slice(1, 5).abs().max().item<float>(), 0.0f);
  EXPECT_GT(out.proxies.slice(1, 0, 5).abs().min().item<float>() +
                out.proxies.slice(1, 0, 5).abs().max().item<float>(),
            0.0f);
  EXPECT_TRUE(torch::isfinite(out.proxies).all().item<bool>());
}

TEST(PlaneProxyNetwork, ShapesForThePaperPresetAtBatchOne) {
  const ModelConfig config = ModelConfig::preset("paper");
  PlaneProxyNetwork net(config);
  net->eval();
  torch::NoGradGuard no_grad;
  const auto b = layeredBatch(1, 2048, 4);
  const auto out = net->forward(b.points, b.normals, b.labels);
  EXPECT_EQ(out.proxies.sizes(), (std::vector<int64_t>{1, 20, 384}));
  EXPECT_EQ(out.point_proxies.sizes(), (std::vector<int64_t>{1, 128, 384}));
  EXPECT_EQ(out.mask.sum().item<int64_t>(), 4);
}

TEST(PlaneProxyNetwork, KeepsTheKLargestSegmentsWithTheirPlanes) {
  const ModelConfig config = tinyConfig();  // K = 6
  PlaneProxyNetwork net(config);
  net->eval();
  torch::NoGradGuard no_grad;
  const auto b = layeredBatch(1, 500, 9);  // 9 segments, sizes 90, 80, ..., 10
  const auto out = net->forward(b.points, b.normals, b.labels);
  EXPECT_TRUE(out.mask.all().item<bool>());
  for (int s = 0; s < 6; ++s) {
    EXPECT_EQ(out.slot_segments[0][s].item<int64_t>(), s);  // largest first
    EXPECT_NEAR(out.slot_normals[0][s][2].item<float>(), 1.0f, 1e-6);
    EXPECT_NEAR(out.slot_offsets[0][s].item<float>(), s * 0.05f - 0.3f, 1e-5);
  }
}

TEST(PlaneProxyNetwork, CentreLabelsComeFromTheirPoints) {
  const ModelConfig config = tinyConfig();
  PlaneProxyNetwork net(config);
  torch::NoGradGuard no_grad;
  const auto b = layeredBatch(1, 300, 3);
  const auto out = net->forward(b.points, b.normals, b.labels);
  // Each centre is an input point; its label is that point's label.
  auto d = torch::cdist(out.centres[0], b.points[0]);
  auto nearest = std::get<1>(d.min(1));
  EXPECT_TRUE(out.centre_labels[0].eq(b.labels[0].index_select(0, nearest)).all().item<bool>());
}

TEST(PlaneProxyNetwork, UnsegmentedCloudHasNoValidSlot) {
  PlaneProxyNetwork net(tinyConfig());
  torch::NoGradGuard no_grad;
  auto b = layeredBatch(1, 100, 2);
  b.labels.fill_(-1);
  const auto out = net->forward(b.points, b.normals, b.labels);
  EXPECT_FALSE(out.mask.any().item<bool>());
  EXPECT_EQ(out.proxies.abs().max().item<float>(), 0.0f);
}

TEST(PlaneProxyNetwork, FewerPointsThanCentresStillWork) {
  PlaneProxyNetwork net(tinyConfig());  // 32 centres, k = 8
  torch::NoGradGuard no_grad;
  const auto b = layeredBatch(1, 12, 1);
  const auto out = net->forward(b.points, b.normals, b.labels);
  EXPECT_TRUE(torch::isfinite(out.proxies).all().item<bool>());
  EXPECT_EQ(out.mask.sum().item<int64_t>(), 1);
}

TEST(PlaneProxyNetwork, RejectsBadShapes) {
  PlaneProxyNetwork net(tinyConfig());
  auto b = layeredBatch(1, 50, 2);
  EXPECT_THROW(net->forward(b.points.squeeze(0), b.normals, b.labels), InvalidInputError);
  EXPECT_THROW(net->forward(b.points, b.normals.slice(1, 0, 10), b.labels), InvalidInputError);
  EXPECT_THROW(net->forward(b.points, b.normals, b.labels.slice(1, 0, 10)), InvalidInputError);
}

TEST(PlaneProxyNetwork, GradientsReachTheEdgeConvs) {
  PlaneProxyNetwork net(tinyConfig());
  const auto b = layeredBatch(2, 200, 3);
  net->forward(b.points, b.normals, b.labels).proxies.pow(2).sum().backward();
  for (const auto& p : net->named_parameters())
    ASSERT_TRUE(p.value().grad().defined()) << p.key();
  const auto conv = net->named_parameters()["edge_conv0.weight"];
  EXPECT_GT(conv.grad().abs().sum().item<float>(), 0.0f);
}

TEST(PolarToNormal, GivesUnitVectors) {
  auto theta = torch::linspace(-4, 4, 17), phi = torch::linspace(-7, 7, 17);
  auto n = polarToNormal(theta, phi);
  EXPECT_LT((n.norm(2, -1) - 1).abs().max().item<float>(), 1e-6);
  auto z = polarToNormal(torch::zeros({1}), torch::zeros({1}));
  EXPECT_NEAR(z[0][2].item<float>(), 1.0f, 1e-7);
}

}  // namespace
}  // namespace paco
