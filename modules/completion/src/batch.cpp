#include <paco/completion/batch.h>

#include <paco/common/error.h>
#include <paco/common/orientation.h>

#include <algorithm>
#include <numeric>
#include <random>

namespace paco::completion {

std::vector<std::int64_t> resampleIndices(std::int64_t n, std::int64_t count, std::uint64_t seed) {
  if (n <= 0) throw InvalidInputError("resampleIndices: cannot re-sample an empty point set");
  std::mt19937_64 rng(seed);
  std::vector<std::int64_t> all(static_cast<std::size_t>(n));
  std::iota(all.begin(), all.end(), 0);
  if (n == count) return all;
  if (n > count) {
    std::shuffle(all.begin(), all.end(), rng);
    all.resize(static_cast<std::size_t>(count));
    return all;
  }
  // Fewer points than wanted: keep every point once, fill up with random repeats.
  std::uniform_int_distribution<std::int64_t> pick(0, n - 1);
  while (static_cast<std::int64_t>(all.size()) < count) all.push_back(pick(rng));
  return all;
}

#if PACO_HAVE_DATA
namespace {

// x -> scale * rotation * x + shift: the chosen frame, then the augmentation.
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  Eigen::Vector3d apply(const Eigen::Vector3d& x) const { return scale * (rotation * x) + shift; }
};

// The rotation PlaneProxyEncoder applies at inference for input_orientation "seen-planes":
// each input segment's plane normal (here the mean of its points' normals) weighted by its size.
Eigen::Matrix3d seenPlanesRotationOf(const paco::data::Sample& sample) {
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> sizes;
  for (std::size_t i = 0; i < sample.input.size(); ++i) {
    const int label = sample.input_labels[i];
    if (label < 0) continue;
    const auto slot = static_cast<std::size_t>(label);
    if (slot >= normals.size()) {
      normals.resize(slot + 1, Eigen::Vector3d::Zero());
      sizes.resize(slot + 1, 0.0);
    }
    const auto& q = sample.input[i];
    const Eigen::Vector3d n(q.normal_x, q.normal_y, q.normal_z);
    if (!n.allFinite()) continue;
    // Orient along the segment's first normal so that flipped normals do not cancel.
    normals[slot] += normals[slot].dot(n) < 0.0 ? -n : n;
    sizes[slot] += 1.0;
  }
  return seenPlanesRotation(normals, sizes);
}

Similarity frameOf(const paco::data::Sample& sample, const CollateOptions& options, std::mt19937_64& rng) {
  Similarity frame;
  if (options.input_orientation != "as-is" && options.input_orientation != "seen-planes")
    throw InvalidInputError("collate: unknown input orientation '" + options.input_orientation +
                            "'; use \"as-is\" or \"seen-planes\"");
  if (options.input_frame == "own") {
    if (options.input_orientation == "seen-planes") frame.rotation = seenPlanesRotationOf(sample);
    const Normalization own = Normalization::fromBoundingBox(sample.input, frame.rotation);
    frame.scale = own.scale;
    frame.shift = -own.scale * (own.rotation * own.center);
  } else if (options.input_frame != "complete") {
    throw InvalidInputError("collate: unknown input frame '" + options.input_frame +
                            "'; use \"complete\" or \"own\"");
  } else if (options.input_orientation != "as-is") {
    throw InvalidInputError("collate: input orientation '" + options.input_orientation +
                            "' needs input frame \"own\" (the complete frame is the paper's, never turned)");
  }
  if (options.augment_scale > 0.0) {
    std::uniform_real_distribution<double> s(1.0 - options.augment_scale, 1.0 + options.augment_scale);
    const double factor = s(rng);
    frame.scale *= factor;
    frame.shift *= factor;
  }
  if (options.augment_offset > 0.0) {
    std::uniform_real_distribution<double> t(-options.augment_offset, options.augment_offset);
    for (int k = 0; k < 3; ++k) frame.shift[k] += t(rng);
  }
  return frame;
}

void validateSample(const paco::data::Sample& s, std::size_t index) {
  const std::string where = "collate: sample " + std::to_string(index) + " ('" + s.part + "')";
  if (s.input.empty()) throw InvalidInputError(where + " has an empty input cloud");
  if (s.input_labels.size() != s.input.size())
    throw InvalidInputError(where + " has " + std::to_string(s.input_labels.size()) + " input labels for " +
                            std::to_string(s.input.size()) + " input points");
  if (s.gt_points.empty()) throw InvalidInputError(where + " has no ground-truth points");
  if (s.gt_labels.size() != s.gt_points.size())
    throw InvalidInputError(where + " has " + std::to_string(s.gt_labels.size()) + " GT labels for " +
                            std::to_string(s.gt_points.size()) + " GT points");
  if (s.gt_planes.empty()) throw InvalidInputError(where + " has no ground-truth planes");
  for (int label : s.gt_labels)
    if (label < 0 || label >= static_cast<int>(s.gt_planes.size()))
      throw InvalidInputError(where + " has a GT label " + std::to_string(label) + " outside [0, " +
                              std::to_string(s.gt_planes.size()) + "); the dataset is damaged, rebuild it");
  for (const auto& p : s.input)
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
      throw InvalidInputError(where + " has a non-finite input point");
}

}  // namespace

TrainingBatch collate(const std::vector<paco::data::Sample>& samples, const CollateOptions& options,
                      std::uint64_t seed) {
  if (samples.empty()) throw InvalidInputError("collate: no samples to collate");
  if (options.input_points <= 0 || options.gt_points <= 0)
    throw InvalidInputError("collate: input_points and gt_points must be positive");
  const auto B = static_cast<std::int64_t>(samples.size());
  const std::int64_t N = options.input_points, G = options.gt_points;
  std::int64_t max_planes = 0;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    validateSample(samples[i], i);
    max_planes = std::max<std::int64_t>(max_planes, static_cast<std::int64_t>(samples[i].gt_planes.size()));
  }
  auto points = torch::zeros({B, N, 3}, torch::kFloat);
  auto normals = torch::zeros({B, N, 3}, torch::kFloat);
  auto labels = torch::full({B, N}, -1, torch::kLong);
  auto gt_points = torch::zeros({B, G, 3}, torch::kFloat);
  auto gt_labels = torch::zeros({B, G}, torch::kLong);
  auto plane_normals = torch::zeros({B, max_planes, 3}, torch::kFloat);
  auto plane_offsets = torch::zeros({B, max_planes}, torch::kFloat);
  auto mask = torch::zeros({B, max_planes}, torch::kBool);
  auto p = points.accessor<float, 3>();
  auto n = normals.accessor<float, 3>();
  auto l = labels.accessor<std::int64_t, 2>();
  auto gp = gt_points.accessor<float, 3>();
  auto gl = gt_labels.accessor<std::int64_t, 2>();
  auto pn = plane_normals.accessor<float, 3>();
  auto po = plane_offsets.accessor<float, 2>();
  auto pm = mask.accessor<bool, 2>();

  TrainingBatch batch;
  for (std::int64_t b = 0; b < B; ++b) {
    const auto& s = samples[static_cast<std::size_t>(b)];
    batch.parts.push_back(s.part);
    const std::uint64_t sample_seed = seed * 0x9E3779B97F4A7C15ULL + static_cast<std::uint64_t>(b) * 7919u + 1;
    std::mt19937_64 rng(sample_seed);
    const Similarity frame = frameOf(s, options, rng);
    // A stream of its own, so that jitter changes nothing else of the batch (re-sampling, frame).
    std::mt19937_64 jitter_rng(sample_seed ^ 0xA5A5A5A5DEADBEEFULL);
    const double sigma =
        options.augment_jitter > 0.0 ? std::uniform_real_distribution<double>(0.0, options.augment_jitter)(jitter_rng)
                                     : 0.0;
    std::normal_distribution<double> jitter(0.0, 1.0);
    const auto input_index = resampleIndices(static_cast<std::int64_t>(s.input.size()), N, rng());
    for (std::int64_t i = 0; i < N; ++i) {
      const auto& q = s.input[static_cast<std::size_t>(input_index[i])];
      Eigen::Vector3d x = frame.apply(Eigen::Vector3d(q.x, q.y, q.z));
      if (sigma > 0.0)
        for (int k = 0; k < 3; ++k) x[k] += sigma * jitter(jitter_rng);
      for (int k = 0; k < 3; ++k) p[b][i][k] = static_cast<float>(x[k]);
      const Eigen::Vector3d normal = frame.rotation * Eigen::Vector3d(q.normal_x, q.normal_y, q.normal_z);
      for (int k = 0; k < 3; ++k) n[b][i][k] = static_cast<float>(normal[k]);
      l[b][i] = s.input_labels[static_cast<std::size_t>(input_index[i])];
    }
    const auto gt_index = resampleIndices(static_cast<std::int64_t>(s.gt_points.size()), G, rng());
    for (std::int64_t i = 0; i < G; ++i) {
      const auto k_src = static_cast<std::size_t>(gt_index[i]);
      const auto& q = s.gt_points[k_src];
      const Eigen::Vector3d x = frame.apply(Eigen::Vector3d(q.x, q.y, q.z));
      for (int k = 0; k < 3; ++k) gp[b][i][k] = static_cast<float>(x[k]);
      gl[b][i] = s.gt_labels[k_src];
    }
    for (std::size_t g = 0; g < s.gt_planes.size(); ++g) {
      const Plane& plane = s.gt_planes[g];
      // The frame is a similarity with positive scale: normals turn with it and stay outward,
      // and the plane moves with its foot point; r = n'·foot' for the plane n'·x = r.
      const Eigen::Vector3d foot = frame.apply(plane.foot());
      const Eigen::Vector3d normal = frame.rotation * plane.normal;
      for (int k = 0; k < 3; ++k) pn[b][static_cast<std::int64_t>(g)][k] = static_cast<float>(normal[k]);
      po[b][static_cast<std::int64_t>(g)] = static_cast<float>(normal.dot(foot));
      pm[b][static_cast<std::int64_t>(g)] = true;
    }
  }
  batch.input.points = points;
  batch.input.normals = normals;
  batch.input.labels = labels;
  batch.truth.points = gt_points;
  batch.truth.labels = gt_labels;
  batch.truth.normals = plane_normals;
  batch.truth.offsets = plane_offsets;
  batch.truth.mask = mask;
  return batch;
}
#endif

}  // namespace paco::completion
