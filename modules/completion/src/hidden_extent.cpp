#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/hash.h>
#include <paco/common/orientation.h>
#include <paco/completion/hidden_extent.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/encoding/model_file.h>
#include <paco/encoding/plane_proxy_encoder.h>

#include "decoder_access.h"

#include <torch/torch.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <mutex>

namespace paco {
namespace {

// Version of the head files this build writes and reads.
constexpr std::int64_t kExtentHeadFormat = 1;
// Marks a head file; a completion model file has no such entry.
const char kFormatKey[] = "paco_extent_head_format";

torch::nn::Sequential makeMlp(int features, int hidden) {
  return torch::nn::Sequential(torch::nn::Linear(features, hidden), torch::nn::GELU(), torch::nn::Dropout(0.2),
                               torch::nn::Linear(hidden, kBoxSides), torch::nn::Softplus());
}

torch::Tensor featureMatrix(const std::vector<ExtentExample>& examples, int width) {
  auto x = torch::empty({static_cast<std::int64_t>(examples.size()), width});
  for (std::size_t i = 0; i < examples.size(); ++i) {
    if (static_cast<int>(examples[i].features.size()) != width)
      throw InvalidInputError("extent examples: example " + std::to_string(i) + " has " +
                              std::to_string(examples[i].features.size()) + " features, the first has " +
                              std::to_string(width));
    std::copy(examples[i].features.begin(), examples[i].features.end(),
              x[static_cast<std::int64_t>(i)].data_ptr<float>());
  }
  return x;
}

torch::Tensor targetMatrix(const std::vector<ExtentExample>& examples) {
  auto y = torch::empty({static_cast<std::int64_t>(examples.size()), kBoxSides});
  for (std::size_t i = 0; i < examples.size(); ++i)
    std::copy(examples[i].beyond.begin(), examples[i].beyond.end(), y[static_cast<std::int64_t>(i)].data_ptr<float>());
  return y;
}

}  // namespace

struct HiddenExtentModel::Impl {
  std::string path;
  int feature_width = 0;
  int hidden = 0;
  std::uint64_t fingerprint = 0;
  torch::Tensor mean, spread;  // standardisation of the features, (F)
  // mutable: a forward pass is logically const, LibTorch's forward() is not.
  mutable torch::nn::Sequential mlp{nullptr};
  mutable std::mutex mutex;  // LibTorch modules are not documented as safe for concurrent forwards

  torch::Tensor forward(const torch::Tensor& features) const {
    return mlp->forward((features - mean) / spread);
  }
};

HiddenExtentModel::HiddenExtentModel(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

const std::string& HiddenExtentModel::path() const { return impl_->path; }
int HiddenExtentModel::featureWidth() const { return impl_->feature_width; }
std::uint64_t HiddenExtentModel::networkFingerprint() const { return impl_->fingerprint; }

void HiddenExtentModel::checkMatches(const CompletionModel& model) const {
  if (paco::networkFingerprint(model) != impl_->fingerprint)
    throw ModelError("the hidden-extent head '" + impl_->path + "' was trained on another completion network than '" +
                     model.path() + "'; use the model it was trained with or train a head for this one "
                     "(paco_train DATASET --extent-head-for MODEL -o HEAD.pt)");
  if (model.config().global_width + 3 != impl_->feature_width)
    throw ModelError("the hidden-extent head '" + impl_->path + "' takes " + std::to_string(impl_->feature_width) +
                     " features, the network '" + model.path() + "' gives " + std::to_string(model.config().global_width + 3));
}

std::array<double, kBoxSides> HiddenExtentModel::predict(const std::vector<float>& features) const {
  if (static_cast<int>(features.size()) != impl_->feature_width)
    throw InvalidInputError("HiddenExtentModel::predict: " + std::to_string(features.size()) + " features for a head of " +
                            std::to_string(impl_->feature_width));
  torch::Tensor out;
  {
    std::lock_guard<std::mutex> lock(impl_->mutex);
    torch::NoGradGuard no_grad;
    out = impl_->forward(torch::from_blob(const_cast<float*>(features.data()), {1, impl_->feature_width}).clone())
              .contiguous();
  }
  std::array<double, kBoxSides> beyond{};
  for (int s = 0; s < kBoxSides; ++s) beyond[static_cast<std::size_t>(s)] = out[0][s].item<float>();
  return beyond;
}

void HiddenExtentModel::save(const std::string& path) const {
  torch::serialize::OutputArchive root;
  root.write(kFormatKey, torch::tensor({kExtentHeadFormat}, torch::kLong));
  root.write("shape", torch::tensor({static_cast<std::int64_t>(impl_->feature_width), static_cast<std::int64_t>(impl_->hidden)},
                                    torch::kLong));
  std::int64_t fingerprint = 0;
  static_assert(sizeof fingerprint == sizeof impl_->fingerprint, "the fingerprint is stored as 64 bits");
  std::memcpy(&fingerprint, &impl_->fingerprint, sizeof fingerprint);
  root.write("network_fingerprint", torch::tensor({fingerprint}, torch::kLong));
  root.write("mean", impl_->mean);
  root.write("spread", impl_->spread);
  torch::serialize::OutputArchive mlp;
  impl_->mlp->save(mlp);
  root.write("mlp", mlp);
  saveArchiveAtomically(root, path, "hidden-extent head");
}

HiddenExtentModel::ConstPtr HiddenExtentModel::load(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec))
    throw ModelError("hidden-extent head '" + path + "' does not exist or is not a file; paco_train --extent-head-for "
                     "writes one (models/README.md)");
  auto impl = std::make_shared<Impl>();
  impl->path = path;
  try {
    torch::serialize::InputArchive root;
    root.load_from(path);
    torch::Tensor format;
    if (!root.try_read(kFormatKey, format))
      throw ModelError("'" + path + "' is not a hidden-extent head (a completion model goes to --model; "
                       "paco_train --extent-head-for writes heads)");
    if (format.numel() != 1 || format.item<std::int64_t>() != kExtentHeadFormat)
      throw ModelError("hidden-extent head '" + path + "' has format " + std::to_string(format.item<std::int64_t>()) +
                       "; this build reads format " + std::to_string(kExtentHeadFormat) + ": train it again");
    torch::Tensor shape, fingerprint;
    root.read("shape", shape);
    root.read("network_fingerprint", fingerprint);
    if (shape.numel() != 2 || fingerprint.numel() != 1)
      throw ModelError("hidden-extent head '" + path + "' is damaged (bad shape entries): train it again");
    impl->feature_width = static_cast<int>(shape[0].item<std::int64_t>());
    impl->hidden = static_cast<int>(shape[1].item<std::int64_t>());
    if (impl->feature_width < 1 || impl->hidden < 1)
      throw ModelError("hidden-extent head '" + path + "' is damaged (sizes " + std::to_string(impl->feature_width) +
                       " x " + std::to_string(impl->hidden) + "): train it again");
    const std::int64_t stored = fingerprint.item<std::int64_t>();
    std::memcpy(&impl->fingerprint, &stored, sizeof stored);
    root.read("mean", impl->mean);
    root.read("spread", impl->spread);
    if (impl->mean.numel() != impl->feature_width || impl->spread.numel() != impl->feature_width ||
        !(impl->spread > 0).all().item<bool>())
      throw ModelError("hidden-extent head '" + path + "' is damaged (feature scaling): train it again");
    impl->mlp = makeMlp(impl->feature_width, impl->hidden);
    torch::serialize::InputArchive mlp;
    root.read("mlp", mlp);
    impl->mlp->load(mlp);
    checkWeightsReadable(*impl->mlp, "hidden-extent head '" + path + "':");
  } catch (const c10::Error& e) {
    throw ModelError("hidden-extent head '" + path + "' is corrupt or truncated (" + e.what_without_backtrace() +
                     "): train it again or restore the file");
  }
  impl->mlp->eval();
  return std::make_shared<const HiddenExtentModel>(std::move(impl));
}

std::uint64_t networkFingerprint(const CompletionModel& model) {
  auto& impl = *model.impl();
  std::lock_guard<std::mutex> lock(impl.mutex);
  std::uint64_t hash = kFnv1aOffsetBasis;
  for (const auto& [name, crc] : weightChecksums(*impl.encoder)) hash = fnv1a("encoder." + name + std::to_string(crc), hash);
  for (const auto& [name, crc] : weightChecksums(*detail::decoderOf(impl)))
    hash = fnv1a("decoder." + name + std::to_string(crc), hash);
  return hash;
}

Eigen::Matrix3d closingBoxRotation(const PlanarSegmentation& segmentation, const Eigen::Vector3d& scanner_direction,
                                   std::size_t min_points) {
  const std::vector<std::size_t> sizes = segmentation.pointsPerSegment();
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> weights;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    const Eigen::Vector3d& normal = segmentation.planes[i].normal;
    if (sizes[i] < min_points || !(normal.norm() > 0.0)) continue;
    normals.push_back(normal.normalized());
    weights.push_back(static_cast<double>(sizes[i]));
  }
  const ClosingBoxAxes axes = closingBoxAxes(normals, weights, scanner_direction);
  return axes.axes ? rotationOntoAxesClosestToIdentity(*axes.axes) : Eigen::Matrix3d::Identity();
}

ExtentObservation observeExtent(const CompletionModel::ConstPtr& model,
                                const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                const PlanarSegmentation& segmentation, const Eigen::Matrix3d& turn,
                                const Eigen::Vector3d& scanner_direction) {
  if (!model) throw ModelError("observeExtent: no completion model");
  PlaneProxyEncoder encoder;
  encoder.setModel(model);
  encoder.setInputCloud(cloud);
  encoder.setSegmentation(segmentation);
  // The box fill's axes onto the coordinate axes, so that the head's box is the fill's. A model
  // trained on turned inputs turns them itself.
  encoder.setTurn(model->config().input_orientation == "seen-planes"
                      ? turn
                      : Eigen::Matrix3d(turn * closingBoxRotation(segmentation, scanner_direction)));
  PlaneProxies proxies;
  encoder.encode(proxies);
  const PlaneProxyOutput in = detail::decoderInputOf(proxies);
  auto& impl = *model->impl();
  torch::Tensor global;
  {
    std::lock_guard<std::mutex> lock(impl.mutex);
    torch::NoGradGuard no_grad;
    global = detail::decoderOf(impl)->forward(in).global_feature[0].contiguous();
  }
  ExtentObservation observation;
  observation.frame = proxies.normalization;
  for (const auto& p : *cloud) observation.seen_box.extend(observation.frame.apply(p.getVector3fMap().cast<double>()));
  const float* g = global.data_ptr<float>();
  observation.features.assign(g, g + global.numel());
  const Eigen::Vector3d sides = observation.seen_box.sizes();
  for (int a = 0; a < 3; ++a) observation.features.push_back(static_cast<float>(sides[a]));
  return observation;
}

std::array<float, kBoxSides> extentBeyond(const ExtentObservation& observation,
                                          const std::vector<Eigen::Vector3d>& complete) {
  Eigen::AlignedBox3d whole;
  for (const auto& p : complete) whole.extend(observation.frame.apply(p));
  std::array<float, kBoxSides> beyond{};
  if (whole.isEmpty()) return beyond;
  for (int a = 0; a < 3; ++a) {
    beyond[static_cast<std::size_t>(a)] =
        static_cast<float>(std::max(0.0, observation.seen_box.min()[a] - whole.min()[a]));
    beyond[static_cast<std::size_t>(a + 3)] =
        static_cast<float>(std::max(0.0, whole.max()[a] - observation.seen_box.max()[a]));
  }
  return beyond;
}

Eigen::AlignedBox3d HiddenExtent::grownBox() const {
  Eigen::AlignedBox3d box = seen_box;
  for (int a = 0; a < 3; ++a) {
    box.min()[a] -= beyond[static_cast<std::size_t>(a)];
    box.max()[a] += beyond[static_cast<std::size_t>(a + 3)];
  }
  return box;
}

std::vector<Eigen::Vector3d> HiddenExtent::corners() const {
  const Eigen::AlignedBox3d box = grownBox();
  std::vector<Eigen::Vector3d> result;
  if (box.isEmpty()) return result;
  for (int c = 0; c < 8; ++c)
    result.push_back(frame.applyInverse(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(c))));
  return result;
}

double HiddenExtent::largestInUserUnits() const {
  return *std::max_element(beyond.begin(), beyond.end()) / frame.scale;
}

HiddenExtent estimateHiddenExtent(const CompletionModel::ConstPtr& model, const HiddenExtentModel& head,
                                  const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                  const PlanarSegmentation& segmentation, int turns,
                                  const Eigen::Vector3d& scanner_direction) {
  if (!model) throw ModelError("estimateHiddenExtent: no completion model");
  head.checkMatches(*model);
  const std::vector<Eigen::Matrix3d> all_turns = ensembleTurns(turns);
  HiddenExtent extent;
  for (std::size_t t = 0; t < all_turns.size(); ++t) {
    const Eigen::Matrix3d& turn = all_turns[t];
    const ExtentObservation observation = observeExtent(model, cloud, segmentation, turn, scanner_direction);
    if (t == 0) {  // the identity: the unturned frame
      extent.frame = observation.frame;
      extent.seen_box = observation.seen_box;
    }
    const auto beyond = head.predict(observation.features);
    // Side (axis a, sign) of the turned box is the unturned box's side along turn^T e_a.
    for (int a = 0; a < 3; ++a) {
      const Eigen::Vector3d direction = turn.transpose().col(a);
      int b = 0;
      direction.cwiseAbs().maxCoeff(&b);
      const bool flipped = direction[b] < 0.0;
      extent.beyond[static_cast<std::size_t>(flipped ? b + 3 : b)] += beyond[static_cast<std::size_t>(a)];
      extent.beyond[static_cast<std::size_t>(flipped ? b : b + 3)] += beyond[static_cast<std::size_t>(a + 3)];
    }
  }
  for (double& b : extent.beyond) b /= static_cast<double>(all_turns.size());
  closeSidesOnSeenFaces(extent, *cloud, segmentation);
  return extent;
}

void closeSidesOnSeenFaces(HiddenExtent& extent, const pcl::PointCloud<pcl::PointNormal>& cloud,
                           const PlanarSegmentation& segmentation, double reach, std::size_t min_points) {
  if (extent.seen_box.isEmpty()) return;
  const double min_cosine = std::cos(degreesToRadians(20.0));
  for (std::size_t i = 0; i < segmentation.segments.size() && i < segmentation.planes.size(); ++i) {
    const Eigen::Vector3d& normal = segmentation.planes[i].normal;
    if (segmentation.segments[i].indices.size() < min_points || !(normal.norm() > 0.0)) continue;
    const Eigen::Vector3d n = extent.frame.applyToDirection(normal.normalized());
    for (int side = 0; side < kBoxSides; ++side) {
      const int axis = side % 3;
      const bool at_max = side >= 3;
      if ((at_max ? n[axis] : -n[axis]) < min_cosine || extent.closed_by_seen_face[static_cast<std::size_t>(side)])
        continue;
      const double level = at_max ? extent.seen_box.max()[axis] : extent.seen_box.min()[axis];
      for (const int index : segmentation.segments[i].indices) {
        if (index < 0 || static_cast<std::size_t>(index) >= cloud.size()) continue;
        const Eigen::Vector3d p = extent.frame.apply(cloud[static_cast<std::size_t>(index)].getVector3fMap().cast<double>());
        if (std::abs(p[axis] - level) <= reach) {
          extent.closed_by_seen_face[static_cast<std::size_t>(side)] = true;
          break;
        }
      }
    }
  }
  for (int side = 0; side < kBoxSides; ++side)
    if (extent.closed_by_seen_face[static_cast<std::size_t>(side)]) extent.beyond[static_cast<std::size_t>(side)] = 0.0;
}

HiddenExtentModel::ConstPtr trainHiddenExtentModel(std::uint64_t network_fingerprint,
                                                   const std::vector<ExtentExample>& examples,
                                                   const ExtentTrainingOptions& options) {
  if (examples.empty()) throw InvalidInputError("trainHiddenExtentModel: no training example");
  if (options.epochs < 0 || options.hidden < 1 || options.batch < 1 || !(options.learning_rate > 0.0))
    throw InvalidInputError("trainHiddenExtentModel: epochs >= 0, hidden >= 1, batch >= 1 and a positive learning "
                            "rate are needed");
  torch::manual_seed(options.seed);
  const int width = static_cast<int>(examples.front().features.size());
  if (width < 1) throw InvalidInputError("trainHiddenExtentModel: the examples have no feature");
  const torch::Tensor x = featureMatrix(examples, width), y = targetMatrix(examples);
  auto impl = std::make_shared<HiddenExtentModel::Impl>();
  impl->feature_width = width;
  impl->hidden = options.hidden;
  impl->fingerprint = network_fingerprint;
  impl->mean = x.mean(0);
  // A feature constant over the examples would divide by zero; it carries nothing anyway.
  impl->spread = x.size(0) > 1 ? x.std(0).clamp_min(1e-6) : torch::ones({width});
  impl->mlp = makeMlp(width, options.hidden);
  torch::optim::AdamW optimizer(impl->mlp->parameters(),
                                torch::optim::AdamWOptions(options.learning_rate).weight_decay(1e-2));
  const std::int64_t n = x.size(0);
  for (int epoch = 1; epoch <= options.epochs; ++epoch) {
    impl->mlp->train();
    const auto order = torch::randperm(n, torch::kLong);
    double sum = 0.0;
    for (std::int64_t begin = 0; begin < n; begin += options.batch) {
      const auto rows = order.slice(0, begin, std::min(n, begin + options.batch));
      auto loss = (impl->forward(x.index_select(0, rows)) - y.index_select(0, rows)).abs().mean();
      optimizer.zero_grad();
      loss.backward();
      optimizer.step();
      sum += loss.item<double>() * static_cast<double>(rows.size(0));
    }
    if (options.after_epoch && !options.after_epoch(epoch, sum / static_cast<double>(n))) break;
  }
  impl->mlp->eval();
  return std::make_shared<const HiddenExtentModel>(std::move(impl));
}

double meanAbsoluteExtentError(const HiddenExtentModel* head, const std::vector<ExtentExample>& examples) {
  if (examples.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& example : examples) {
    std::array<double, kBoxSides> predicted{};
    if (head) predicted = head->predict(example.features);
    for (int s = 0; s < kBoxSides; ++s)
      sum += std::abs(predicted[static_cast<std::size_t>(s)] - example.beyond[static_cast<std::size_t>(s)]);
  }
  return sum / (static_cast<double>(examples.size()) * kBoxSides);
}

}  // namespace paco
