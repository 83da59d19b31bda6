// paco::solveAssignment (paco/common/assignment.h) against brute force.
#include <paco/common/assignment.h>
#include <paco/common/error.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <numeric>
#include <random>

namespace {

// Minimum over all injective row->column maps (rows <= cols) or column->row maps.
double bruteForce(const Eigen::MatrixXd& cost) {
  const bool wide = cost.rows() <= cost.cols();
  const Eigen::MatrixXd c = wide ? cost : Eigen::MatrixXd(cost.transpose());
  std::vector<int> columns(static_cast<std::size_t>(c.cols()));
  std::iota(columns.begin(), columns.end(), 0);
  double best = std::numeric_limits<double>::infinity();
  do {  // every permutation; the first c.rows() entries are the assignment
    double total = 0.0;
    for (Eigen::Index i = 0; i < c.rows(); ++i) total += c(i, columns[static_cast<std::size_t>(i)]);
    best = std::min(best, total);
  } while (std::next_permutation(columns.begin(), columns.end()));
  return best;
}

void expectValid(const std::vector<int>& assignment, const Eigen::MatrixXd& cost) {
  ASSERT_EQ(assignment.size(), static_cast<std::size_t>(cost.rows()));
  std::vector<int> used;
  for (int j : assignment) {
    if (j < 0) continue;
    EXPECT_LT(j, cost.cols());
    used.push_back(j);
  }
  std::sort(used.begin(), used.end());
  EXPECT_TRUE(std::adjacent_find(used.begin(), used.end()) == used.end()) << "a column is used twice";
  EXPECT_EQ(used.size(), static_cast<std::size_t>(std::min(cost.rows(), cost.cols())));
}

}  // namespace

TEST(Assignment, EqualsBruteForceOnRandomMatrices) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> value(-3.0, 5.0);
  std::uniform_int_distribution<int> small(0, 2);
  const std::vector<std::pair<int, int>> shapes = {{1, 1}, {2, 2}, {3, 3}, {5, 5}, {7, 7}, {3, 6}, {6, 3}, {2, 7}, {7, 4}};
  for (const auto& [rows, cols] : shapes) {
    for (int trial = 0; trial < 20; ++trial) {
      Eigen::MatrixXd cost(rows, cols);
      for (int i = 0; i < rows; ++i)
        for (int j = 0; j < cols; ++j)
          cost(i, j) = trial % 2 ? value(rng) : static_cast<double>(small(rng));  // even trials: many ties
      const std::vector<int> a = paco::solveAssignment(cost);
      expectValid(a, cost);
      EXPECT_NEAR(paco::assignmentCost(cost, a), bruteForce(cost), 1e-9) << rows << "x" << cols << " trial " << trial;
    }
  }
}

TEST(Assignment, KnownPermutationIsRecovered) {
  // Cost 0 on a permutation, 1 elsewhere: the permutation is the unique optimum.
  const std::vector<int> permutation = {3, 0, 4, 1, 2};
  Eigen::MatrixXd cost = Eigen::MatrixXd::Ones(5, 5);
  for (int i = 0; i < 5; ++i) cost(i, permutation[static_cast<std::size_t>(i)]) = 0.0;
  EXPECT_EQ(paco::solveAssignment(cost), permutation);
}

TEST(Assignment, EmptyAndInvalidInput) {
  EXPECT_TRUE(paco::solveAssignment(Eigen::MatrixXd(0, 3)).empty());
  EXPECT_EQ(paco::solveAssignment(Eigen::MatrixXd(2, 0)), (std::vector<int>{-1, -1}));
  Eigen::MatrixXd bad = Eigen::MatrixXd::Zero(2, 2);
  bad(1, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(paco::solveAssignment(bad), paco::InvalidInputError);
}
