#include <paco/common/error.h>
#include <paco/common/assignment.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

using paco::assignmentCost;
using paco::solveAssignment;

namespace {

// Best total over every injective map of the smaller side into the larger one.
double bruteForceMinimum(const Eigen::MatrixXd& cost) {
  const bool wide = cost.rows() <= cost.cols();
  const Eigen::MatrixXd c = wide ? cost : Eigen::MatrixXd(cost.transpose());
  std::vector<int> columns(c.cols());
  std::iota(columns.begin(), columns.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {  // every permutation; its first rows() entries are the assignment
    double total = 0.0;
    for (Eigen::Index i = 0; i < c.rows(); ++i) total += c(i, columns[i]);
    best = std::min(best, total);
  } while (std::next_permutation(columns.begin(), columns.end()));
  return best;
}

void expectValidAssignment(const Eigen::MatrixXd& cost, const std::vector<int>& column_of_row) {
  ASSERT_EQ(column_of_row.size(), static_cast<std::size_t>(cost.rows()));
  std::vector<int> used(cost.cols(), 0);
  int assigned = 0;
  for (int column : column_of_row) {
    if (column < 0) continue;
    ASSERT_LT(column, cost.cols());
    EXPECT_EQ(used[column]++, 0) << "column " << column << " used twice";
    ++assigned;
  }
  EXPECT_EQ(assigned, std::min(cost.rows(), cost.cols()));
}

Eigen::MatrixXd randomCost(int rows, int cols, std::mt19937& rng, bool integers) {
  std::uniform_real_distribution<double> real(-5.0, 10.0);
  std::uniform_int_distribution<int> small(0, 4);  // many ties
  Eigen::MatrixXd cost(rows, cols);
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) cost(i, j) = integers ? small(rng) : real(rng);
  return cost;
}

}  // namespace

TEST(Matching, EqualsBruteForceOnRandomSquare6x6) {
  for (unsigned seed = 0; seed < 300; ++seed) {
    std::mt19937 rng(seed);
    const Eigen::MatrixXd cost = randomCost(6, 6, rng, /*integers=*/seed % 3 == 0);
    const auto assignment = solveAssignment(cost);
    expectValidAssignment(cost, assignment);
    EXPECT_NEAR(assignmentCost(cost, assignment), bruteForceMinimum(cost), 1e-9) << "seed " << seed;
  }
}

TEST(Matching, EqualsBruteForceOnRectangular) {
  const std::vector<std::pair<int, int>> shapes{{1, 6}, {3, 6}, {4, 7}, {6, 4}, {7, 3}, {5, 1}, {2, 2}};
  for (const auto& [rows, cols] : shapes) {
    for (unsigned seed = 0; seed < 60; ++seed) {
      std::mt19937 rng(seed * 31 + rows * 7 + cols);
      const Eigen::MatrixXd cost = randomCost(rows, cols, rng, seed % 2 == 0);
      const auto assignment = solveAssignment(cost);
      expectValidAssignment(cost, assignment);
      EXPECT_NEAR(assignmentCost(cost, assignment), bruteForceMinimum(cost), 1e-9)
          << rows << "x" << cols << " seed " << seed;
    }
  }
}

TEST(Matching, KnownSmallCase) {
  Eigen::MatrixXd cost(3, 3);
  cost << 4, 1, 3,
          2, 0, 5,
          3, 2, 2;
  const auto assignment = solveAssignment(cost);
  EXPECT_EQ(assignment, (std::vector<int>{1, 0, 2}));  // 1 + 2 + 2 = 5
  EXPECT_DOUBLE_EQ(assignmentCost(cost, assignment), 5.0);
}

TEST(Matching, MoreRowsThanColumnsLeavesRowsOut) {
  Eigen::MatrixXd cost(3, 1);
  cost << 5, -1, 2;
  const auto assignment = solveAssignment(cost);
  EXPECT_EQ(assignment, (std::vector<int>{-1, 0, -1}));
}

TEST(Matching, LargeRectangularIsConsistent) {
  // 30 GT planes x 40 predictions, as in training: valid and no worse than the greedy answer.
  std::mt19937 rng(7);
  const Eigen::MatrixXd cost = randomCost(30, 40, rng, false);
  const auto assignment = solveAssignment(cost);
  expectValidAssignment(cost, assignment);
  std::vector<char> taken(40, 0);
  double greedy = 0.0;
  for (int i = 0; i < 30; ++i) {
    int best = -1;
    for (int j = 0; j < 40; ++j)
      if (!taken[j] && (best < 0 || cost(i, j) < cost(i, best))) best = j;
    taken[best] = 1;
    greedy += cost(i, best);
  }
  EXPECT_LE(assignmentCost(cost, assignment), greedy + 1e-9);
}

TEST(Matching, EmptyAndNonFinite) {
  EXPECT_TRUE(solveAssignment(Eigen::MatrixXd(0, 5)).empty());
  EXPECT_EQ(solveAssignment(Eigen::MatrixXd(2, 0)), (std::vector<int>{-1, -1}));
  Eigen::MatrixXd bad = Eigen::MatrixXd::Zero(2, 2);
  bad(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(solveAssignment(bad), paco::InvalidInputError);
}

// The nearest-neighbour kernels behind fusion (internal to paco_completion).
#include "../../modules/completion/src/nearest_neighbours.h"

namespace {

float squaredDistance(const std::vector<float>& rows, std::int64_t a, std::int64_t b) {
  float sum = 0.0f;
  for (int c = 0; c < 3; ++c) sum += (rows[3 * a + c] - rows[3 * b + c]) * (rows[3 * a + c] - rows[3 * b + c]);
  return sum;
}

TEST(NearestNeighbours, TheNearestOtherPointIsExactWithTheKdTreeToo) {
  // 2,000 points: 4e6 pairs, above kBruteForcePairs, so the kd-tree answers; 40 points brute force.
  std::mt19937 random(7);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  for (std::int64_t count : {40, 2000}) {
    std::vector<float> rows(3 * static_cast<std::size_t>(count));
    for (float& v : rows) v = uniform(random);
    rows[3] = rows[0], rows[4] = rows[1], rows[5] = rows[2];  // a duplicate: each is the other's nearest
    std::vector<std::int64_t> nearest(static_cast<std::size_t>(count));
    paco::completion::detail::nearestOtherPoint(rows.data(), count, nearest.data());
    EXPECT_EQ(nearest[0], 1);
    EXPECT_EQ(nearest[1], 0);
    for (std::int64_t i = 0; i < count; ++i) {
      ASSERT_NE(nearest[i], i);
      float best = std::numeric_limits<float>::infinity();
      for (std::int64_t j = 0; j < count; ++j)
        if (j != i) best = std::min(best, squaredDistance(rows, i, j));
      EXPECT_EQ(squaredDistance(rows, i, nearest[i]), best) << "point " << i << " of " << count;
    }
  }
}

TEST(NearestNeighbours, CoordinatesWhoseSquaresOverflowStillGiveAValidIndex) {
  // Squared distances near 1e40 overflow a float: FLANN then finds nothing.
  std::vector<float> data = {1e20f, 0, 0, -1e20f, 0, 0, 0, 1e20f, 0};
  std::vector<float> queries(3 * 600, 3e20f);
  std::vector<std::int64_t> nearest(600, -7);
  paco::completion::detail::nearestIn(data.data(), 3, queries.data(), 600, nearest.data());
  for (std::int64_t n : nearest) {
    EXPECT_GE(n, 0);
    EXPECT_LT(n, 3);
  }
}

}  // namespace
