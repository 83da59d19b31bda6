#pragma once
// Usage:
//   paco::completion::CollateOptions options;                  // 2048 input / 8192 GT points
//   paco::completion::TrainingBatch batch = paco::completion::collate(samples, options, seed);
//   paco::completion::NetworkOutput out = network->forward(batch.input);
#include <paco/completion/network.h>

#include <torch/torch.h>

#include <cstdint>
#include <string>
#include <vector>

#if PACO_HAVE_DATA
#include <paco/data/dataset.h>
#endif

namespace paco::completion {

/// Ground truth of a batch in the network's frame. Planes are padded to the largest count in
/// the batch; every GT point row is real (samples with fewer points repeat some).
struct GroundTruthBatch {
  torch::Tensor points;   ///< (B, G, 3) float: points sampled uniformly on the complete surface
  torch::Tensor labels;   ///< (B, G) int64: index of each point's plane in `normals`/`offsets`
  torch::Tensor normals;  ///< (B, Pmax, 3) float: unit outward plane normals (0 in padding)
  torch::Tensor offsets;  ///< (B, Pmax) float: r of the plane n·x = r (0 in padding)
  torch::Tensor mask;     ///< (B, Pmax) bool: true for a real plane, false for padding

  int batchSize() const { return points.defined() ? static_cast<int>(points.size(0)) : 0; }
  /// Number of real planes of sample b.
  int planeCount(int b) const;
};

/// One collated batch: what the network reads and what the losses compare with.
struct TrainingBatch {
  NetworkInput input;
  GroundTruthBatch truth;
  std::vector<std::string> parts;  ///< part name of each sample (for logs)
  int size() const { return truth.batchSize(); }
};

/// How raw samples become fixed-size tensors.
struct CollateOptions {
  int input_points = 2048;  ///< points per input cloud: fewer are repeated, more are sub-sampled
  int gt_points = 8192;     ///< GT points per sample, same rule
  /// "complete": keep the dataset frame (normalised by the complete shape, the paper's
  /// protocol). "own": re-normalise every sample by the bounding box of its own partial input
  /// (centre at the origin, unit diagonal) and move its ground truth the same way, as a user
  /// scan with no complete-shape frame will be at inference.
  std::string input_frame = "complete";
  /// "as-is" or "seen-planes": with the own frame, also turn each sample so that its dominant
  /// input segments' planes lie on the coordinate axes (paco::seenPlanesRotation, the box taken
  /// in the turned axes), input normals and ground truth with it; what PlaneProxyEncoder does
  /// at inference for a model whose ModelConfig::input_orientation is "seen-planes".
  std::string input_orientation = "as-is";
  /// Random similarity applied after the frame (0 = off): scale factor drawn uniformly in
  /// [1 - s, 1 + s] and a translation in [-t, t]³ (normalised units). Applied to input and GT.
  double augment_scale = 0.0;
  double augment_offset = 0.0;
  /// Gaussian jitter of the input positions only (0 = off), in normalised units: each sample
  /// draws σ uniformly in [0, augment_jitter], so clean inputs stay in the mix. Scanner-like
  /// noise; labels and normals stay those of the clean scan, and the truth does not move.
  double augment_jitter = 0.0;
};

/// Re-samples `count` indices of [0, n) deterministically from `seed`: a random permutation
/// prefix when n ≥ count, otherwise all of them plus random repeats. n must be positive.
std::vector<std::int64_t> resampleIndices(std::int64_t n, std::int64_t count, std::uint64_t seed);

#if PACO_HAVE_DATA
/// Collates samples (all in the dataset's normalised frame) into a batch. `seed` drives the
/// re-sampling and augmentation, so a batch is reproducible. Throws InvalidInputError on an
/// empty list, an empty input or GT cloud, labels of the wrong length or out of range, or a
/// sample without planes.
TrainingBatch collate(const std::vector<paco::data::Sample>& samples, const CollateOptions& options,
                      std::uint64_t seed);
#endif

}  // namespace paco::completion
