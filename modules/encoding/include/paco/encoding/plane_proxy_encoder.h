#pragma once
// Usage:
//   paco::PlaneProxyEncoder encoder; encoder.setModel(model);          // paco::CompletionModel
//   encoder.setInputCloud(cloud); encoder.setSegmentation(segmentation);
//   paco::PlaneProxies proxies; encoder.encode(proxies);               // stage 2 of the pipeline
#include <paco/common/normalization.h>
#include <paco/common/plane.h>
#include <paco/common/primitive.h>
#include <paco/encoding/completion_model.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace paco {

/// The plane proxies of one cloud: stage 2's result, stage 3's input. Plain data.
struct PlaneProxies {
  int slots = 0;  ///< K
  int width = 0;  ///< C
  /// K x C features, row-major, in the normalised frame; padding rows are zero.
  std::vector<float> features;
  std::vector<std::uint8_t> mask;   ///< K entries: 1 = slot holds an input segment
  std::vector<int> slot_segments;   ///< K entries: input segment index of each slot (-1: padding)
  /// K entries: the plane of each slot in the NORMALISED frame (unit normal; padding: default).
  std::vector<Plane> slot_planes;
  /// The input segments' planes in the user's frame (all of them, also those beyond K).
  std::vector<Plane> input_planes;
  /// User frame -> normalised frame (centre of the bounding box, unit diagonal).
  Normalization normalization;
  /// The model that produced these proxies (stage 3 must use the same one).
  std::shared_ptr<const CompletionModel> model;
  bool empty() const { return slots == 0; }
};

/// Stage 2: encodes a segmented incomplete cloud into K plane proxies with the model's
/// PlaneProxyNetwork. The cloud is normalised by its own bounding box first. At most
/// `max_points` points are used (a deterministic subset), fewer are repeated, as in training.
class PlaneProxyEncoder {
 public:
  using Ptr = std::shared_ptr<PlaneProxyEncoder>;
  PlaneProxyEncoder();
  virtual ~PlaneProxyEncoder();

  /// The cloud to encode, in the user's frame and units (normals optional: the segment planes'
  /// normals are used).
  void setInputCloud(const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud) { cloud_ = cloud; }
  /// Its planar segmentation (labels.size() == cloud size), e.g. from paco::PlanarSegmenter.
  void setSegmentation(const PlanarSegmentation& segmentation) { segmentation_ = segmentation; }
  void setModel(const CompletionModel::ConstPtr& model) { model_ = model; }
  /// Points fed to the network (default 2048, the training size; >= the model's num_centres).
  void setNumPoints(int points) { num_points_ = points; }
  int getNumPoints() const { return num_points_; }
  /// The user-to-network frame. By default (nothing set) the input's own bounding box: centre at
  /// the origin, unit diagonal, as paco_reconstruct does for a scan; a model trained with
  /// input_orientation "seen-planes" also turns the input so that its largest segments' planes
  /// lie on the coordinate axes (the box is then taken in the turned axes). Set it to evaluate the
  /// paper's protocol, where the partial input is already in the complete shape's frame (pass
  /// the identity, Normalization{}). The completed primitives come back in the user's frame.
  void setFrame(const Normalization& frame) { frame_ = frame; }
  /// Back to the input's own bounding box.
  void resetFrame() { frame_.reset(); }
  /// Also turns the input by this proper rotation inside the own frame (after the model's own
  /// turn, if any; the box is taken in the turned axes). Default the identity. Test-time
  /// ensembling (paco::completeWithTurns) runs the network on several 90-degree turns of one
  /// scan. Not used when setFrame() gave a frame.
  void setTurn(const Eigen::Matrix3d& turn) { turn_ = turn; }
  const Eigen::Matrix3d& getTurn() const { return turn_; }

  /// Validates the input (InvalidInputError: no/empty cloud, NaN points, labels size mismatch,
  /// no segment; ModelError: no model) then encodes.
  void encode(PlaneProxies& proxies);

 protected:
  /// Checks the input; throws on bad input.
  virtual void initCompute();
  virtual void computeProxies(PlaneProxies& proxies);
  /// The default frame: the input's own (turned, if the model says so) bounding box.
  Normalization ownFrame() const;

  pcl::PointCloud<pcl::PointNormal>::ConstPtr cloud_;
  PlanarSegmentation segmentation_;
  CompletionModel::ConstPtr model_;
  int num_points_ = 2048;
  std::optional<Normalization> frame_;
  Eigen::Matrix3d turn_ = Eigen::Matrix3d::Identity();
};

}  // namespace paco
