#pragma once
// Usage:
//   Eigen::MatrixXd cost(3, 5);  ... fill: cost(i, j) = cost of giving row i to column j ...
//   std::vector<int> column_of_row = paco::solveAssignment(cost);
//   double total = paco::assignmentCost(cost, column_of_row);
#include <Eigen/Core>

#include <vector>

namespace paco {

/// Minimum-cost assignment on a rectangular cost matrix (Hungarian method with row/column
/// potentials and shortest augmenting paths, O(n² m) for n = min(R, C), m = max(R, C)).
///
/// With R rows and C columns, min(R, C) pairs are formed, each row and each column used at most
/// once, and the sum of their costs is minimal. Returns, for each row, its column, or -1 for the
/// rows left over when R > C. Costs may be negative. Throws InvalidInputError on a non-finite
/// cost. An empty matrix gives an empty (R = 0) or all -1 (C = 0) result.
std::vector<int> solveAssignment(const Eigen::MatrixXd& cost);

/// Sum of cost(i, column_of_row[i]) over the assigned rows (rows with -1 are skipped).
double assignmentCost(const Eigen::MatrixXd& cost, const std::vector<int>& column_of_row);

}  // namespace paco
