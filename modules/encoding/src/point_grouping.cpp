#include <paco/common/error.h>
#include <paco/encoding/point_grouping.h>

#include <algorithm>
#include <limits>
#include <map>
#include <numeric>

namespace paco {
namespace {

inline float squaredDistance(const float* a, const float* b) {
  const float dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return dx * dx + dy * dy + dz * dz;
}

}  // namespace

std::vector<std::int64_t> farthestPointSampling(const float* xyz, std::int64_t num_points,
                                                std::int64_t count, std::int64_t first) {
  if (num_points <= 0) throw InvalidInputError("farthestPointSampling: the cloud is empty");
  if (first < 0 || first >= num_points)
    throw InvalidInputError("farthestPointSampling: start index out of range");
  std::vector<std::int64_t> order;
  const std::int64_t distinct = std::min(count, num_points);
  order.reserve(static_cast<std::size_t>(std::max<std::int64_t>(count, 0)));
  std::vector<float> nearest(static_cast<std::size_t>(num_points),
                             std::numeric_limits<float>::infinity());
  std::int64_t current = first;
  for (std::int64_t i = 0; i < distinct; ++i) {
    order.push_back(current);
    const float* c = xyz + 3 * current;
    std::int64_t farthest = 0;
    float farthest_distance = -1.0f;
    for (std::int64_t p = 0; p < num_points; ++p) {
      const float d = std::min(nearest[p], squaredDistance(xyz + 3 * p, c));
      nearest[p] = d;
      if (d > farthest_distance) {
        farthest_distance = d;
        farthest = p;
      }
    }
    current = farthest;
  }
  for (std::int64_t i = distinct; i < count; ++i) order.push_back(order[i % distinct]);
  return order;
}

std::vector<std::int64_t> knnGroups(const float* xyz, std::int64_t num_points,
                                    const std::vector<std::int64_t>& centres, std::int64_t k) {
  if (num_points <= 0) throw InvalidInputError("knnGroups: the cloud is empty");
  if (k < 1) throw InvalidInputError("knnGroups: k must be >= 1");
  const std::int64_t kept = std::min(k, num_points);
  std::vector<std::int64_t> groups;
  groups.reserve(centres.size() * static_cast<std::size_t>(k));
  std::vector<std::pair<float, std::int64_t>> candidates(static_cast<std::size_t>(num_points));
  for (std::int64_t centre : centres) {
    const float* c = xyz + 3 * centre;
    for (std::int64_t p = 0; p < num_points; ++p)
      candidates[p] = {squaredDistance(xyz + 3 * p, c), p};
    // The centre itself first: distance 0 and then by index makes ties deterministic.
    candidates[centre].first = -1.0f;
    std::partial_sort(candidates.begin(), candidates.begin() + kept, candidates.end());
    for (std::int64_t j = 0; j < k; ++j) groups.push_back(candidates[j % kept].second);
  }
  return groups;
}

LookupTable buildLookupTable(const float* xyz, std::int64_t num_points, const std::int64_t* labels,
                             const std::vector<std::int64_t>& centres, int slots) {
  if (num_points <= 0) throw InvalidInputError("buildLookupTable: the cloud is empty");
  if (centres.empty()) throw InvalidInputError("buildLookupTable: no centres");
  if (slots < 1) throw InvalidInputError("buildLookupTable: slots must be >= 1");
  LookupTable table;
  const std::size_t num_centres = centres.size();
  table.centre_labels.resize(num_centres);
  for (std::size_t c = 0; c < num_centres; ++c)
    table.centre_labels[c] = static_cast<int>(labels[centres[c]]);

  table.point_to_centre.resize(static_cast<std::size_t>(num_points));
  for (std::int64_t p = 0; p < num_points; ++p) {
    float best = std::numeric_limits<float>::infinity();
    std::int64_t best_centre = 0;
    for (std::size_t c = 0; c < num_centres; ++c) {
      const float d = squaredDistance(xyz + 3 * p, xyz + 3 * centres[c]);
      if (d < best) {
        best = d;
        best_centre = static_cast<std::int64_t>(c);
      }
    }
    table.point_to_centre[p] = best_centre;
  }

  std::map<std::int64_t, std::int64_t> counts;
  for (std::int64_t p = 0; p < num_points; ++p)
    if (labels[p] >= 0) ++counts[labels[p]];
  std::vector<std::pair<std::int64_t, std::int64_t>> by_size(counts.begin(), counts.end());
  std::stable_sort(by_size.begin(), by_size.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  if (by_size.size() > static_cast<std::size_t>(slots)) by_size.resize(slots);
  for (const auto& [label, count] : by_size) {
    table.slot_segments.push_back(static_cast<int>(label));
    table.slot_point_counts.push_back(count);
  }

  table.pooling.assign(static_cast<std::size_t>(slots) * num_centres, 0.0f);
  for (std::size_t s = 0; s < table.slot_segments.size(); ++s) {
    float* row = table.pooling.data() + s * num_centres;
    bool any = false;
    for (std::size_t c = 0; c < num_centres; ++c)
      if (table.centre_labels[c] == table.slot_segments[s]) row[c] = 1.0f, any = true;
    if (!any)  // a small segment with no centre on it: pool the patches its points fall in
      for (std::int64_t p = 0; p < num_points; ++p)
        if (labels[p] == table.slot_segments[s]) row[table.point_to_centre[p]] = 1.0f;
  }
  return table;
}

}  // namespace paco
