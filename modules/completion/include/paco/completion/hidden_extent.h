#pragma once
// Usage:
//   auto head = paco::HiddenExtentModel::load("models/extent/mfcad_cube.pt");    // paco_train --extent-head-for
//   paco::HiddenExtent extent = paco::estimateHiddenExtent(model, *head, cloud, segmentation);
//   fusion.known_extent_points = extent.corners();   // paco::fuseWithObserved's box fill reaches them
//
// The box fill of observed fusion closes a scan at the box of what was seen. Where a whole side
// of an object was never scanned, the object goes on beyond that box, and nothing in the scan
// says how far. A small learned head guesses it from the completion network's global feature
// (what the network makes of the scan) and the seen box's shape. It learns the prior of the
// objects it was trained on: on MFCAD, whose parts are all cut from a cube, it learns to grow a
// scan back to a cube. So it is a separate file that a user chooses for such objects, not part
// of the general model (doc/evaluation.md, "A guessed extent"; training: doc/training.md).
#include <paco/common/normalization.h>
#include <paco/common/primitive.h>
#include <paco/completion/observed_fusion.h>
#include <paco/encoding/completion_model.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace paco {

/// Sides of a box in the order the head predicts them: -x, -y, -z, +x, +y, +z.
constexpr int kBoxSides = 6;

/// What the head sees of one scan: the network's global feature for the scan turned onto the box
/// fill's axes (closingBoxRotation), and the shape of the scan's box there.
struct ExtentObservation {
  std::vector<float> features;  ///< the decoder's global feature, then the box's three side lengths
  Normalization frame;          ///< user frame -> the turned, unit-diagonal frame the head works in
  Eigen::AlignedBox3d seen_box;  ///< the scan's box in that frame
};

/// How far an object reaches beyond the box of its scan, side by side.
struct HiddenExtent {
  Normalization frame;           ///< as ExtentObservation::frame
  Eigen::AlignedBox3d seen_box;  ///< the scan's box in that frame
  std::array<double, kBoxSides> beyond{};  ///< >= 0, in that frame's units (the scan's box has diagonal 1)
  /// Sides on which a seen face ends the object (closeSidesOnSeenFaces); `beyond` is 0 there.
  std::array<bool, kBoxSides> closed_by_seen_face{};

  /// The seen box grown by `beyond`, in the head's frame.
  Eigen::AlignedBox3d grownBox() const;
  /// The eight corners of the grown box in the user's frame and units.
  std::vector<Eigen::Vector3d> corners() const;
  /// The largest of `beyond`, in the user's units.
  double largestInUserUnits() const;
};

/// A trained head: a small MLP from ExtentObservation::features to the six `beyond` values, tied
/// to the completion network whose features it reads. Thread-safe to use from several threads.
class HiddenExtentModel {
 public:
  using ConstPtr = std::shared_ptr<const HiddenExtentModel>;

  /// Reads a head written by save(). Throws ModelError for a missing, corrupt, truncated or
  /// other-format file.
  static ConstPtr load(const std::string& path);
  /// Writes it atomically (a temporary file renamed into place); IoError on failure.
  void save(const std::string& path) const;

  const std::string& path() const;
  /// Width of the features it takes (the network's global_width + 3).
  int featureWidth() const;
  /// networkFingerprint() of the completion model it was trained on.
  std::uint64_t networkFingerprint() const;
  /// Throws ModelError when `model` is not the network this head was trained on.
  void checkMatches(const CompletionModel& model) const;
  /// The six `beyond` values for one observation's features (>= 0).
  std::array<double, kBoxSides> predict(const std::vector<float>& features) const;

  struct Impl;  ///< LibTorch state (internal)
  explicit HiddenExtentModel(std::shared_ptr<Impl> impl);

 private:
  std::shared_ptr<Impl> impl_;
};

/// A fingerprint of a completion model's weights (CRC-32 of each tensor, combined): a head is
/// valid only for the network it was trained on.
std::uint64_t networkFingerprint(const CompletionModel& model);

/// The rotation that puts the box fill's axes onto the coordinate axes
/// (rotationOntoAxesClosestToIdentity of paco::closingBoxAxes over the segments of at least
/// `min_points` points, each weighted by its number of points, as fuseWithObserved trusts them;
/// the identity when none counts). The head's box is then the fill's box: in another frame, the
/// corners of its grown box widen the fill's box on every side (a gable roof's box, on one slope
/// here and on the bisectors in the fill, grew from 38 x 24 m to 49 x 42 m).
Eigen::Matrix3d closingBoxRotation(const PlanarSegmentation& segmentation,
                                   const Eigen::Vector3d& scanner_direction = Eigen::Vector3d::Zero(),
                                   std::size_t min_points = ObservedFusionOptions().min_observed_points);

/// Runs the model's network once on the cloud turned onto the box fill's axes
/// (closingBoxRotation; `scanner_direction` as ObservedFusionOptions takes it, zero when unknown),
/// then by `turn` (an axis-preserving rotation, paco::ensembleTurns), and returns what the head
/// sees. Throws as PlaneProxyEncoder::encode does.
ExtentObservation observeExtent(const CompletionModel::ConstPtr& model,
                                const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                const PlanarSegmentation& segmentation,
                                const Eigen::Matrix3d& turn = Eigen::Matrix3d::Identity(),
                                const Eigen::Vector3d& scanner_direction = Eigen::Vector3d::Zero());

/// How far `complete` (points of the whole object, user frame) reaches beyond each side of the
/// observation's box, in the head's frame units, 0 where it does not: the training target.
std::array<float, kBoxSides> extentBeyond(const ExtentObservation& observation,
                                          const std::vector<Eigen::Vector3d>& complete);

/// Closes the sides of `extent`'s box on which a seen face ends the object: a segment of at least
/// `min_points` points whose plane faces out of that side (its normal within 20 degrees of the
/// side's outward axis, in the head's frame) and with a point within `reach` of the side (the
/// head's frame units: the scan's box has diagonal 1). Their `beyond` becomes 0 and
/// `closed_by_seen_face` is set. Only a face seen on the box's side says where the object ends;
/// the edges of faces across it do not, since a cut through the object leaves them too. The head
/// reads the network's global feature, not the faces, and grew such sides: on stretched validation
/// parts at 50 % missing it lost 0.12 in CD without this rule (doc/results.md). Planes must face out
/// of the object, as the tools orient them (paco::normalSides).
void closeSidesOnSeenFaces(HiddenExtent& extent, const pcl::PointCloud<pcl::PointNormal>& cloud,
                           const PlanarSegmentation& segmentation, double reach = 0.02,
                           std::size_t min_points = ObservedFusionOptions().min_observed_points);

/// observeExtent, then the head's guess, averaged side by side over the first `turns` of
/// paco::ensembleTurns (1..24; the identity and the three half turns for 4, the default), as the
/// network's planes are (paco::completeWithTurns), then closeSidesOnSeenFaces with its defaults.
/// The result is in the unturned frame. Throws ModelError when the head was trained on another
/// network, InvalidInputError for turns outside 1..24.
HiddenExtent estimateHiddenExtent(const CompletionModel::ConstPtr& model, const HiddenExtentModel& head,
                                  const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                  const PlanarSegmentation& segmentation, int turns = 4,
                                  const Eigen::Vector3d& scanner_direction = Eigen::Vector3d::Zero());

/// One training example: an observation's features and its target.
struct ExtentExample {
  std::vector<float> features;
  std::array<float, kBoxSides> beyond{};
};

struct ExtentTrainingOptions {
  int epochs = 100;
  double learning_rate = 1e-3;  ///< AdamW, weight decay 0.01
  int hidden = 256;             ///< width of the MLP's hidden layer
  int batch = 256;
  std::uint64_t seed = 1;
  /// Called after each epoch with its mean training L1; return false to stop (Ctrl-C).
  std::function<bool(int epoch, double train_l1)> after_epoch;
};

/// Fits a head (L1 loss, features standardised by the examples' mean and spread) for the network
/// with `network_fingerprint`. Throws InvalidInputError for no example or features of unequal width.
HiddenExtentModel::ConstPtr trainHiddenExtentModel(std::uint64_t network_fingerprint,
                                                   const std::vector<ExtentExample>& examples,
                                                   const ExtentTrainingOptions& options);

/// Mean absolute error over the examples and their sides, of the head (`head` given) or of
/// predicting 0 everywhere, what the box fill does without a head (`head` null).
double meanAbsoluteExtentError(const HiddenExtentModel* head, const std::vector<ExtentExample>& examples);

}  // namespace paco
