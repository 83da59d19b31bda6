#pragma once
// A hashed grid of square cells on a plane, for the lines of sight of observed fusion: values are
// stored at their position (a, b) across a line of sight, and a query visits those within a
// radius of its own position. Internal to paco_completion.
#include <cmath>
#include <cstddef>
#include <unordered_map>
#include <vector>

namespace paco::completion::detail {

template <typename T>
class PlaneBins {
 public:
  struct Entry {
    double a, b;
    T value;
  };

  /// Cells `cell` wide; a cell that is not > 0 (or not finite) stores nothing.
  explicit PlaneBins(double cell) : cell_(cell) {}

  /// Stores `value` at (a, b). False, and nothing stored, when there are no cells or the position
  /// is too far out for a cell index (or not finite).
  bool insert(double a, double b, const T& value) {
    long long ia = 0, ib = 0;
    if (!cellOf(a, b, ia, ib)) return false;
    cells_[key(ia, ib)].push_back({a, b, value});
    ++size_;
    return true;
  }

  /// Calls visit(entry) for every stored entry within `radius` of (a, b), the boundary included,
  /// cell by cell and in the order of insertion within a cell. `radius` must be at most the cell
  /// width, since only the 3 x 3 cells around the query are visited. False, with nothing visited,
  /// when (a, b) has no cell (see insert).
  template <typename Visit>
  bool forEachWithin(double a, double b, double radius, Visit&& visit) const {
    long long ia = 0, ib = 0;
    if (!cellOf(a, b, ia, ib)) return false;
    for (long long da = -1; da <= 1; ++da)
      for (long long db = -1; db <= 1; ++db) {
        const auto found = cells_.find(key(ia + da, ib + db));
        if (found == cells_.end()) continue;
        for (const Entry& entry : found->second)
          if ((entry.a - a) * (entry.a - a) + (entry.b - b) * (entry.b - b) <= radius * radius) visit(entry);
      }
    return true;
  }

  double cellWidth() const { return cell_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

 private:
  bool cellOf(double a, double b, long long& ia, long long& ib) const {
    if (!(cell_ > 0.0) || !std::isfinite(cell_)) return false;
    // Checked as doubles: casting a cell beyond the range of long long is undefined.
    const double fa = std::floor(a / cell_), fb = std::floor(b / cell_);
    if (!(std::abs(fa) < static_cast<double>(kMaxCell) && std::abs(fb) < static_cast<double>(kMaxCell))) return false;
    ia = static_cast<long long>(fa);
    ib = static_cast<long long>(fb);
    return true;
  }
  // One key per cell: |ia|, |ib| < kMaxCell, so ia * (2 kMaxCell + 1) + ib is unique and fits.
  static long long key(long long ia, long long ib) { return ia * (2 * kMaxCell + 1) + ib; }
  static constexpr long long kMaxCell = 1LL << 30;

  double cell_;
  std::size_t size_ = 0;
  std::unordered_map<long long, std::vector<Entry>> cells_;
};

}  // namespace paco::completion::detail
