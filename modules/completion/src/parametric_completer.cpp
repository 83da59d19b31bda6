#include <paco/common/error.h>
#include <paco/completion/network.h>
#include <paco/completion/parametric_completer.h>
#include <paco/encoding/completion_model_impl.h>

#include "decoder_access.h"

#include <algorithm>
#include <cmath>

namespace paco {
namespace detail {

CompletionDecoder decoderOf(CompletionModel::Impl& impl) {
  if (!impl.decoder) {
    torch::serialize::InputArchive archive;
    try {
      if (!impl.file.model->try_read("decoder", archive))
        throw ModelError("model file '" + impl.file.path +
                         "' has no decoder weights: the file is damaged; train it again");
    } catch (const c10::Error& e) {
      throw ModelError("model file '" + impl.file.path + "' is corrupt (" +
                       e.what_without_backtrace() + "): download or train it again");
    }
    CompletionDecoder decoder(impl.file.config);
    loadModuleWeights(*decoder, archive, impl.file, "decoder.", "decoder");
    decoder->eval();
    impl.decoder = decoder.ptr();
  }
  return CompletionDecoder(std::dynamic_pointer_cast<CompletionDecoderImpl>(impl.decoder));
}

PlaneProxyOutput decoderInputOf(const PlaneProxies& proxies) {
  const int K = proxies.slots, C = proxies.width;
  PlaneProxyOutput in;
  in.proxies = torch::from_blob(const_cast<float*>(proxies.features.data()), {1, K, C}).clone();
  in.mask = torch::zeros({1, K}, torch::kBool);
  in.slot_normals = torch::zeros({1, K, 3});
  in.slot_offsets = torch::zeros({1, K});
  for (int s = 0; s < K; ++s) {
    if (!proxies.mask[static_cast<std::size_t>(s)]) continue;
    in.mask[0][s] = true;
    const Plane& plane = proxies.slot_planes[static_cast<std::size_t>(s)];
    for (int a = 0; a < 3; ++a) in.slot_normals[0][s][a] = static_cast<float>(plane.normal[a]);
    in.slot_offsets[0][s] = static_cast<float>(-plane.offset);
  }
  return in;
}

}  // namespace detail

ParametricCompleter::ParametricCompleter() = default;
ParametricCompleter::~ParametricCompleter() = default;

void ParametricCompleter::complete(std::vector<PlanarPrimitive>& primitives) {
  initCompute();
  computePrimitives(primitives);
}

void ParametricCompleter::initCompute() {
  if (!model_)
    throw ModelError("ParametricCompleter: no model set; load one with "
                     "paco::CompletionModel::load() and call setModel()");
  if (proxies_.empty())
    throw InvalidInputError("ParametricCompleter: no plane proxies; run PlaneProxyEncoder::encode "
                            "and call setInputProxies()");
  if (proxies_.model && proxies_.model != model_)
    throw ModelError("ParametricCompleter: the proxies were encoded by another model ('" +
                     proxies_.model->path() + "'); use the same model for both stages");
  const auto& config = model_->config();
  if (proxies_.slots != config.plane_slots || proxies_.width != config.width ||
      proxies_.features.size() != static_cast<std::size_t>(proxies_.slots) * proxies_.width ||
      proxies_.mask.size() != static_cast<std::size_t>(proxies_.slots) ||
      proxies_.slot_planes.size() != static_cast<std::size_t>(proxies_.slots))
    throw InvalidInputError("ParametricCompleter: the proxies (" + std::to_string(proxies_.slots) +
                            " x " + std::to_string(proxies_.width) +
                            ") do not fit the model (" + std::to_string(config.plane_slots) +
                            " x " + std::to_string(config.width) + ")");
  if (!(threshold_ >= 0.0 && threshold_ <= 1.0))
    throw InvalidInputError("ParametricCompleter: confidence threshold " +
                            std::to_string(threshold_) + " is outside [0, 1]");
}

void ParametricCompleter::computePrimitives(std::vector<PlanarPrimitive>& primitives) {
  const PlaneProxyOutput in = detail::decoderInputOf(proxies_);
  auto& impl = *model_->impl();
  NetworkOutput out;
  {
    std::lock_guard<std::mutex> lock(impl.mutex);
    torch::NoGradGuard no_grad;
    out = detail::decoderOf(impl)->forward(in);
  }
  auto confidence = torch::sigmoid(out.logits[0]).contiguous();
  auto normals = out.normals[0].contiguous();
  auto offsets = out.offsets[0].contiguous();
  auto points = out.points[0].contiguous();
  const int64_t M = normals.size(0), P = points.size(1);
  primitives.clear();
  for (int64_t m = 0; m < M; ++m) {
    const float kappa = confidence[m].item<float>();
    if (!(kappa > threshold_)) continue;
    const float* n = normals[m].data_ptr<float>();
    const Eigen::Vector3d normal(n[0], n[1], n[2]);
    PlanarPrimitive primitive;
    primitive.plane = Plane(normal, -offsets[m].item<float>());
    primitive.confidence = kappa;
    const float* x = points[m].data_ptr<float>();
    primitive.points.resize(static_cast<std::size_t>(P));
    for (int64_t j = 0; j < P; ++j) {
      auto& q = primitive.points[static_cast<std::size_t>(j)];
      q.x = x[3 * j], q.y = x[3 * j + 1], q.z = x[3 * j + 2];
      q.normal_x = n[0], q.normal_y = n[1], q.normal_z = n[2];
      q.curvature = 0.0f;
    }
    proxies_.normalization.applyInverse(primitive);  // back to the user's frame and units
    primitives.push_back(std::move(primitive));
  }
  std::stable_sort(primitives.begin(), primitives.end(),
                   [](const PlanarPrimitive& a, const PlanarPrimitive& b) {
                     return a.confidence > b.confidence;
                   });
}

}  // namespace paco
