#pragma once
// Usage:
//   paco::ParametricCompleter completer; completer.setModel(model);   // paco::CompletionModel
//   completer.setInputProxies(proxies);                                // from PlaneProxyEncoder
//   std::vector<paco::PlanarPrimitive> primitives; completer.complete(primitives);
#include <paco/common/primitive.h>
#include <paco/encoding/completion_model.h>
#include <paco/encoding/plane_proxy_encoder.h>
#include <memory>
#include <vector>

namespace paco {

/// Stage 3: from plane proxies, predicts the primitives of the COMPLETE surface (planes plus
/// points on them) and keeps those whose confidence exceeds the threshold. Results are in the
/// user's own frame and units.
class ParametricCompleter {
 public:
  using Ptr = std::shared_ptr<ParametricCompleter>;
  ParametricCompleter();
  virtual ~ParametricCompleter();

  void setInputProxies(const PlaneProxies& proxies) { proxies_ = proxies; }
  /// Must be the model that produced the proxies.
  void setModel(const CompletionModel::ConstPtr& model) { model_ = model; }
  /// Keep primitives with confidence (sigmoid of the selector logit) above this, in [0, 1];
  /// default 0.7, the paper's: chosen for the shipped model on never-trained parts, followed by
  /// observed fusion (paco::fuseWithObserved), whose thinning of the unseen primitives' points
  /// keeps PolyFit from following the extra guesses (doc/results.md). Without fusion, 0.8 keeps
  /// fewer spurious planes.
  void setConfidenceThreshold(double threshold) { threshold_ = threshold; }
  double getConfidenceThreshold() const { return threshold_; }

  /// Validates (InvalidInputError: no proxies, threshold outside [0,1]; ModelError: no model or
  /// not the proxies' model) then completes. Primitives are sorted by decreasing confidence;
  /// each has P points with normals equal to its plane normal.
  void complete(std::vector<PlanarPrimitive>& primitives);

 protected:
  virtual void initCompute();
  virtual void computePrimitives(std::vector<PlanarPrimitive>& primitives);

  PlaneProxies proxies_;
  CompletionModel::ConstPtr model_;
  double threshold_ = 0.7;
};

}  // namespace paco
