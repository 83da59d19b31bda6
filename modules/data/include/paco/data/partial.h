#pragma once
// Usage:
//   paco::data::PartialScanner scanner(gt, options);                 // dense sample (+ ray casts)
//   paco::data::PartialScan scan = scanner.scan(viewpointDirection(0, 8), 0.5, seed);
//   // scan.points: 2048 points, scan.normals, scan.labels (GT faces), scan.missing_ratio
#include <paco/data/ground_truth.h>

#include <Eigen/Core>

#include <cstdint>
#include <string>
#include <vector>

namespace paco::data {

/// How the points of a partial view are removed.
enum class RemovalMode {
  Nearest,     ///< AdaPoinTr: drop the dense points nearest to the viewpoint until the ratio is reached
  Visibility,  ///< ray cast: keep points a scanner can see (see doc/dataset.md for the exact rule)
};
std::string toString(RemovalMode mode);          ///< "nearest" / "visibility"
RemovalMode removalModeFromString(const std::string& name);  ///< throws InvalidInputError

/// Direction (unit vector) of viewpoint `view` out of `views`: the 8 cube corners
/// (+-1,+-1,+-1)/sqrt(3) in a fixed order when views <= 8 (AdaPoinTr's fixed viewpoints), else a
/// Fibonacci sphere of `views` directions.
Eigen::Vector3d viewpointDirection(int view, int views);

struct PartialOptions {
  RemovalMode mode = RemovalMode::Nearest;
  std::size_t dense_points = 16384;  ///< dense surface sample the views are cut from (>= output_points)
  std::size_t output_points = 2048;  ///< points of a partial input after resampling
  double viewpoint_distance = 1.0;   ///< distance of the viewpoint from the centre (diagonal units; > 0.5)
  double noise_percent = 0.0;        ///< Gaussian sigma per coordinate, % of the diagonal (0: none)
  int visibility_stations = 8;       ///< Visibility mode: stations at the first 1..8 cube corners (default 8)
  /// Visibility mode: only the scanner at the viewpoint, no station adds to what it sees.
  bool single_scanner = false;
};

/// A partial input.
struct PartialScan {
  std::vector<Eigen::Vector3d> points;   ///< output_points positions (noise added)
  std::vector<Eigen::Vector3d> normals;  ///< normal of each point's GT face
  std::vector<int> labels;               ///< GT face of each point
  double missing_ratio = 0.0;            ///< fraction of the dense sample removed
  double cut_distance = 0.0;             ///< Nearest mode: every kept point is at least this far from the viewpoint
};

/// Cuts partial views from one ground-truth shape. The dense sample (and, in Visibility mode, the
/// visibility of every dense point from every station) is computed once in the constructor and
/// shared by all views and levels.
class PartialScanner {
 public:
  /// `gt` should be normalised (centre at origin, unit diagonal); `seed` fixes the dense sample.
  PartialScanner(const GroundTruth& gt, const PartialOptions& options, std::uint64_t seed);
  ~PartialScanner();
  PartialScanner(const PartialScanner&) = delete;
  PartialScanner& operator=(const PartialScanner&) = delete;

  /// A partial view from `direction` (unit vector) with `missing_ratio` in [0, 1) of the surface
  /// removed; `seed` fixes resampling and noise.
  PartialScan scan(const Eigen::Vector3d& direction, double missing_ratio, std::uint64_t seed) const;

  const std::vector<Eigen::Vector3d>& densePoints() const { return dense_points_; }

 private:
  PartialOptions options_;
  std::vector<Eigen::Vector3d> dense_points_, dense_normals_;
  std::vector<int> dense_labels_;
  /// Visibility mode: visible_[s][i] is true when dense point i is seen from station s.
  std::vector<std::vector<bool>> visible_;
  std::vector<Eigen::Vector3d> stations_;
  SurfaceMesh mesh_;        // Visibility mode: the triangles rays are cast against
  double diagonal_ = 1.0;
};

/// For every point on the surface of `triangles`: true when the segment from the point (moved by
/// `epsilon` along its outward normal) to `eye` crosses no triangle (CGAL AABB tree), i.e. a
/// scanner at `eye` sees it. Back-facing points are not visible.
std::vector<bool> visibleFrom(const SurfaceMesh& triangles, const std::vector<Eigen::Vector3d>& points,
                              const std::vector<Eigen::Vector3d>& normals, const Eigen::Vector3d& eye,
                              double epsilon = 1e-6);

}  // namespace paco::data
