// The grid behind observed fusion's lines of sight (modules/completion/src/plane_bins.h).
#include "../../modules/completion/src/plane_bins.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace {

using paco::completion::detail::PlaneBins;

std::vector<int> within(const PlaneBins<int>& bins, double a, double b, double radius) {
  std::vector<int> found;
  bins.forEachWithin(a, b, radius, [&](const auto& entry) { found.push_back(entry.value); });
  return found;
}

TEST(PlaneBins, AQueryFindsExactlyTheValuesWithinItsRadiusAcrossCells) {
  PlaneBins<int> bins(1.0);
  // Around the query (0.25, 0.25), in numbers exact in binary: two in its own cell, two in
  // neighbouring cells (one exactly on the radius, which counts), one in its cell but outside the
  // radius, and one two cells away.
  EXPECT_TRUE(bins.insert(0.5, 0.25, 1));    // distance 0.25
  EXPECT_TRUE(bins.insert(0.25, 0.25, 2));   // distance 0
  EXPECT_TRUE(bins.insert(-0.5, 0.25, 3));   // distance 0.75, cell (-1, 0)
  EXPECT_TRUE(bins.insert(0.25, 1.25, 4));   // distance 1 exactly, cell (0, 1)
  EXPECT_TRUE(bins.insert(0.99, 0.99, 5));   // distance 1.05
  EXPECT_TRUE(bins.insert(2.5, 0.25, 6));    // two cells away
  EXPECT_EQ(bins.size(), 6u);
  // Cells in order (-1,-1) ... (1,1), values in order of insertion within a cell.
  EXPECT_EQ(within(bins, 0.25, 0.25, 1.0), (std::vector<int>{3, 1, 2, 4}));
  EXPECT_EQ(within(bins, 0.25, 0.25, 0.25), (std::vector<int>{1, 2}));
}

TEST(PlaneBins, NegativePositionsFallInTheirOwnCells) {
  PlaneBins<int> bins(0.5);
  bins.insert(-0.01, -0.01, 1);
  bins.insert(0.01, 0.01, 2);
  bins.insert(-1.2, -1.2, 3);
  EXPECT_EQ(within(bins, 0.0, 0.0, 0.1), (std::vector<int>{1, 2}));
  EXPECT_EQ(within(bins, -1.1, -1.1, 0.2), (std::vector<int>{3}));
}

TEST(PlaneBins, PositionsBeyondTheGridAreRefusedNotWrapped) {
  PlaneBins<int> bins(1e-3);
  const double far = 1e20, nan = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(bins.insert(far, 0.0, 1));
  EXPECT_FALSE(bins.insert(0.0, -far, 2));
  EXPECT_FALSE(bins.insert(nan, 0.0, 3));
  EXPECT_TRUE(bins.empty());
  EXPECT_TRUE(bins.insert(0.0, 0.0, 4));
  bool visited = false;
  EXPECT_FALSE(bins.forEachWithin(far, 0.0, 1e-3, [&](const auto&) { visited = true; }));
  EXPECT_FALSE(bins.forEachWithin(nan, nan, 1e-3, [&](const auto&) { visited = true; }));
  EXPECT_FALSE(visited);
  EXPECT_TRUE(bins.forEachWithin(0.0, 0.0, 1e-3, [&](const auto&) { visited = true; }));
  EXPECT_TRUE(visited);
}

TEST(PlaneBins, WithoutAWidthNothingIsStoredOrFound) {
  for (const double cell : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN()}) {
    PlaneBins<int> bins(cell);
    EXPECT_FALSE(bins.insert(0.0, 0.0, 1)) << "cell " << cell;
    EXPECT_TRUE(bins.empty());
    EXPECT_FALSE(bins.forEachWithin(0.0, 0.0, 1.0, [](const auto&) {}));
  }
}

}  // namespace
