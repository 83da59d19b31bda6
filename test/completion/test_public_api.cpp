#include "shapes.h"
#include "test_network_support.h"
#include "test_support.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/parametric_completer.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/encoding/completion_model.h>
#include <paco/encoding/plane_proxy_encoder.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <numeric>

namespace paco {
namespace {

// A 4 x 2 x 1 box far from the origin (user units), sampled with 2,048 points, segmented by face.
struct SegmentedBox {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud;
  PlanarSegmentation segmentation;
  SegmentedBox() {
    test::FaceLabelledScan scan = test::scanByFace(test::makeBox({10, -5, 3}, {14, -3, 4}), 2048, 7);
    cloud = scan.cloud;
    segmentation = std::move(scan.segmentation);
  }
};

class PublicApi : public ::testing::Test {
 protected:
  void SetUp() override {
    torch::manual_seed(2);
    PacoNetwork net(test::tinyModelConfig());
    saveCheckpoint(dir.file("tiny.pt"), net);
    model = CompletionModel::load(dir.file("tiny.pt"));
  }
  // Stage 2: the input's planes encoded by the fixture's model.
  PlaneProxies encode(const SegmentedBox& input, const Eigen::Matrix3d& turn = Eigen::Matrix3d::Identity()) const {
    PlaneProxyEncoder encoder;
    encoder.setModel(model);
    encoder.setInputCloud(input.cloud);
    encoder.setSegmentation(input.segmentation);
    encoder.setTurn(turn);
    PlaneProxies proxies;
    encoder.encode(proxies);
    return proxies;
  }
  // Stages 2-3 once, every prediction kept; `proxies` receives the encoder's output.
  std::vector<PlanarPrimitive> completeAll(const SegmentedBox& input, PlaneProxies& proxies,
                                           const Eigen::Matrix3d& turn = Eigen::Matrix3d::Identity()) const {
    proxies = encode(input, turn);
    ParametricCompleter completer;
    completer.setModel(model);
    completer.setInputProxies(proxies);
    completer.setConfidenceThreshold(0.0);
    std::vector<PlanarPrimitive> primitives;
    completer.complete(primitives);
    return primitives;
  }
  test::TempDir dir;
  CompletionModel::ConstPtr model;
  SegmentedBox box;
};

TEST_F(PublicApi, CompletionModelReportsItsConfig) {
  EXPECT_EQ(model->config(), test::tinyModelConfig());
  EXPECT_EQ(model->path(), dir.file("tiny.pt"));
  EXPECT_EQ(model->parameterCount(), parameterCount(*PacoNetwork(test::tinyModelConfig())));
}

TEST_F(PublicApi, EncoderFillsTheProxies) {
  const PlaneProxies proxies = encode(box);
  const auto& c = model->config();
  EXPECT_EQ(proxies.slots, c.plane_slots);
  EXPECT_EQ(proxies.width, c.width);
  EXPECT_EQ(proxies.features.size(), std::size_t(c.plane_slots * c.width));
  EXPECT_EQ(std::accumulate(proxies.mask.begin(), proxies.mask.end(), 0), 6);
  EXPECT_EQ(proxies.input_planes.size(), 6u);
  EXPECT_EQ(proxies.model, model);
  // Slot planes are the input face planes, in the normalised frame.
  for (int s = 0; s < 6; ++s) {
    const int segment = proxies.slot_segments[s];
    ASSERT_GE(segment, 0);
    const Plane expected = proxies.normalization.apply(box.segmentation.planes[segment]);
    EXPECT_NEAR(proxies.slot_planes[s].normal.dot(expected.normal), 1.0, 1e-5);
    EXPECT_NEAR(proxies.slot_planes[s].offset, expected.offset, 1e-5);
  }
}

TEST_F(PublicApi, CompleteReturnsTheNetworkOutputInTheUsersFrame) {
  PlaneProxies proxies;
  const std::vector<PlanarPrimitive> primitives = completeAll(box, proxies);

  // The same cloud through the network directly, in the normalised frame.
  const Normalization norm = Normalization::fromBoundingBox(*box.cloud);
  const int64_t n = int64_t(box.cloud->size());
  NetworkInput input{torch::empty({1, n, 3}), torch::empty({1, n, 3}), torch::empty({1, n}, torch::kLong)};
  for (int64_t i = 0; i < n; ++i) {
    const auto& p = box.cloud->points[i];
    const Eigen::Vector3d x = norm.apply(Eigen::Vector3d(p.x, p.y, p.z));
    const int label = box.segmentation.labels[i];
    for (int a = 0; a < 3; ++a) {
      input.points[0][i][a] = float(x[a]);
      input.normals[0][i][a] = float(box.segmentation.planes[label].normal[a]);
    }
    input.labels[0][i] = label;
  }
  auto network = loadCheckpoint(dir.file("tiny.pt")).network;
  torch::NoGradGuard no_grad;
  const auto out = network->forward(input);
  auto confidence = torch::sigmoid(out.logits[0]);
  auto order = std::get<1>(confidence.sort(0, /*descending=*/true));

  const int64_t M = model->config().kept_queries, P = model->config().points_per_plane;
  ASSERT_EQ(int64_t(primitives.size()), M);  // threshold 0 keeps every query
  const double unit = 1.0 / norm.scale;       // one normalised unit in user units
  for (int64_t i = 0; i < M; ++i) {
    const int64_t m = order[i].item<int64_t>();
    const auto& primitive = primitives[i];
    EXPECT_NEAR(primitive.confidence, confidence[m].item<float>(), 1e-5);
    Eigen::Vector3d normal(out.normals[0][m][0].item<float>(), out.normals[0][m][1].item<float>(),
                           out.normals[0][m][2].item<float>());
    const Plane expected = norm.applyInverse(Plane(normal, -out.offsets[0][m].item<float>()));
    EXPECT_NEAR(primitive.plane.normal.dot(expected.normal), 1.0, 1e-5);
    EXPECT_NEAR(primitive.plane.offset, expected.offset, 1e-4 * unit);
    ASSERT_EQ(int64_t(primitive.points.size()), P);
    for (int64_t j = 0; j < P; ++j) {
      const auto& q = primitive.points[j];
      const Eigen::Vector3d x(q.x, q.y, q.z);
      const Eigen::Vector3d want = norm.applyInverse(Eigen::Vector3d(
          out.points[0][m][j][0].item<float>(), out.points[0][m][j][1].item<float>(),
          out.points[0][m][j][2].item<float>()));
      EXPECT_LT((x - want).norm(), 1e-4 * unit);
      EXPECT_LT(std::abs(primitive.plane.signedDistance(x)), 1e-4 * unit);
    }
  }
}

TEST_F(PublicApi, SeenPlanesModelCompletesATurnedScanAsTheUnturnedOneTurned) {
  ModelConfig config = test::tinyModelConfig();
  config.input_orientation = "seen-planes";
  torch::manual_seed(2);
  PacoNetwork net(config);
  saveCheckpoint(dir.file("turning.pt"), net);
  const auto turning = CompletionModel::load(dir.file("turning.pt"));

  // The box turned by 30 degrees about an oblique axis through a corner, in user units.
  const Eigen::Matrix3d R0 =
      Eigen::AngleAxisd(paco::degreesToRadians(30.0), Eigen::Vector3d(1, 2, 0.5).normalized()).toRotationMatrix();
  const Eigen::Vector3d pivot(10, -5, 3);
  SegmentedBox turned;
  for (auto& p : turned.cloud->points) {
    p.getVector3fMap() = (pivot + R0 * (p.getVector3fMap().cast<double>() - pivot)).cast<float>();
    p.getNormalVector3fMap() = (R0 * p.getNormalVector3fMap().cast<double>()).cast<float>();
  }
  for (auto& plane : turned.segmentation.planes)
    plane = Plane::fromPointAndNormal(pivot + R0 * (plane.foot() - pivot), R0 * plane.normal);

  const auto run = [&](const SegmentedBox& input, PlaneProxies& proxies) {
    PlaneProxyEncoder encoder;
    encoder.setModel(turning);
    encoder.setInputCloud(input.cloud);
    encoder.setSegmentation(input.segmentation);
    encoder.encode(proxies);
    ParametricCompleter completer;
    completer.setModel(turning);
    completer.setInputProxies(proxies);
    completer.setConfidenceThreshold(0.0);
    std::vector<PlanarPrimitive> primitives;
    completer.complete(primitives);
    return primitives;
  };
  PlaneProxies straight_proxies, turned_proxies;
  const auto straight = run(box, straight_proxies);
  const auto completed = run(turned, turned_proxies);
  // The axis-aligned box is left as it is; the turned one is turned back.
  EXPECT_TRUE(straight_proxies.normalization.rotation.isApprox(Eigen::Matrix3d::Identity()));
  EXPECT_LT(Eigen::AngleAxisd(turned_proxies.normalization.rotation * R0).angle(), 1e-5);
  // So the network reads the same input and the completion comes back turned with the scan.
  ASSERT_EQ(straight_proxies.features.size(), turned_proxies.features.size());
  for (std::size_t i = 0; i < straight_proxies.features.size(); ++i)
    ASSERT_NEAR(straight_proxies.features[i], turned_proxies.features[i], 1e-3) << "feature " << i;
  ASSERT_EQ(straight.size(), completed.size());
  for (std::size_t i = 0; i < straight.size(); ++i) {
    EXPECT_NEAR(completed[i].confidence, straight[i].confidence, 1e-4);
    EXPECT_GT(completed[i].plane.normal.dot(R0 * straight[i].plane.normal), 1.0 - 1e-5);
    ASSERT_EQ(completed[i].points.size(), straight[i].points.size());
    for (std::size_t j = 0; j < straight[i].points.size(); j += 97) {
      const Eigen::Vector3d want = pivot + R0 * (straight[i].points[j].getVector3fMap().cast<double>() - pivot);
      EXPECT_LT((completed[i].points[j].getVector3fMap().cast<double>() - want).norm(), 1e-3);
    }
  }
}

TEST_F(PublicApi, AnEncoderTurnReadsTheScanAsTheTurnedScanAndAnswersInTheUsersFrame) {
  // A turn that swaps two axes, and the box turned by it about its centre.
  const Eigen::Matrix3d turn = ensembleTurns(kMaxEnsembleTurns)[5];
  ASSERT_FALSE(turn.cwiseAbs().isIdentity(0.0));  // not a half turn: the box's extents swap
  const Eigen::Vector3d centre(12, -4, 3.5);
  SegmentedBox turned;
  for (auto& p : turned.cloud->points) {
    p.getVector3fMap() = (centre + turn * (p.getVector3fMap().cast<double>() - centre)).cast<float>();
    p.getNormalVector3fMap() = (turn * p.getNormalVector3fMap().cast<double>()).cast<float>();
  }
  for (auto& plane : turned.segmentation.planes)
    plane = Plane::fromPointAndNormal(centre + turn * (plane.foot() - centre), turn * plane.normal);

  PlaneProxies by_turn_proxies, of_turned_proxies;
  const auto by_turn = completeAll(box, by_turn_proxies, turn);
  const auto of_turned = completeAll(turned, of_turned_proxies);
  EXPECT_TRUE(by_turn_proxies.normalization.rotation.isApprox(turn));
  EXPECT_TRUE(of_turned_proxies.normalization.rotation.isIdentity(0.0));
  // The network reads the same input, so the answers agree once the turned scan's is turned back.
  ASSERT_EQ(by_turn.size(), of_turned.size());
  for (std::size_t i = 0; i < by_turn.size(); ++i) {
    EXPECT_NEAR(by_turn[i].confidence, of_turned[i].confidence, 1e-4);
    EXPECT_GT(by_turn[i].plane.normal.dot(turn.transpose() * of_turned[i].plane.normal), 1.0 - 1e-5);
    ASSERT_EQ(by_turn[i].points.size(), of_turned[i].points.size());
    for (std::size_t j = 0; j < by_turn[i].points.size(); j += 13) {
      const Eigen::Vector3d want =
          centre + turn.transpose() * (of_turned[i].points[j].getVector3fMap().cast<double>() - centre);
      EXPECT_LT((by_turn[i].points[j].getVector3fMap().cast<double>() - want).norm(), 1e-3);
    }
  }
  // A turn that is not a rotation is refused.
  PlaneProxyEncoder encoder;
  encoder.setModel(model);
  encoder.setInputCloud(box.cloud);
  encoder.setSegmentation(box.segmentation);
  encoder.setTurn(Eigen::Vector3d(1, 1, -1).asDiagonal());
  PlaneProxies proxies;
  EXPECT_THROW(encoder.encode(proxies), InvalidInputError);
}

TEST_F(PublicApi, CompleteWithTurnsIsTheCompleterWithOneTurnAndAVoteWithMore) {
  TurnEnsembleOptions options;
  EXPECT_EQ(options.turns, 4);  // the default, measured in doc/results.md
  options.turns = 1;
  options.threshold = 0.0;
  Normalization frame;
  frame.scale = -1.0;
  const auto once = completeWithTurns(model, box.cloud, box.segmentation, options, &frame);
  PlaneProxies proxies;
  const auto direct = completeAll(box, proxies);
  EXPECT_DOUBLE_EQ(frame.scale, proxies.normalization.scale);
  EXPECT_TRUE(frame.center.isApprox(proxies.normalization.center));
  ASSERT_EQ(once.size(), direct.size());
  for (std::size_t i = 0; i < once.size(); ++i) {
    EXPECT_EQ(once[i].confidence, direct[i].confidence);
    EXPECT_TRUE(once[i].plane.normal.isApprox(direct[i].plane.normal));
    EXPECT_EQ(once[i].points.size(), direct[i].points.size());
  }

  // Four turns, every prediction voting: each merged primitive's confidence is a mean over the
  // turns, the primitives are sorted, and their points lie on their planes.
  options.turns = 4;
  options.candidate_threshold = 0.0;
  frame = Normalization{};
  const auto voted = completeWithTurns(model, box.cloud, box.segmentation, options, &frame);
  EXPECT_DOUBLE_EQ(frame.scale, proxies.normalization.scale);  // the unturned run's frame
  EXPECT_TRUE(frame.rotation.isIdentity(0.0));
  ASSERT_FALSE(voted.empty());
  const double unit = std::sqrt(21.0);  // the box's diagonal in user units
  for (std::size_t i = 0; i < voted.size(); ++i) {
    EXPECT_GT(voted[i].confidence, 0.0f);
    EXPECT_LE(voted[i].confidence, 1.0f);
    if (i > 0) {
      EXPECT_LE(voted[i].confidence, voted[i - 1].confidence);
    }
    ASSERT_FALSE(voted[i].points.empty());
    for (const auto& p : voted[i].points)
      EXPECT_LT(std::abs(voted[i].plane.signedDistance(p.getVector3fMap().cast<double>())), 1e-4 * unit);
  }
  options.candidate_threshold = 1.5;
  EXPECT_THROW(completeWithTurns(model, box.cloud, box.segmentation, options), InvalidInputError);
  options.candidate_threshold = 0.0;
  options.turns = 0;
  EXPECT_THROW(completeWithTurns(model, box.cloud, box.segmentation, options), InvalidInputError);
}

TEST_F(PublicApi, ThresholdKeepsOnlyConfidentPrimitivesSorted) {
  ParametricCompleter completer;
  completer.setModel(model);
  completer.setInputProxies(encode(box));
  std::vector<PlanarPrimitive> all, confident;
  completer.setConfidenceThreshold(0.0);
  completer.complete(all);
  // A threshold in the middle of the confidences splits them.
  const double threshold = (all.front().confidence + all.back().confidence) / 2;
  completer.setConfidenceThreshold(threshold);
  completer.complete(confident);
  const auto expected = std::count_if(all.begin(), all.end(), [&](const PlanarPrimitive& p) {
    return p.confidence > threshold;
  });
  EXPECT_EQ(std::ptrdiff_t(confident.size()), expected);
  EXPECT_GT(confident.size(), 0u);
  EXPECT_LT(confident.size(), all.size());
  for (std::size_t i = 0; i < confident.size(); ++i) {
    EXPECT_GT(confident[i].confidence, threshold);
    if (i > 0) {
      EXPECT_LE(confident[i].confidence, confident[i - 1].confidence);
    }
  }
  EXPECT_DOUBLE_EQ(ParametricCompleter().getConfidenceThreshold(), 0.7);
}

TEST_F(PublicApi, EncoderValidatesItsInput) {
  PlaneProxyEncoder encoder;
  PlaneProxies proxies;
  encoder.setModel(model);
  encoder.setSegmentation(box.segmentation);
  EXPECT_THROW(encoder.encode(proxies), InvalidInputError);  // no cloud
  encoder.setInputCloud(pcl::PointCloud<pcl::PointNormal>::Ptr(new pcl::PointCloud<pcl::PointNormal>));
  EXPECT_THROW(encoder.encode(proxies), InvalidInputError);  // empty cloud
  encoder.setInputCloud(box.cloud);
  PlanarSegmentation short_labels = box.segmentation;
  short_labels.labels.pop_back();
  encoder.setSegmentation(short_labels);
  try {
    encoder.encode(proxies);
    ADD_FAILURE() << "labels size mismatch accepted";
  } catch (const InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("2047 labels for 2048 points"), std::string::npos) << e.what();
  }
  encoder.setSegmentation(PlanarSegmentation{std::vector<int>(box.cloud->size(), -1), {}, {}});
  EXPECT_THROW(encoder.encode(proxies), InvalidInputError);  // no segment
  encoder.setSegmentation(box.segmentation);
  auto nan_cloud = pcl::PointCloud<pcl::PointNormal>::Ptr(new pcl::PointCloud<pcl::PointNormal>(*box.cloud));
  nan_cloud->points[5].x = std::numeric_limits<float>::quiet_NaN();
  encoder.setInputCloud(nan_cloud);
  EXPECT_THROW(encoder.encode(proxies), InvalidInputError);
  PlaneProxyEncoder no_model;
  no_model.setInputCloud(box.cloud);
  no_model.setSegmentation(box.segmentation);
  EXPECT_THROW(no_model.encode(proxies), ModelError);
}

TEST_F(PublicApi, CompleterValidatesItsInput) {
  ParametricCompleter completer;
  std::vector<PlanarPrimitive> primitives;
  completer.setModel(model);
  EXPECT_THROW(completer.complete(primitives), InvalidInputError);  // no proxies
  const PlaneProxies proxies = encode(box);
  completer.setInputProxies(proxies);
  completer.setConfidenceThreshold(1.5);
  EXPECT_THROW(completer.complete(primitives), InvalidInputError);
  completer.setConfidenceThreshold(0.7);
  ParametricCompleter no_model;
  no_model.setInputProxies(proxies);
  EXPECT_THROW(no_model.complete(primitives), ModelError);
  // Proxies from another model cannot be completed by this one.
  PacoNetwork other(test::tinyModelConfig());
  saveCheckpoint(dir.file("other.pt"), other);
  completer.setModel(CompletionModel::load(dir.file("other.pt")));
  EXPECT_THROW(completer.complete(primitives), ModelError);
}

TEST(CompletionModel, FindShippedModelHonoursTheEnvironment) {
  ::setenv("PACO_MODEL", "/some/where/model.pt", 1);
  EXPECT_EQ(CompletionModel::findShippedModel(), "/some/where/model.pt");
  ::unsetenv("PACO_MODEL");
  EXPECT_THROW(CompletionModel::load("/some/where/model.pt"), ModelError);
}

}  // namespace
}  // namespace paco

namespace paco {
namespace {

// The paco_complete tool end to end (skipped when the tool is not built: it needs the io and
// segmentation modules).
TEST(PacoCompleteTool, WritesPrimitivesAndFailsCleanly) {
  const std::string tool = test::toolPath("paco_complete");
  if (!std::filesystem::exists(tool)) GTEST_SKIP() << "paco_complete is not built";
  test::TempDir dir;
  PacoNetwork net(test::tinyModelConfig());
  saveCheckpoint(dir.file("tiny.pt"), net);
  SegmentedBox box;
  std::string xyz;
  for (const auto& p : box.cloud->points)
    xyz += std::to_string(p.x) + " " + std::to_string(p.y) + " " + std::to_string(p.z) + " " +
           std::to_string(p.normal_x) + " " + std::to_string(p.normal_y) + " " +
           std::to_string(p.normal_z) + "\n";
  test::writeBytes(dir.file("box.xyz"), xyz);
  std::string output;
  const std::string common = tool + " " + dir.file("box.xyz") + " --segmenter region-growing --threads 1";
  EXPECT_EQ(test::runCommand(common + " -o " + dir.file("out.vg") + " --pcd " + dir.file("out.pcd") +
                                 " --threshold 0 --turns 1 --model " + dir.file("tiny.pt"),
                             &output),
            0)
      << output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("out.vg"))) << output;
  EXPECT_TRUE(std::filesystem::exists(dir.file("out.pcd"))) << output;
  EXPECT_NE(output.find("complete: 6 primitives"), std::string::npos) << output;  // one run: M = 6
  EXPECT_EQ(output.find("turned by"), std::string::npos) << output;  // an "as-is" model
  // A "seen-planes" model turns a box turned by 20 degrees about z back onto the axes, and says so.
  ModelConfig turning = test::tinyModelConfig();
  turning.input_orientation = "seen-planes";
  PacoNetwork turning_net(turning);
  saveCheckpoint(dir.file("turning.pt"), turning_net);
  const Eigen::Matrix3d R0 = Eigen::AngleAxisd(paco::degreesToRadians(20.0), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::string turned_xyz;
  for (const auto& p : box.cloud->points) {
    const Eigen::Vector3d x = R0 * p.getVector3fMap().cast<double>();
    turned_xyz += std::to_string(x.x()) + " " + std::to_string(x.y()) + " " + std::to_string(x.z()) + "\n";
  }
  test::writeBytes(dir.file("turned.xyz"), turned_xyz);
  EXPECT_EQ(test::runCommand(tool + " " + dir.file("turned.xyz") + " --segmenter region-growing --threads 1 -o " +
                                 dir.file("turned.vg") + " --threshold 0 --model " + dir.file("turning.pt"),
                             &output),
            0)
      << output;
  EXPECT_NE(output.find("turned by 20.0 deg"), std::string::npos) << output;
  EXPECT_NE(output.find("voted over 4 turns"), std::string::npos) << output;  // the default
  // Turns outside 1..24: a usage error (exit 2), no output file.
  EXPECT_EQ(test::runCommand(common + " -o " + dir.file("t.vg") + " --turns 25 --model " + dir.file("tiny.pt"), &output), 2);
  EXPECT_NE(output.find("--turns must be 1 to 24"), std::string::npos) << output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("t.vg")));
  // So is a known extent that is neither a point nor a box (fusion's option, shared with
  // paco_reconstruct).
  EXPECT_EQ(test::runCommand(common + " -o " + dir.file("t.vg") + " --known-extent 0,0,0,1,1 --model " + dir.file("tiny.pt"),
                             &output),
            2);
  EXPECT_NE(output.find("--known-extent takes X,Y,Z (a point), X0,Y0,Z0,X1,Y1,Z1 (a box)"), std::string::npos)
      << output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("t.vg")));
  // A corrupt model: a clear error, a non-zero exit and no output file.
  test::writeBytes(dir.file("bad.pt"), "garbage");
  EXPECT_NE(test::runCommand(common + " -o " + dir.file("bad.vg") + " --model " + dir.file("bad.pt"), &output), 0);
  EXPECT_NE(output.find("corrupt"), std::string::npos) << output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.vg")));
  EXPECT_NE(test::runCommand(common + " -o " + dir.file("x.txt") + " --model " + dir.file("tiny.pt"), &output), 0);
}

}  // namespace
}  // namespace paco
