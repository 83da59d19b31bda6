#include <paco/common/error.h>
#include <paco/encoding/completion_model_impl.h>
#include <paco/common/orientation.h>
#include <paco/encoding/plane_proxy_encoder.h>

#include <cmath>
#include <numeric>
#include <random>

namespace paco {

PlaneProxyEncoder::PlaneProxyEncoder() = default;
PlaneProxyEncoder::~PlaneProxyEncoder() = default;

void PlaneProxyEncoder::encode(PlaneProxies& proxies) {
  initCompute();
  computeProxies(proxies);
}

void PlaneProxyEncoder::initCompute() {
  if (!cloud_ || cloud_->empty())
    throw InvalidInputError("PlaneProxyEncoder: the input cloud is empty or not set; call "
                            "setInputCloud() with a non-empty cloud");
  if (!model_)
    throw ModelError("PlaneProxyEncoder: no model set; load one with "
                     "paco::CompletionModel::load() and call setModel()");
  if (segmentation_.labels.size() != cloud_->size())
    throw InvalidInputError("PlaneProxyEncoder: the segmentation has " +
                            std::to_string(segmentation_.labels.size()) + " labels for " +
                            std::to_string(cloud_->size()) +
                            " points; segment this very cloud and call setSegmentation()");
  if (segmentation_.empty())
    throw InvalidInputError("PlaneProxyEncoder: the segmentation has no plane; the cloud needs "
                            "at least one planar segment (try a lower segmenter threshold)");
  for (int label : segmentation_.labels)
    if (label < -1 || label >= static_cast<int>(segmentation_.planes.size()))
      throw InvalidInputError("PlaneProxyEncoder: segmentation label " + std::to_string(label) +
                              " is outside [-1, " + std::to_string(segmentation_.size()) + ")");
  for (const auto& p : cloud_->points)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InvalidInputError("PlaneProxyEncoder: the input cloud has non-finite coordinates; "
                              "remove NaN points first (pcl::removeNaNFromPointCloud)");
  if (num_points_ < model_->config().num_centres)
    throw InvalidInputError("PlaneProxyEncoder: setNumPoints(" + std::to_string(num_points_) +
                            ") is below the model's " +
                            std::to_string(model_->config().num_centres) + " centres");
}

Normalization PlaneProxyEncoder::ownFrame() const {
  if (model_->config().input_orientation != "seen-planes") {
    if (turn_.isIdentity(0.0)) return Normalization::fromBoundingBox(*cloud_);
    return Normalization::fromBoundingBox(*cloud_, turn_);
  }
  // The segments' planes weighted by their point counts, as paco::completion::collate does
  // in training (there the planes come from the points' normals).
  return Normalization::fromBoundingBox(*cloud_, turn_ * seenPlanesRotation(segmentation_));
}

void PlaneProxyEncoder::computeProxies(PlaneProxies& proxies) {
  const auto& cloud = *cloud_;
  const std::int64_t n = static_cast<std::int64_t>(cloud.size());
  const Normalization normalization = frame_ ? *frame_ : ownFrame();

  // The network was trained on num_points_ points: a fixed random subset, or repeats.
  std::vector<std::int64_t> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  if (n > num_points_) {
    std::mt19937 random(0);
    std::shuffle(order.begin(), order.end(), random);
  }
  auto points = torch::empty({1, num_points_, 3});
  auto normals = torch::zeros({1, num_points_, 3});
  auto labels = torch::empty({1, num_points_}, torch::kLong);
  float* xyz = points.data_ptr<float>();
  float* nrm = normals.data_ptr<float>();
  std::int64_t* lab = labels.data_ptr<std::int64_t>();
  for (int i = 0; i < num_points_; ++i) {
    const std::int64_t index = order[static_cast<std::size_t>(i % n)];
    const auto& p = cloud.points[static_cast<std::size_t>(index)];
    const Eigen::Vector3d x = normalization.apply(Eigen::Vector3d(p.x, p.y, p.z));
    const int label = segmentation_.labels[static_cast<std::size_t>(index)];
    Eigen::Vector3d normal(p.normal_x, p.normal_y, p.normal_z);
    if (label >= 0) normal = segmentation_.planes[static_cast<std::size_t>(label)].normal;
    normal = normalization.applyToDirection(normal);
    if (!normal.allFinite()) normal.setZero();
    for (int a = 0; a < 3; ++a) {
      xyz[3 * i + a] = static_cast<float>(x[a]);
      nrm[3 * i + a] = static_cast<float>(normal[a]);
    }
    lab[i] = label;
  }

  auto& impl = *model_->impl();
  PlaneProxyOutput out;
  {
    std::lock_guard<std::mutex> lock(impl.mutex);
    torch::NoGradGuard no_grad;
    impl.encoder->eval();
    out = impl.encoder->forward(points, normals, labels);
  }
  const auto& config = model_->config();
  proxies = PlaneProxies{};
  proxies.slots = config.plane_slots;
  proxies.width = config.width;
  auto features = out.proxies[0].contiguous();
  proxies.features.assign(features.data_ptr<float>(), features.data_ptr<float>() + features.numel());
  auto mask = out.mask[0].contiguous();
  auto slot_normals = out.slot_normals[0].contiguous();
  auto slot_offsets = out.slot_offsets[0].contiguous();
  auto slot_segments = out.slot_segments[0].contiguous();
  for (int s = 0; s < config.plane_slots; ++s) {
    proxies.mask.push_back(mask[s].item<bool>() ? 1 : 0);
    proxies.slot_segments.push_back(static_cast<int>(slot_segments[s].item<std::int64_t>()));
    Plane plane;
    if (proxies.mask.back()) {
      const float* nn = slot_normals[s].data_ptr<float>();
      plane = Plane(Eigen::Vector3d(nn[0], nn[1], nn[2]), -slot_offsets[s].item<float>());
    }
    proxies.slot_planes.push_back(plane);
  }
  proxies.input_planes = segmentation_.planes;
  proxies.normalization = normalization;
  proxies.model = model_;
}

}  // namespace paco
