#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/completion/batch.h>
#include <paco/completion/losses.h>
#include <paco/completion/matching.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <set>

using namespace paco::completion;

namespace {

torch::Tensor grid(int nx, int ny, double spacing, double z) {
  std::vector<float> values;
  for (int i = 0; i < nx; ++i)
    for (int j = 0; j < ny; ++j) {
      values.push_back(static_cast<float>(i * spacing));
      values.push_back(static_cast<float>(j * spacing));
      values.push_back(static_cast<float>(z));
    }
  return torch::tensor(values).view({nx * ny, 3});
}

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// Two GT planes z = 0 (normal -z, outward below) and z = 0.5 (normal +z), 16 points each; three
// predictions: 0 = garbage, 1 = exactly GT plane 1, 2 = exactly GT plane 0.
struct Scene {
  paco::NetworkOutput output;
  GroundTruthBatch truth;
};

Scene makeScene() {
  Scene s;
  const auto bottom = grid(4, 4, 0.1, 0.0);
  const auto top = grid(4, 4, 0.1, 0.5);
  s.truth.points = torch::cat({bottom, top}).unsqueeze(0);  // (1, 32, 3)
  s.truth.labels = torch::cat({torch::zeros({16}, torch::kLong), torch::ones({16}, torch::kLong)}).unsqueeze(0);
  s.truth.normals = torch::tensor({0.f, 0.f, -1.f, 0.f, 0.f, 1.f}).view({1, 2, 3});
  s.truth.offsets = torch::tensor({0.f, 0.5f}).view({1, 2});  // -z = 0, z = 0.5
  s.truth.mask = torch::ones({1, 2}, torch::kBool);
  s.output.normals = torch::tensor({1.f, 0.f, 0.f, 0.f, 0.f, 1.f, 0.f, 0.f, -1.f}).view({1, 3, 3});
  s.output.offsets = torch::tensor({0.3f, 0.5f, 0.0f}).view({1, 3});
  const auto garbage = grid(4, 4, 0.05, 0.0).index_select(1, torch::tensor({2, 0, 1})) + 0.3;  // on x = 0.3
  s.output.points = torch::stack({garbage, top, bottom}).unsqueeze(0);  // (1, 3, 16, 3)
  s.output.logits = torch::tensor({-1.0f, 2.0f, 0.5f}).view({1, 3});
  return s;
}

// The scene with predicted plane 1 (GT plane 1, z = 0.5) and its points moved to z.
Scene makeSceneWithPlane1At(float z) {
  Scene s = makeScene();
  s.output.offsets[0][1] = z;
  s.output.points[0][1].select(1, 2).fill_(z);
  return s;
}

}  // namespace

TEST(Losses, ChamferOfIdenticalSetsIsZero) {
  const auto a = grid(5, 5, 0.1, 0.2);
  EXPECT_NEAR(chamferSquared(a, a.clone()).item<double>(), 0.0, 1e-12);
}

TEST(Losses, ChamferHandComputed) {
  const auto a = torch::tensor({0.f, 0.f, 0.f}).view({1, 3});
  const auto b = torch::tensor({1.f, 0.f, 0.f, 0.f, 2.f, 0.f}).view({2, 3});
  // a -> b: 1; b -> a: (1 + 4) / 2.
  EXPECT_NEAR(chamferSquared(a, b).item<double>(), 3.5, 1e-6);
  // A small shift t of a well-spaced grid: each direction |t|².
  const auto g = grid(4, 4, 1.0, 0.0);
  const auto shifted = g + torch::tensor({0.1f, 0.2f, 0.0f});
  EXPECT_NEAR(chamferSquared(g, shifted).item<double>(), 2 * (0.01 + 0.04), 1e-5);
}

TEST(Losses, ChamferGradientPullsTowardsTarget) {
  auto a = torch::tensor({0.f, 0.f, 0.3f}).view({1, 3}).set_requires_grad(true);
  const auto b = torch::tensor({0.f, 0.f, 0.f}).view({1, 3});
  chamferSquared(a, b).backward();
  // d/dz of 2 z² at z = 0.3 is 1.2: gradient descent moves a down to b.
  EXPECT_NEAR(a.grad()[0][2].item<double>(), 1.2, 1e-5);
}

TEST(Losses, NormalLossHandComputed) {
  const auto n = torch::tensor({0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f}).view({3, 3});
  const auto t = torch::tensor({0.f, 0.f, 1.f, 0.f, 0.f, -1.f, 1.f, 0.f, 0.f}).view({3, 3});
  const auto loss = normalLoss(n, t, 1.0);
  EXPECT_NEAR(loss[0].item<double>(), 0.0, 1e-7);
  EXPECT_NEAR(loss[1].item<double>(), 4.0 + 2.0, 1e-6);  // flipped: the orientation matters
  EXPECT_NEAR(loss[2].item<double>(), 2.0 + 1.0, 1e-6);
  EXPECT_NEAR(normalLoss(n, t, 0.5)[2].item<double>(), 2.0 + 0.5, 1e-6);
}

TEST(Losses, RepulsionHandComputedAndPushesApart) {
  // Two points 0.01 apart, k = 1: both see d = 0.01.
  auto x = torch::tensor({0.f, 0.f, 0.f, 0.01f, 0.f, 0.f}).view({1, 2, 3}).set_requires_grad(true);
  const auto loss = repulsionLoss(x, 1, 0.03, 0.07);
  const double expected = 0.07 - 0.01 * std::exp(-0.0001 / 0.0009);
  EXPECT_NEAR(loss[0].item<double>(), expected, 1e-6);
  loss.sum().backward();
  // Descending the gradient moves point 0 towards -x and point 1 towards +x: apart.
  EXPECT_GT(x.grad()[0][0][0].item<double>(), 0.0);
  EXPECT_LT(x.grad()[0][1][0].item<double>(), 0.0);
  // Far points (beyond the kernel) feel next to nothing.
  const auto far = torch::tensor({0.f, 0.f, 0.f, 0.5f, 0.f, 0.f}).view({1, 2, 3});
  EXPECT_NEAR(repulsionLoss(far, 1, 0.03, 0.07)[0].item<double>(), 0.07, 1e-9);
}

TEST(Losses, MatchingFindsExactPredictions) {
  const Scene s = makeScene();
  LossConfig config;
  const Matching m = matchPredictions(s.output, s.truth, config);
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0], (std::vector<int>{2, 1}));
  const Eigen::MatrixXd cost = matchingCost(s.output, s.truth, 0, config);
  EXPECT_EQ(cost.rows(), 2);
  EXPECT_EQ(cost.cols(), 3);
}

TEST(Losses, TotalOfExactPredictionsIsClassificationPlusRepulsion) {
  const Scene s = makeScene();
  LossConfig config;
  config.ranking = false;
  const LossResult r = computeLosses(s.output, s.truth, config);
  EXPECT_NEAR(r.terms.at("normal"), 0.0, 1e-6);
  EXPECT_NEAR(r.terms.at("offset"), 0.0, 1e-6);
  EXPECT_NEAR(r.terms.at("plane_chamfer"), 0.0, 1e-6);
  EXPECT_NEAR(r.terms.at("overall_chamfer"), 0.0, 1e-6);
  // BCE: matched 1 and 2 to "plane", 0 to "empty" with weight 0.4, over 2 GT planes.
  const double cls = (-std::log(sigmoid(2.0)) - std::log(sigmoid(0.5)) - 0.4 * std::log(1.0 - sigmoid(-1.0))) / 2.0;
  EXPECT_NEAR(r.terms.at("classification"), cls, 1e-5);
  // Repulsion of the two matched 4x4 grids (spacing 0.1), weight 2, over 2 GT planes.
  const auto rep = repulsionLoss(s.output.points[0].slice(0, 1, 3), 5, 0.03, 0.07).sum().item<double>();
  EXPECT_NEAR(r.terms.at("repulsion"), 2.0 * rep / 2.0, 1e-6);
  EXPECT_NEAR(r.total.item<double>(), cls + rep, 1e-5);
}

TEST(Losses, KnownOffsetsGiveKnownValues) {
  // Predicted plane 1 (GT plane 1, z = 0.5) moved up by 0.1, points included.
  const Scene s = makeSceneWithPlane1At(0.6f);
  LossConfig config;
  config.ranking = false;
  const LossResult r = computeLosses(s.output, s.truth, config);
  EXPECT_EQ(r.matching[0], (std::vector<int>{2, 1}));
  EXPECT_NEAR(r.terms.at("offset"), 0.1 / 2.0, 1e-6);                 // |Δr| over 2 GT planes
  EXPECT_NEAR(r.terms.at("plane_chamfer"), 20.0 * 2 * 0.01, 1e-5);    // 2 directions x 0.1², /B=1
  // Overall: the 16 moved points are 0.01 from their nearest GT point; the GT top points too.
  EXPECT_NEAR(r.terms.at("overall_chamfer"), 20.0 * (0.5 * 0.01 + 0.5 * 0.01), 1e-5);
}

TEST(Losses, QualityClassificationGivesAFarMatchedPlaneTheEmptyTarget) {
  // Predicted plane 1 stays matched to GT plane 1 (z = 0.5) but lies 0.1 above it, beyond
  // quality_offset (0.05); predicted plane 2 is exact.
  Scene s = makeSceneWithPlane1At(0.6f);
  LossConfig config;
  config.ranking = false;
  config.quality_classification = true;
  const LossResult r = computeLosses(s.output, s.truth, config);
  ASSERT_EQ(r.matching[0], (std::vector<int>{2, 1}));
  // Over 2 GT planes: 2 to "plane"; 1 (too far) and 0 (unmatched) to "empty" with weight 0.4.
  const double cls =
      (-std::log(sigmoid(0.5)) - 0.4 * std::log(1.0 - sigmoid(2.0)) - 0.4 * std::log(1.0 - sigmoid(-1.0))) / 2.0;
  EXPECT_NEAR(r.terms.at("classification"), cls, 1e-5);
  // Within the tolerance (0.04 off) it is a plane again, as without the option.
  s.output.offsets[0][1] = 0.54f;
  const LossResult near = computeLosses(s.output, s.truth, config);
  const double cls_near =
      (-std::log(sigmoid(2.0)) - std::log(sigmoid(0.5)) - 0.4 * std::log(1.0 - sigmoid(-1.0))) / 2.0;
  EXPECT_NEAR(near.terms.at("classification"), cls_near, 1e-5);
}

TEST(Losses, GradientOfTotalFlowsToEveryHead) {
  Scene s = makeScene();
  s.output.normals = s.output.normals.clone().set_requires_grad(true);
  s.output.offsets = (s.output.offsets + 0.05).detach().set_requires_grad(true);
  s.output.points = (s.output.points + 0.01).detach().set_requires_grad(true);
  s.output.logits = s.output.logits.clone().set_requires_grad(true);
  LossConfig config;
  config.ranking = false;
  computeLosses(s.output, s.truth, config).total.backward();
  for (const auto* t : {&s.output.normals, &s.output.offsets, &s.output.points, &s.output.logits}) {
    ASSERT_TRUE(t->grad().defined());
    EXPECT_GT(t->grad().abs().sum().item<double>(), 0.0);
  }
}

TEST(Losses, DisablingTermsRemovesThem) {
  const Scene s = makeScene();
  LossConfig config;
  config.ranking = false;
  config.disable("repulsion");
  config.disable("classification");
  EXPECT_FALSE(config.enabled("repulsion"));
  const LossResult r = computeLosses(s.output, s.truth, config);
  EXPECT_EQ(r.terms.count("repulsion"), 0u);
  EXPECT_EQ(r.terms.count("classification"), 0u);
  EXPECT_NEAR(r.total.item<double>(), 0.0, 1e-5);
  EXPECT_THROW(config.disable("chamfer"), paco::InvalidInputError);
}

TEST(Losses, RankingTargetsAndLoss) {
  Scene s = makeScene();
  // Candidates: GT plane 1 exactly, GT plane 0 flipped (same plane, other orientation), off by 0.1 in r, 5° off.
  const double a = paco::degreesToRadians(5.0);
  s.output.candidate_normals = torch::tensor({0.f, 0.f, 1.f, 0.f, 0.f, 1.f, 0.f, 0.f, 1.f,
                                              static_cast<float>(std::sin(a)), 0.f, static_cast<float>(std::cos(a))})
                                   .view({1, 4, 3});
  s.output.candidate_offsets = torch::tensor({0.5f, 0.0f, 0.6f, 0.5f}).view({1, 4});
  LossConfig config;
  const auto targets = rankingTargets(s.output.candidate_normals, s.output.candidate_offsets, s.truth, config);
  EXPECT_TRUE(torch::equal(targets, torch::tensor({1.f, 0.f, 0.f, 1.f}).view({1, 4})));
  s.output.candidate_scores = torch::tensor({3.f, -3.f, 0.f, 1.f}).view({1, 4});
  s.output.candidate_valid = torch::tensor({true, true, true, false}).view({1, 4});
  const LossResult r = computeLosses(s.output, s.truth, config);
  // Mean BCE over the 3 valid candidates.
  const double expected = (-std::log(sigmoid(3.0)) - std::log(1.0 - sigmoid(-3.0)) - std::log(0.5)) / 3.0;
  EXPECT_NEAR(r.terms.at("ranking"), expected, 1e-5);
}

TEST(Losses, PlaneMetricsCountRecallAndPrecision) {
  const Scene s = makeScene();
  LossConfig config;
  const Matching m = matchPredictions(s.output, s.truth, config);
  // Confidence > 0.7 keeps only prediction 1 (sigmoid(2) = 0.88): GT plane 1 recalled.
  const PlaneMetrics metrics = planeMetrics(s.output, s.truth, m, config, 0.7);
  EXPECT_EQ(metrics.gt_planes, 2);
  EXPECT_EQ(metrics.confident, 1);
  EXPECT_DOUBLE_EQ(metrics.recall, 0.5);
  EXPECT_DOUBLE_EQ(metrics.precision, 1.0);
  EXPECT_NEAR(metrics.nc_prim, 1.0, 1e-6);
}

TEST(Losses, MismatchedShapesAreRejected) {
  Scene s = makeScene();
  s.output.logits = torch::zeros({1, 4});
  EXPECT_THROW(computeLosses(s.output, s.truth, LossConfig()), paco::InvalidInputError);
  Scene t = makeScene();
  t.output.normals[0][0][0] = std::nanf("");
  EXPECT_THROW(computeLosses(t.output, t.truth, LossConfig()), paco::ModelError);
}

TEST(Batch, ResampleIndices) {
  const auto same = resampleIndices(5, 5, 1);
  EXPECT_EQ(same, (std::vector<std::int64_t>{0, 1, 2, 3, 4}));
  const auto fewer = resampleIndices(10, 4, 3);
  EXPECT_EQ(fewer.size(), 4u);
  EXPECT_EQ(std::set<std::int64_t>(fewer.begin(), fewer.end()).size(), 4u);
  const auto more = resampleIndices(3, 8, 3);
  EXPECT_EQ(more.size(), 8u);
  EXPECT_EQ(std::set<std::int64_t>(more.begin(), more.end()).size(), 3u);  // every point kept
  EXPECT_EQ(resampleIndices(10, 4, 3), fewer);                             // deterministic
  EXPECT_THROW(resampleIndices(0, 4, 1), paco::InvalidInputError);
}

#if PACO_HAVE_DATA
namespace {

// Two planes of a unit cube, z = 0 (outward -z) and x = 1 (outward +x); the input sees part of them.
paco::data::Sample cubeSample() {
  paco::data::Sample s;
  s.part = "cube";
  s.gt_planes = {paco::Plane(Eigen::Vector3d(0, 0, -1), 0.0), paco::Plane(Eigen::Vector3d(1, 0, 0), -1.0)};
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) {
      pcl::PointNormal p;
      p.x = i / 9.f; p.y = j / 9.f; p.z = 0.f;
      p.normal_x = 0; p.normal_y = 0; p.normal_z = -1;
      s.gt_points.push_back(p);
      s.gt_labels.push_back(0);
      if (i < 5) { s.input.push_back(p); s.input_labels.push_back(0); }
      pcl::PointNormal q;
      q.x = 1.f; q.y = i / 9.f; q.z = j / 9.f;
      q.normal_x = 1; q.normal_y = 0; q.normal_z = 0;
      s.gt_points.push_back(q);
      s.gt_labels.push_back(1);
      if (j < 3) { s.input.push_back(q); s.input_labels.push_back(1); }
    }
  return s;
}

}  // namespace

TEST(Batch, CollateOwnFrameMovesInputAndTruthTogether) {
  CollateOptions options;
  options.input_points = 64;
  options.gt_points = 150;
  options.input_frame = "own";
  options.augment_scale = 0.2;
  options.augment_offset = 0.05;
  const TrainingBatch batch = collate({cubeSample(), cubeSample()}, options, 3);
  ASSERT_EQ(batch.input.points.sizes(), (std::vector<std::int64_t>{2, 64, 3}));
  ASSERT_EQ(batch.truth.points.sizes(), (std::vector<std::int64_t>{2, 150, 3}));
  ASSERT_EQ(batch.truth.normals.sizes(), (std::vector<std::int64_t>{2, 2, 3}));
  EXPECT_TRUE(batch.truth.mask.all().item<bool>());
  for (int b = 0; b < 2; ++b) {
    // Every GT point lies on its transformed plane n·x = r; normals keep their outward direction.
    const auto n = batch.truth.normals[b].index_select(0, batch.truth.labels[b]);
    const auto r = batch.truth.offsets[b].index_select(0, batch.truth.labels[b]);
    EXPECT_LT(((batch.truth.points[b] * n).sum(-1) - r).abs().max().item<double>(), 1e-5);
    EXPECT_NEAR(batch.truth.normals[b][0][2].item<double>(), -1.0, 1e-6);
    // The input's own box has a diagonal of 1 up to the augmentation scale (within 20 %).
    const auto lo = std::get<0>(batch.input.points[b].min(0)), hi = std::get<0>(batch.input.points[b].max(0));
    const double diagonal = (hi - lo).norm().item<double>();
    EXPECT_GT(diagonal, 0.79);
    EXPECT_LT(diagonal, 1.21);
  }
  // Without augmentation the own frame is exact: centre at the origin, unit diagonal.
  options.augment_scale = options.augment_offset = 0.0;
  const TrainingBatch plain = collate({cubeSample()}, options, 3);
  const auto lo = std::get<0>(plain.input.points[0].min(0)), hi = std::get<0>(plain.input.points[0].max(0));
  EXPECT_NEAR((hi - lo).norm().item<double>(), 1.0, 1e-5);
  EXPECT_LT(((hi + lo) * 0.5).abs().max().item<double>(), 1e-5);
  // The complete frame leaves coordinates alone: the plane x = 1 keeps r = 1.
  options.input_frame = "complete";
  const TrainingBatch same = collate({cubeSample()}, options, 3);
  EXPECT_NEAR(same.truth.offsets[0][1].item<double>(), 1.0, 1e-6);
  EXPECT_NEAR(same.truth.offsets[0][0].item<double>(), 0.0, 1e-6);
}

TEST(Batch, CollateSeenPlanesTurnsTheSampleOntoTheAxes) {
  // The cube sample turned by 30 degrees about (1, 2, 0): its faces are on no axis.
  const Eigen::Matrix3d R0 =
      Eigen::AngleAxisd(paco::degreesToRadians(30.0), Eigen::Vector3d(1, 2, 0).normalized()).toRotationMatrix();
  paco::data::Sample s = cubeSample();
  for (auto* cloud : {&s.input, &s.gt_points})
    for (auto& p : *cloud) {
      p.getVector3fMap() = (R0 * p.getVector3fMap().cast<double>()).cast<float>();
      p.getNormalVector3fMap() = (R0 * p.getNormalVector3fMap().cast<double>()).cast<float>();
    }
  for (auto& plane : s.gt_planes) plane = paco::Plane::fromPointAndNormal(R0 * plane.foot(), R0 * plane.normal);
  CollateOptions options;
  options.input_points = 64;
  options.gt_points = 150;
  options.input_frame = "own";
  options.input_orientation = "seen-planes";
  const TrainingBatch batch = collate({s}, options, 3);
  // The faces are back on the axes (the turn closest to the identity undoes R0 exactly)...
  EXPECT_NEAR(batch.truth.normals[0][0][2].item<double>(), -1.0, 1e-5);
  EXPECT_NEAR(batch.truth.normals[0][1][0].item<double>(), 1.0, 1e-5);
  const auto input_normals = batch.input.normals[0];
  EXPECT_NEAR(std::get<0>(input_normals.abs().max(-1)).min().item<double>(), 1.0, 1e-5);
  // ...the truth still lies on its planes, and the input's box in the turned axes is the unit one.
  const auto n = batch.truth.normals[0].index_select(0, batch.truth.labels[0]);
  const auto r = batch.truth.offsets[0].index_select(0, batch.truth.labels[0]);
  EXPECT_LT(((batch.truth.points[0] * n).sum(-1) - r).abs().max().item<double>(), 1e-5);
  const auto lo = std::get<0>(batch.input.points[0].min(0)), hi = std::get<0>(batch.input.points[0].max(0));
  EXPECT_NEAR((hi - lo).norm().item<double>(), 1.0, 1e-5);
  EXPECT_LT(((hi + lo) * 0.5).abs().max().item<double>(), 1e-5);
  // The same as collating the unturned sample.
  EXPECT_TRUE(torch::allclose(batch.truth.points, collate({cubeSample()}, options, 3).truth.points, 1e-4, 1e-5));

  options.input_frame = "complete";  // the paper's frame is never turned
  EXPECT_THROW(collate({s}, options, 3), paco::InvalidInputError);
  options.input_frame = "own";
  options.input_orientation = "sideways";
  EXPECT_THROW(collate({s}, options, 3), paco::InvalidInputError);
}

TEST(Batch, CollateJitterMovesTheInputOnly) {
  CollateOptions options;
  options.input_points = 64;
  options.gt_points = 150;
  const TrainingBatch clean = collate({cubeSample()}, options, 5);
  // The clean input lies on z = 0 or x = 1 exactly.
  const auto off_plane = [](const torch::Tensor& points) {
    return torch::minimum(points.select(-1, 2).abs(), (points.select(-1, 0) - 1.0).abs());
  };
  EXPECT_LT(off_plane(clean.input.points[0]).max().item<double>(), 1e-6);

  options.augment_jitter = 0.05;
  const TrainingBatch noisy = collate({cubeSample()}, options, 5);
  EXPECT_TRUE(torch::equal(noisy.truth.points, clean.truth.points));  // the truth stays put
  EXPECT_TRUE(torch::equal(noisy.input.labels, clean.input.labels));  // the same points, moved
  const double spread = off_plane(noisy.input.points[0]).max().item<double>();
  EXPECT_GT(spread, 1e-4);
  EXPECT_LT(spread, 5 * 0.05);  // within five sigma of the largest sigma
  EXPECT_TRUE(torch::equal(noisy.input.points, collate({cubeSample()}, options, 5).input.points));  // repeatable
}

TEST(Batch, CollateRejectsBrokenSamples) {
  CollateOptions options;
  EXPECT_THROW(collate({}, options, 1), paco::InvalidInputError);
  auto s = cubeSample();
  s.gt_labels[3] = 7;
  EXPECT_THROW(collate({s}, options, 1), paco::InvalidInputError);
  auto t = cubeSample();
  t.input_labels.pop_back();
  EXPECT_THROW(collate({t}, options, 1), paco::InvalidInputError);
  options.input_frame = "nonsense";
  EXPECT_THROW(collate({cubeSample()}, options, 1), paco::InvalidInputError);
}
#endif

TEST(Losses, LargeChamferUsesKdTreesWithTheSameResult) {
  // 1500 x 1600 pairs exceed the brute-force limit: the kd-tree path must give the exact value.
  torch::manual_seed(3);
  const auto a = torch::rand({1500, 3});
  const auto b = torch::rand({1600, 3}) + 0.05;
  const auto d = pairwiseSquaredDistances(a, b);
  const double expected = (std::get<0>(d.min(1)).mean() + std::get<0>(d.min(0)).mean()).item<double>();
  EXPECT_NEAR(chamferSquared(a, b).item<double>(), expected, 1e-6 * expected);
}

namespace {

// Chamfer (squared L2) of two point sets from the full distance matrix: the reference.
double referenceChamfer(const torch::Tensor& a, const torch::Tensor& b) {
  const auto d = pairwiseSquaredDistances(a.to(torch::kDouble), b.to(torch::kDouble));
  return (std::get<0>(d.min(1)).mean() + std::get<0>(d.min(0)).mean()).item<double>();
}

// A random batch: B samples, M predictions of P points, N GT points on `planes` labelled planes.
Scene randomScene(int B, int M, int P, int N, int planes, int seed) {
  torch::manual_seed(seed);
  Scene s;
  s.truth.points = torch::rand({B, N, 3});
  s.truth.labels = torch::randint(0, planes, {B, N}, torch::kLong);
  s.truth.normals = torch::nn::functional::normalize(torch::randn({B, planes, 3}),
                                                     torch::nn::functional::NormalizeFuncOptions().dim(-1));
  s.truth.offsets = torch::rand({B, planes});
  s.truth.mask = torch::ones({B, planes}, torch::kBool);
  s.output.normals = torch::nn::functional::normalize(torch::randn({B, M, 3}),
                                                      torch::nn::functional::NormalizeFuncOptions().dim(-1));
  s.output.offsets = torch::rand({B, M});
  s.output.points = torch::rand({B, M, P, 3});
  s.output.logits = torch::randn({B, M});
  return s;
}

}  // namespace

TEST(Losses, MatchingChamferCostEqualsTheDistanceMatrixFormula) {
  const Scene s = randomScene(2, 7, 24, 300, 5, 11);
  LossConfig config;
  config.classification = config.normal = config.offset = config.repulsion = false;
  config.match_gt_points = 0;  // all points: the formula below uses all of them
  config.match_points_per_plane = 0;
  for (int b = 0; b < 2; ++b) {
    const Eigen::MatrixXd cost = matchingCost(s.output, s.truth, b, config);
    for (int g = 0; g < 5; ++g) {
      const auto members = torch::nonzero(s.truth.labels[b] == g).view({-1});
      for (int j = 0; j < 7; ++j) {
        const double expected =
            config.match_chamfer_weight * referenceChamfer(s.output.points[b][j], s.truth.points[b].index_select(0, members));
        EXPECT_NEAR(cost(g, j), expected, 1e-5 * expected) << "sample " << b << " plane " << g << " prediction " << j;
      }
    }
  }
}

TEST(Losses, BatchedChamferTermsEqualThePerPairFormula) {
  const Scene s = randomScene(3, 6, 20, 250, 4, 12);
  LossConfig config;
  config.ranking = false;
  const LossResult r = computeLosses(s.output, s.truth, config);
  double plane = 0.0, overall = 0.0;
  for (int b = 0; b < 3; ++b) {
    std::vector<torch::Tensor> matched;
    for (int g = 0; g < 4; ++g) {
      const int j = r.matching[b][g];
      ASSERT_GE(j, 0);
      const auto members = torch::nonzero(s.truth.labels[b] == g).view({-1});
      plane += referenceChamfer(s.output.points[b][j], s.truth.points[b].index_select(0, members));
      matched.push_back(s.output.points[b][j]);
    }
    overall += referenceChamfer(torch::cat(matched), s.truth.points[b]);
  }
  EXPECT_NEAR(r.terms.at("plane_chamfer"), config.plane_chamfer_weight * plane / 3.0, 1e-5 * plane);
  EXPECT_NEAR(r.terms.at("overall_chamfer"), config.overall_chamfer_weight * overall / 3.0, 1e-5 * overall);
}

TEST(Losses, RepulsionNeighboursEqualTopK) {
  torch::manual_seed(5);
  const auto x = torch::rand({3, 40, 3}) * 0.1;
  const int k = 5;
  const double h = 0.03, radius = 0.07;
  // Reference: k nearest from the full (masked) distance matrix.
  const auto d2 = (x.unsqueeze(2) - x.unsqueeze(1)).pow(2).sum(-1) + torch::eye(40).unsqueeze(0) * 1e10;
  const auto nearest = std::get<0>(torch::topk(d2, k, -1, /*largest=*/false)).clamp_min(1e-12);
  const auto expected = (radius - nearest.sqrt() * torch::exp(-nearest / (h * h))).mean({1, 2});
  EXPECT_TRUE(torch::allclose(repulsionLoss(x, k, h, radius), expected, 1e-5, 1e-7));
}
