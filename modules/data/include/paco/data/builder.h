#pragma once
// Usage:
//   paco::data::BuildOptions options;  options.info.mode = "visibility";
//   paco::data::PartSamples part = paco::data::buildPart("bracket", mesh, options);  // throws if unusable
//   paco::data::DatasetWriter writer("/data/ds", options.info);  writer.write(part);
#include <paco/data/dataset.h>
#include <paco/data/ground_truth.h>
#include <paco/data/partial.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace paco::data {

/// Everything that decides how samples are built. `info` is what gets stored in the dataset.
struct BuildOptions {
  DatasetInfo info;              ///< mode, levels, views, noise, augmentation, seed, sizes
  GroundTruthOptions ground_truth;
  /// Label partial inputs with paco::PlanarSegmenter instead of GT faces. Needs the
  /// segmentation module (segmentationAvailable()); otherwise buildPart throws.
  bool segment = false;
};

/// True when this build of paco::data can label inputs with PlanarSegmenter (--segment).
bool segmentationAvailable();

/// One partial input of a part.
struct PartialSample {
  MissingLevel level = MissingLevel::Simple;
  int view = 0;
  Eigen::Vector3d viewpoint = Eigen::Vector3d::Zero();  ///< unit view direction
  double missing_ratio = 0.0;                           ///< measured
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<int> labels;
};

/// Every sample of one part, in its normalised frame.
struct PartSamples {
  std::string part;
  GroundTruth ground_truth;           ///< of the augmented, normalised mesh
  paco::Normalization normalization;  ///< augmented source frame -> normalised frame
  Eigen::Matrix3d augmentation = Eigen::Matrix3d::Identity();  ///< source -> augmented (linear)
  GtPoints gt;                        ///< info.gt_points points
  std::vector<PartialSample> samples; ///< ordered by level (as in info.levels), then view
  bool labels_from_segmenter = false;
};

/// The random linear map (rotation x anisotropic scale) applied to part `part` before views are
/// taken; identity when augmentation is off. Deterministic in (info.seed, part).
Eigen::Matrix3d augmentationFor(const std::string& part, const DatasetInfo& info);

/// Builds the ground truth and all partial views of one mesh. Throws InvalidInputError (with the
/// reason) for a mesh that is not closed or not plane-only.
PartSamples buildPart(const std::string& part, const SurfaceMesh& mesh, const BuildOptions& options);

/// Serialises a part into the part-file format of doc/dataset.md.
std::string encodePartFile(const PartSamples& part);

/// Writes a dataset folder: info.tsv, index.tsv, failures.tsv, parts/*.bin, meshes/*.off.
/// Resumable: opening an existing folder reads its index; finished or failed parts are skipped.
/// write() and fail() are thread-safe; a part appears in index.tsv only once its files are
/// complete, so an interrupted run leaves a consistent index.
class DatasetWriter {
 public:
  /// Creates or reopens `folder`. Throws IoError when it holds a dataset made with other options.
  DatasetWriter(const std::string& folder, const DatasetInfo& info);
  /// Parts already finished (in index.tsv) or failed (in failures.tsv) in an earlier run.
  bool isDone(const std::string& part) const;
  std::size_t numFinished() const;
  std::size_t numFailed() const;
  void write(const PartSamples& part);
  void fail(const std::string& part, const std::string& reason);

 private:
  std::string folder_;
  mutable std::mutex mutex_;
  std::set<std::string> finished_, failed_;
};

}  // namespace paco::data
