#pragma once
// Usage:
//   auto centres = paco::farthestPointSampling(xyz, n, 128, 0);            // indices into xyz
//   auto groups  = paco::knnGroups(xyz, n, centres, 16);                   // 128 x 16 indices
//   auto table   = paco::buildLookupTable(xyz, n, labels, centres, 20);    // point -> patch -> plane
#include <cstdint>
#include <vector>

namespace paco {

/// Farthest-point sampling over `num_points` points stored as xyz triples (plain C++ loop: ~8x
/// faster than the same with LibTorch ops). Starts at `first`; returns `count` distinct indices
/// when count <= num_points, else repeats the sequence cyclically. Deterministic.
std::vector<std::int64_t> farthestPointSampling(const float* xyz, std::int64_t num_points,
                                                std::int64_t count, std::int64_t first = 0);

/// For each centre (an index into the cloud), the indices of its `k` nearest points, nearest
/// first (the centre itself comes first). Row-major, centres.size() x k. When k > num_points the
/// nearest points are repeated cyclically.
std::vector<std::int64_t> knnGroups(const float* xyz, std::int64_t num_points,
                                    const std::vector<std::int64_t>& centres, std::int64_t k);

/// The point -> patch -> plane lookup table of one cloud.
struct LookupTable {
  /// Segment label of each centre (the label of the input point it sits on; -1 for none).
  std::vector<int> centre_labels;
  /// For each input point, the index of its nearest centre (its patch).
  std::vector<std::int64_t> point_to_centre;
  /// The kept segments, largest first (ties: smaller label first); at most K. slot s holds
  /// segment slot_segments[s]; slots beyond slot_segments.size() are padding.
  std::vector<int> slot_segments;
  /// Points per kept segment (same order as slot_segments).
  std::vector<std::int64_t> slot_point_counts;
  /// Pooling weights, row-major K x num_centres: 1 where centre c belongs to the plane in slot
  /// s (its label). A kept segment on which no centre sits pools the patches its points map to,
  /// so no kept segment is left without features. Padding rows are all zero.
  std::vector<float> pooling;
};

/// Builds the lookup table. `labels` has num_points entries (-1 = unsegmented); `centres` are
/// point indices (from farthestPointSampling); `slots` = K.
LookupTable buildLookupTable(const float* xyz, std::int64_t num_points, const std::int64_t* labels,
                             const std::vector<std::int64_t>& centres, int slots);

}  // namespace paco
