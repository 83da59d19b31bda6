#include <paco/encoding/point_grouping.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <set>

namespace paco {
namespace {

std::vector<float> randomCloud(int n, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  std::vector<float> xyz(3 * n);
  for (auto& v : xyz) v = u(random);
  return xyz;
}

float distance2(const std::vector<float>& xyz, int64_t a, int64_t b) {
  float d = 0;
  for (int i = 0; i < 3; ++i) d += (xyz[3 * a + i] - xyz[3 * b + i]) * (xyz[3 * a + i] - xyz[3 * b + i]);
  return d;
}

TEST(PointGrouping, FarthestPointSamplingPicksTheFarthestPointEachTime) {
  const int n = 300;
  const auto xyz = randomCloud(n, 1);
  const auto picked = farthestPointSampling(xyz.data(), n, 40, 7);
  ASSERT_EQ(picked.size(), 40u);
  EXPECT_EQ(picked[0], 7);
  EXPECT_EQ(std::set<int64_t>(picked.begin(), picked.end()).size(), 40u);
  for (std::size_t i = 1; i < picked.size(); ++i) {
    // Brute force: the distance of each point to the picked set so far; the pick maximises it.
    float best = -1;
    for (int p = 0; p < n; ++p) {
      float nearest = std::numeric_limits<float>::infinity();
      for (std::size_t j = 0; j < i; ++j) nearest = std::min(nearest, distance2(xyz, p, picked[j]));
      best = std::max(best, nearest);
    }
    float nearest_of_pick = std::numeric_limits<float>::infinity();
    for (std::size_t j = 0; j < i; ++j)
      nearest_of_pick = std::min(nearest_of_pick, distance2(xyz, picked[i], picked[j]));
    EXPECT_FLOAT_EQ(nearest_of_pick, best) << "pick " << i;
  }
}

TEST(PointGrouping, FarthestPointSamplingRepeatsWhenAskedForMoreThanTheCloud) {
  const std::vector<float> xyz{0, 0, 0, 1, 0, 0, 0.4f, 0, 0};
  const auto picked = farthestPointSampling(xyz.data(), 3, 5, 0);
  EXPECT_EQ(picked, (std::vector<int64_t>{0, 1, 2, 0, 1}));
}

TEST(PointGrouping, KnnGroupsAreTheNearestPointsCentreFirst) {
  const int n = 200, k = 9;
  const auto xyz = randomCloud(n, 2);
  const std::vector<int64_t> centres{0, 17, 150};
  const auto groups = knnGroups(xyz.data(), n, centres, k);
  ASSERT_EQ(groups.size(), centres.size() * k);
  for (std::size_t c = 0; c < centres.size(); ++c) {
    std::vector<std::pair<float, int64_t>> all;
    for (int p = 0; p < n; ++p) all.push_back({distance2(xyz, centres[c], p), p});
    std::sort(all.begin(), all.end());
    EXPECT_EQ(groups[c * k], centres[c]);
    for (int j = 0; j < k; ++j) EXPECT_EQ(groups[c * k + j], all[j].second) << c << " " << j;
  }
}

// Three segments of sizes 60, 30, 10 along x, plus 5 unlabelled points.
struct SegmentedLine {
  std::vector<float> xyz;
  std::vector<int64_t> labels;
  SegmentedLine() {
    auto add = [&](int count, float x0, int64_t label) {
      for (int i = 0; i < count; ++i) {
        xyz.insert(xyz.end(), {x0 + 0.001f * i, 0.01f * (i % 7), 0.0f});
        labels.push_back(label);
      }
    };
    add(30, 0.0f, 2);  // segment 2: 30 points
    add(60, 1.0f, 0);  // segment 0: 60 points
    add(10, 2.0f, 1);  // segment 1: 10 points
    add(5, 3.0f, -1);
  }
  int64_t size() const { return static_cast<int64_t>(labels.size()); }
};

TEST(LookupTable, CentresTakeTheirPointsLabelAndPointsTheirNearestCentre) {
  SegmentedLine line;
  const auto centres = farthestPointSampling(line.xyz.data(), line.size(), 12, 0);
  const auto table = buildLookupTable(line.xyz.data(), line.size(), line.labels.data(), centres, 5);
  ASSERT_EQ(table.centre_labels.size(), centres.size());
  for (std::size_t c = 0; c < centres.size(); ++c)
    EXPECT_EQ(table.centre_labels[c], line.labels[centres[c]]);
  for (int64_t p = 0; p < line.size(); ++p) {
    const int64_t mapped = table.point_to_centre[p];
    for (std::size_t c = 0; c < centres.size(); ++c)
      EXPECT_LE(distance2(line.xyz, p, centres[mapped]), distance2(line.xyz, p, centres[c]));
  }
  // Segments are far apart along x, so every point's patch centre carries the point's label.
  for (int64_t p = 0; p < line.size(); ++p)
    EXPECT_EQ(table.centre_labels[table.point_to_centre[p]], line.labels[p]) << p;
}

TEST(LookupTable, KeepsTheKLargestSegmentsAndPoolsTheirCentres) {
  SegmentedLine line;
  const auto centres = farthestPointSampling(line.xyz.data(), line.size(), 12, 0);
  const int K = 2;
  const auto table = buildLookupTable(line.xyz.data(), line.size(), line.labels.data(), centres, K);
  EXPECT_EQ(table.slot_segments, (std::vector<int>{0, 2}));  // 60 then 30 points; 10 dropped
  EXPECT_EQ(table.slot_point_counts, (std::vector<int64_t>{60, 30}));
  ASSERT_EQ(table.pooling.size(), K * centres.size());
  for (int s = 0; s < K; ++s)
    for (std::size_t c = 0; c < centres.size(); ++c)
      EXPECT_EQ(table.pooling[s * centres.size() + c],
                table.centre_labels[c] == table.slot_segments[s] ? 1.0f : 0.0f);
}

TEST(LookupTable, PadsSlotsWithZerosAndFeedsSegmentsWithoutACentre) {
  SegmentedLine line;
  // One centre only, on segment 0: segments 2 and 1 have no centre of their own.
  const std::vector<int64_t> centres{40};
  const auto table = buildLookupTable(line.xyz.data(), line.size(), line.labels.data(), centres, 5);
  EXPECT_EQ(table.slot_segments, (std::vector<int>{0, 2, 1}));
  ASSERT_EQ(table.pooling.size(), 5u);
  EXPECT_EQ(table.pooling[0], 1.0f);
  EXPECT_EQ(table.pooling[1], 1.0f);  // via its points' nearest centre
  EXPECT_EQ(table.pooling[2], 1.0f);
  EXPECT_EQ(table.pooling[3], 0.0f);  // padding
  EXPECT_EQ(table.pooling[4], 0.0f);
}

}  // namespace
}  // namespace paco
