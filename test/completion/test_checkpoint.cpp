#include "shapes.h"
#include "test_network_support.h"
#include "test_support.h"

#include <paco/common/error.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/parametric_completer.h>
#include <paco/encoding/completion_model.h>
#include <paco/encoding/plane_proxy_encoder.h>

#include <gtest/gtest.h>

#include <limits>

namespace paco {
namespace {

using test::boxBatch;
using test::tinyModelConfig;

std::string errorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const ModelError& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("WRONG TYPE: ") + e.what();
  }
  return "NO ERROR";
}

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(Checkpoint, LoadedModelGivesIdenticalOutputs) {
  test::TempDir dir;
  torch::manual_seed(1);
  PacoNetwork net(tinyModelConfig("polar"));
  net->eval();
  saveCheckpoint(dir.file("model.pt"), net);
  auto loaded = loadCheckpoint(dir.file("model.pt"));
  EXPECT_EQ(loaded.config, net->config());
  EXPECT_EQ(loaded.format_version, kCheckpointFormatVersion);
  EXPECT_FALSE(loaded.training_state);
  torch::NoGradGuard no_grad;
  const auto input = boxBatch(2, 300);
  const auto a = net->forward(input), b = loaded.network->forward(input);
  EXPECT_TRUE(a.points.equal(b.points));
  EXPECT_TRUE(a.normals.equal(b.normals));
  EXPECT_TRUE(a.offsets.equal(b.offsets));
  EXPECT_TRUE(a.logits.equal(b.logits));
  EXPECT_TRUE(a.candidate_scores.equal(b.candidate_scores));
  EXPECT_TRUE(a.selected.equal(b.selected));
}

TEST(Checkpoint, TrainingStateRoundTrips) {
  test::TempDir dir;
  PacoNetwork net(tinyModelConfig());
  torch::serialize::OutputArchive state;
  state.write("epoch", c10::IValue(static_cast<int64_t>(17)));
  state.write("moments", torch::arange(5));
  saveCheckpoint(dir.file("model.pt"), net, &state);
  const auto loaded = loadCheckpoint(dir.file("model.pt"), tinyModelConfig());
  ASSERT_TRUE(loaded.training_state);
  c10::IValue epoch;
  loaded.training_state->read("epoch", epoch);
  EXPECT_EQ(epoch.toInt(), 17);
  torch::Tensor moments;
  loaded.training_state->read("moments", moments);
  EXPECT_TRUE(moments.equal(torch::arange(5)));
}

TEST(Checkpoint, MissingFileIsAModelError) {
  test::TempDir dir;
  const auto message = errorOf([&] { loadCheckpoint(dir.file("nope.pt")); });
  EXPECT_TRUE(contains(message, "does not exist")) << message;
  EXPECT_TRUE(contains(message, "nope.pt")) << message;
}

TEST(Checkpoint, CorruptFileIsAModelError) {
  test::TempDir dir;
  test::writeBytes(dir.file("junk.pt"), "this is not a LibTorch archive at all\n");
  const auto message = errorOf([&] { loadCheckpoint(dir.file("junk.pt")); });
  EXPECT_TRUE(contains(message, "corrupt")) << message;
  EXPECT_TRUE(contains(message, "junk.pt")) << message;
  const auto model_message = errorOf([&] { CompletionModel::load(dir.file("junk.pt")); });
  EXPECT_TRUE(contains(model_message, "corrupt")) << model_message;
}

TEST(Checkpoint, TruncatedFileIsAModelError) {
  test::TempDir dir;
  PacoNetwork net(tinyModelConfig());
  saveCheckpoint(dir.file("model.pt"), net);
  const std::string bytes = test::readBytes(dir.file("model.pt"));
  for (double fraction : {0.5, 0.9}) {
    test::writeBytes(dir.file("cut.pt"), bytes.substr(0, static_cast<std::size_t>(bytes.size() * fraction)));
    const auto message = errorOf([&] { loadCheckpoint(dir.file("cut.pt")); });
    EXPECT_TRUE(contains(message, "cut.pt")) << message;
    EXPECT_FALSE(contains(message, "WRONG TYPE") || contains(message, "NO ERROR")) << message;
  }
}

TEST(Checkpoint, OtherFormatVersionIsAModelErrorNamingBoth) {
  test::TempDir dir;
  torch::serialize::OutputArchive archive;
  archive.write("format_version", c10::IValue(static_cast<int64_t>(kCheckpointFormatVersion + 1)));
  archive.write("config", c10::IValue(tinyModelConfig().toJson()));
  archive.save_to(dir.file("future.pt"));
  const auto message = errorOf([&] { loadCheckpoint(dir.file("future.pt")); });
  const std::string expected = "was written by format v" +
                               std::to_string(kCheckpointFormatVersion + 1) + "; this build reads v" +
                               std::to_string(kCheckpointFormatVersion);
  EXPECT_TRUE(contains(message, expected)) << message;
}

TEST(Checkpoint, FileWithoutVersionIsAModelError) {
  test::TempDir dir;
  torch::serialize::OutputArchive archive;
  archive.write("weights", torch::ones({3}));
  archive.save_to(dir.file("foreign.pt"));
  const auto message = errorOf([&] { loadCheckpoint(dir.file("foreign.pt")); });
  EXPECT_TRUE(contains(message, "no paco format version")) << message;
}

TEST(Checkpoint, MismatchedConfigIsAModelErrorNamingTheField) {
  test::TempDir dir;
  PacoNetwork net(tinyModelConfig());
  saveCheckpoint(dir.file("model.pt"), net);
  ModelConfig other = tinyModelConfig();
  other.decoder_depth = 3;
  const auto message = errorOf([&] { loadCheckpoint(dir.file("model.pt"), other); });
  EXPECT_TRUE(contains(message, "decoder_depth")) << message;
}

TEST(Checkpoint, WeightsThatDoNotFitTheirConfigAreAModelError) {
  test::TempDir dir;
  // Weights of a wider network stored under the tiny config.
  ModelConfig wide = tinyModelConfig();
  wide.width = 48;
  PacoNetwork net(wide);
  torch::serialize::OutputArchive model;
  net->save(model);
  writeModelFile(dir.file("mixed.pt"), tinyModelConfig(), model, parameterCount(*net));
  const auto message = errorOf([&] { loadCheckpoint(dir.file("mixed.pt")); });
  EXPECT_TRUE(contains(message, "shape")) << message;
  // A file whose weights miss a layer.
  ModelConfig deeper = tinyModelConfig();
  deeper.decoder_depth = 3;
  torch::serialize::OutputArchive shallow;
  net = PacoNetwork(tinyModelConfig());
  net->save(shallow);
  writeModelFile(dir.file("shallow.pt"), deeper, shallow, 0);
  const auto missing = errorOf([&] { loadCheckpoint(dir.file("shallow.pt")); });
  EXPECT_TRUE(contains(missing, "do not match")) << missing;
}

// Stages 2-3 on a box segmented by face.
void completeABox(const CompletionModel::ConstPtr& model) {
  const SurfaceMesh box = test::makeBox({0, 0, 0}, {2, 1, 1});
  const SurfaceSample sample = sampleSurface(box, 1024, 3);
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  PlanarSegmentation segmentation;
  for (std::size_t f = 0; f < box.faces.size(); ++f)
    segmentation.planes.push_back(Plane::fromPointAndNormal(box.vertices[box.faces[f][0]], faceNormal(box, f)));
  for (std::size_t i = 0; i < sample.points.size(); ++i) {
    pcl::PointNormal p;
    p.getVector3fMap() = sample.points[i].cast<float>();
    p.getNormalVector3fMap() = sample.normals[i].cast<float>();
    cloud->push_back(p);
    segmentation.labels.push_back(static_cast<int>(sample.faces[i]));
  }
  segmentation.rebuildSegmentsFromLabels();
  PlaneProxyEncoder encoder;
  encoder.setModel(model);
  encoder.setInputCloud(cloud);
  encoder.setSegmentation(segmentation);
  PlaneProxies proxies;
  encoder.encode(proxies);
  ParametricCompleter completer;
  completer.setModel(model);
  completer.setInputProxies(proxies);
  std::vector<PlanarPrimitive> primitives;
  completer.complete(primitives);
}

// One byte changed inside a weight tensor leaves a valid archive that LibTorch reads without
// complaint; the stored checksums must catch it, for the network, the encoder and the decoder.
TEST(Checkpoint, ADamagedWeightTensorIsAModelError) {
  test::TempDir dir;
  PacoNetwork net(tinyModelConfig());
  torch::NoGradGuard no_grad;
  std::string encoder_tensor, decoder_tensor;
  for (const auto& item : net->named_parameters()) {
    std::string& name = item.key().rfind("encoder.", 0) == 0 ? encoder_tensor : decoder_tensor;
    if (name.empty() && item.value().numel() >= 4) name = item.key();
  }
  ASSERT_FALSE(encoder_tensor.empty());
  ASSERT_FALSE(decoder_tensor.empty());
  for (const auto& [name, value] : {std::pair<std::string, float>{encoder_tensor, 1234.5f}, {decoder_tensor, -4321.25f}}) {
    SCOPED_TRACE(name);
    PacoNetwork copy(tinyModelConfig());
    copy->named_parameters()[name].fill_(value);
    saveCheckpoint(dir.file("model.pt"), copy);
    std::string bytes = test::readBytes(dir.file("model.pt"));
    // The tensor's bytes: four copies of `value` in a row, found in the stored record.
    std::string pattern;
    for (int i = 0; i < 4; ++i) pattern.append(reinterpret_cast<const char*>(&value), sizeof value);
    const std::size_t at = bytes.find(pattern);
    ASSERT_NE(at, std::string::npos);
    bytes[at + 5] = static_cast<char>(bytes[at + 5] ^ 0x10);  // 1234.5 -> another finite number
    test::writeBytes(dir.file("damaged.pt"), bytes);

    const std::string whole = errorOf([&] { loadCheckpoint(dir.file("damaged.pt")); });
    EXPECT_TRUE(contains(whole, "does not match the checksum stored with it")) << whole;
    EXPECT_TRUE(contains(whole, "damaged.pt")) << whole;
    const bool in_encoder = name == encoder_tensor;
    const std::string stage = errorOf([&] {
      const auto model = CompletionModel::load(dir.file("damaged.pt"));
      if (!in_encoder) completeABox(model);  // the decoder's weights are read when the completer first runs
    });
    EXPECT_TRUE(contains(stage, std::string(in_encoder ? "the encoder tensor '" : "the decoder tensor '") +
                                    name.substr(8) + "' does not match the checksum"))
        << stage;
  }
  // A file written without checksums (as before they existed) still loads.
  torch::serialize::OutputArchive model;
  net->save(model);
  writeModelFile(dir.file("unchecked.pt"), tinyModelConfig(), model, parameterCount(*net));
  EXPECT_EQ(errorOf([&] { loadCheckpoint(dir.file("unchecked.pt")); }), "NO ERROR");
}

// NaN or infinite weights (damaged bytes, or a diverged training run) are refused, in files with
// checksums (which match such values) and without them (the shipped model's kind), not run into
// a completion that finds no plane.
TEST(Checkpoint, NonFiniteWeightsAreAModelErrorWithOrWithoutChecksums) {
  test::TempDir dir;
  torch::NoGradGuard no_grad;
  for (const float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity()}) {
    SCOPED_TRACE(bad);
    PacoNetwork net(tinyModelConfig());
    std::string name;
    for (const auto& item : net->named_parameters())
      if (name.empty() && item.key().rfind("encoder.", 0) == 0) name = item.key();
    ASSERT_FALSE(name.empty());
    net->named_parameters()[name].view(-1)[0] = bad;
    saveCheckpoint(dir.file("checked.pt"), net);
    torch::serialize::OutputArchive archive;
    net->save(archive);
    writeModelFile(dir.file("unchecked.pt"), tinyModelConfig(), archive, parameterCount(*net));
    for (const char* file : {"checked.pt", "unchecked.pt"}) {
      const std::string error = errorOf([&] { CompletionModel::load(dir.file(file)); });
      EXPECT_TRUE(contains(error, "the encoder tensor '" + name.substr(8) + "' holds NaN or infinite values"))
          << error;
      EXPECT_TRUE(contains(error, file)) << error;
    }
  }
}

TEST(Checkpoint, UnwritableFolderIsAnIoError) {
  PacoNetwork net(tinyModelConfig());
  EXPECT_THROW(saveCheckpoint("/nonexistent-folder/model.pt", net), IoError);
}

}  // namespace
}  // namespace paco
