#include <paco/common/assignment.h>
#include <paco/common/error.h>

#include <limits>

namespace paco {

namespace {

// Hungarian method for n <= m (rows <= columns): one augmenting shortest path per row, with
// potentials u (rows) and v (columns) keeping reduced costs non-negative. Index 0 is a sentinel
// column, so rows and columns are 1-based inside.
std::vector<int> solveWide(const Eigen::MatrixXd& cost) {
  const int n = static_cast<int>(cost.rows());
  const int m = static_cast<int>(cost.cols());
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0);
  std::vector<int> row_of_col(m + 1, 0), way(m + 1, 0);
  for (int i = 1; i <= n; ++i) {
    row_of_col[0] = i;
    int j0 = 0;
    std::vector<double> min_to(m + 1, inf);
    std::vector<char> used(m + 1, 0);
    do {
      used[j0] = 1;
      const int i0 = row_of_col[j0];
      double delta = inf;
      int j1 = 0;
      for (int j = 1; j <= m; ++j) {
        if (used[j]) continue;
        const double reduced = cost(i0 - 1, j - 1) - u[i0] - v[j];
        if (reduced < min_to[j]) {
          min_to[j] = reduced;
          way[j] = j0;
        }
        if (min_to[j] < delta) {
          delta = min_to[j];
          j1 = j;
        }
      }
      for (int j = 0; j <= m; ++j) {
        if (used[j]) {
          u[row_of_col[j]] += delta;
          v[j] -= delta;
        } else {
          min_to[j] -= delta;
        }
      }
      j0 = j1;
    } while (row_of_col[j0] != 0);
    do {  // flip the augmenting path
      const int j1 = way[j0];
      row_of_col[j0] = row_of_col[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> column_of_row(n, -1);
  for (int j = 1; j <= m; ++j)
    if (row_of_col[j] != 0) column_of_row[row_of_col[j] - 1] = j - 1;
  return column_of_row;
}

}  // namespace

std::vector<int> solveAssignment(const Eigen::MatrixXd& cost) {
  const auto rows = cost.rows(), cols = cost.cols();
  if (!cost.allFinite())
    throw InvalidInputError("solveAssignment: the cost matrix has a non-finite entry; costs must be finite numbers");
  if (rows == 0) return {};
  if (cols == 0) return std::vector<int>(static_cast<std::size_t>(rows), -1);
  if (rows <= cols) return solveWide(cost);
  // More rows than columns: solve the transpose, then invert the pairing.
  const std::vector<int> row_of_col = solveWide(cost.transpose());
  std::vector<int> column_of_row(static_cast<std::size_t>(rows), -1);
  for (std::size_t j = 0; j < row_of_col.size(); ++j)
    if (row_of_col[j] >= 0) column_of_row[static_cast<std::size_t>(row_of_col[j])] = static_cast<int>(j);
  return column_of_row;
}

double assignmentCost(const Eigen::MatrixXd& cost, const std::vector<int>& column_of_row) {
  double total = 0.0;
  for (std::size_t i = 0; i < column_of_row.size(); ++i)
    if (column_of_row[i] >= 0) total += cost(static_cast<Eigen::Index>(i), column_of_row[i]);
  return total;
}

}  // namespace paco
