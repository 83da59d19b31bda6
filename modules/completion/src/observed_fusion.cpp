#include <paco/completion/observed_fusion.h>

#include "nearest_neighbours.h"
#include "plane_bins.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/orientation.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <pcl/common/centroid.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <utility>

namespace paco {
namespace {


Eigen::Vector3d position(const pcl::PointNormal& p) { return {p.x, p.y, p.z}; }

// Mean |distance| of (at most 256 evenly spaced) points to a plane: enough to rank planes.
double meanDistance(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& plane) {
  const std::size_t n = points.size();
  const std::size_t stride = std::max<std::size_t>(1, n / 256);
  double sum = 0.0;
  std::size_t count = 0;
  for (std::size_t i = 0; i < n; i += stride, ++count) sum += std::abs(plane.signedDistance(position(points[i])));
  return count == 0 ? std::numeric_limits<double>::infinity() : sum / static_cast<double>(count);
}

// Moves the points onto the plane and gives them its normal.
void projectOnto(const Plane& plane, pcl::PointCloud<pcl::PointNormal>& points) {
  for (auto& p : points) {
    const Eigen::Vector3d q = plane.project(position(p));
    p.x = static_cast<float>(q.x());
    p.y = static_cast<float>(q.y());
    p.z = static_cast<float>(q.z());
    p.normal_x = static_cast<float>(plane.normal.x());
    p.normal_y = static_cast<float>(plane.normal.y());
    p.normal_z = static_cast<float>(plane.normal.z());
  }
}

// The primitive takes the plane's position and tilt but keeps its own orientation (the
// network's, outward), and its points move onto it.
void takePlane(PlanarPrimitive& primitive, const Plane& plane) {
  primitive.plane = plane.normal.dot(primitive.plane.normal) < 0.0 ? plane.flipped() : plane;
  projectOnto(primitive.plane, primitive.points);
}

double diagonalOf(const std::vector<PlanarPrimitive>& primitives) {
  Eigen::AlignedBox3d box;
  for (const auto& primitive : primitives)
    for (const auto& p : primitive.points) box.extend(position(p));
  return box.isEmpty() ? 0.0 : box.diagonal().norm();
}

// An observed segment whose plane is trusted: enough points to fit it, and a normal.
bool isTrusted(const PlanarPrimitive& segment, std::size_t min_points) {
  return segment.points.size() >= min_points && segment.plane.normal.norm() > 0.0;
}

// The unit normals of the trusted observed segments and their sizes, and the dominant axes they
// imply. With a distant scanner the axes hold its lines of sight (`scanner_direction`, zero when
// unknown): everything between the scan and the scanner is empty, so the box that closes the hidden
// side has its walls along the lines of sight and its far face across them. Tilted onto a seen
// plane instead (a roof slope, when no two seen planes are perpendicular), the box closed an
// airborne scan of a building with a sloping floor and a slab that stood above the roof; without
// the scanner's direction, the bisectors of mirror-image slopes give a level box.
struct SeenNormals {
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> sizes;
  std::optional<Eigen::Matrix3d> axes;
  // No scanner direction; seen planes at an angle, but none perpendicular: the axes are a guess,
  // from mirror-image planes or else from the largest plane.
  bool axes_on_mirror_pair = false;
  bool axes_on_one_plane = false;
};

SeenNormals seenNormals(const std::vector<PlanarPrimitive>& observed, std::size_t min_points,
                        const Eigen::Vector3d& scanner_direction) {
  SeenNormals seen;
  for (const auto& segment : observed) {
    if (!isTrusted(segment, min_points)) continue;
    seen.normals.push_back(segment.plane.normal.normalized());
    seen.sizes.push_back(static_cast<double>(segment.points.size()));
  }
  const ClosingBoxAxes axes = closingBoxAxes(seen.normals, seen.sizes, scanner_direction);
  seen.axes = axes.axes;
  seen.axes_on_mirror_pair = axes.on_mirror_pair;
  seen.axes_on_one_plane = axes.on_one_plane;
  return seen;
}

// The seen directions: every trusted observed segment's normal and the dominant axes.
std::vector<Eigen::Vector3d> seenDirections(const SeenNormals& seen) {
  std::vector<Eigen::Vector3d> directions = seen.normals;
  if (seen.axes)
    for (int k = 0; k < 3; ++k) directions.push_back(seen.axes->col(k));
  return directions;
}

// The direction nearest to an unoriented normal, and the angle to it (nullptr and pi/2 when there
// is none).
struct NearestDirection {
  const Eigen::Vector3d* direction = nullptr;
  double angle = kPi / 2.0;
};

NearestDirection nearestDirection(const Eigen::Vector3d& normal, const std::vector<Eigen::Vector3d>& directions) {
  NearestDirection nearest;
  double best = -1.0;
  for (const auto& d : directions) {
    const double c = std::abs(normal.dot(d));
    if (c > best) {
      best = c;
      nearest.direction = &d;
    }
  }
  if (nearest.direction) nearest.angle = std::acos(std::min(1.0, best));
  return nearest;
}

// Turns the primitive's plane onto `direction` (keeping its outward side), through its points'
// centroid.
void turnOnto(PlanarPrimitive& primitive, const Eigen::Vector3d& direction) {
  const Eigen::Vector3d normal = primitive.plane.normal.normalized();
  const Eigen::Vector3d turned = normal.dot(direction) < 0.0 ? -direction : direction;
  Eigen::Vector3d pivot = primitive.plane.foot();
  if (!primitive.points.empty()) {
    pivot.setZero();
    for (const auto& p : primitive.points) pivot += position(p);
    pivot /= static_cast<double>(primitive.points.size());
  }
  primitive.plane = Plane::fromPointAndNormal(pivot, turned);
  projectOnto(primitive.plane, primitive.points);
}

// Turns the primitive's plane onto the nearest direction within max_angle (keeping its outward
// side), through its points' centroid; true when it turned.
bool alignWithNearest(PlanarPrimitive& primitive, const std::vector<Eigen::Vector3d>& directions, double max_angle) {
  const NearestDirection nearest = nearestDirection(primitive.plane.normal.normalized(), directions);
  if (!nearest.direction || nearest.angle > max_angle) return false;
  turnOnto(primitive, *nearest.direction);
  return true;
}

// A seen face turns onto the nearest axis of the seen box when its fitted normal lies within this
// many standard errors of it (squareNoisySeenFace).
constexpr double kSquareStandardErrors = 4.0;

// The standard error of a face's fitted normal, in radians: the RMS distance of its points to its
// plane over the square root of their count times their spread (standard deviation) across the
// face's narrow way; 0 for fewer than three points.
double normalStandardError(const PlanarPrimitive& face) {
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  Eigen::Vector4d centroid = Eigen::Vector4d::Zero();
  const std::size_t n = pcl::computeMeanAndCovarianceMatrix(face.points, covariance, centroid);
  if (n < 3) return 0.0;
  // The middle eigenvalue: the spread across the narrow way in the plane (the smallest is across it).
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> spread(covariance);
  const double narrow = std::sqrt(std::max(spread.eigenvalues()[1], 0.0));
  if (!(narrow > 0.0)) return 0.0;
  return rmsDistance(face.points, face.plane) / (std::sqrt(static_cast<double>(n)) * narrow);
}

// Turns a seen face onto the nearest of the box axes (through its points' centroid, keeping its
// outward side) when it lies off that axis by less than kSquareStandardErrors standard errors of
// its fitted normal and at most max_angle; true when it turned. On a noisy scan the fitted plane
// of a narrow face tilts by a few degrees, and the assemblers carried the tilt across the part
// (forty-sixth session: a 0.15-wide strip seen with 293 points tilted by 2.75 degrees, and the
// cell complex's mesh lost a face to it; noise of 1 % of the diagonal, CD -0.135 +- 0.018 with
// the cell complex). A clean scan fits its planes far more closely, so a face tilted on purpose
// (a draft angle) keeps its tilt, and a face already on an axis is left alone.
bool squareNoisySeenFace(PlanarPrimitive& face, const std::vector<Eigen::Vector3d>& axes, double max_angle) {
  const NearestDirection nearest = nearestDirection(face.plane.normal.normalized(), axes);
  if (!nearest.direction || !(nearest.angle > 1e-9) ||
      nearest.angle > std::min(max_angle, kSquareStandardErrors * normalStandardError(face)))
    return false;
  turnOnto(face, *nearest.direction);
  return true;
}

// The box of the observed points on the dominant seen axes (the coordinate axes without them).
struct SeenBox {
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns
  Eigen::AlignedBox3d box;                             // in axes coordinates
  bool contains(const pcl::PointNormal& p) const { return box.contains(axes.transpose() * position(p)); }
};

SeenBox seenBox(const std::vector<PlanarPrimitive>& observed, const SeenNormals& seen) {
  SeenBox result;
  if (seen.axes) result.axes = *seen.axes;
  for (const auto& segment : observed)
    for (const auto& p : segment.points) result.box.extend(result.axes.transpose() * position(p));
  return result;
}

// Noise carries a scan's outermost points off the face they lie on by a few times the scatter of
// its points about its plane (putBoxSidesOnSeenFaces).
constexpr double kBoxSideNoiseWidths = 4.0;

// Moves each side of the box onto the outermost trusted seen face parallel to it (within
// max_angle) that lies within kBoxSideNoiseWidths times its points' RMS distance to its plane
// from the side; the face's position is its points' mean along the axis. On a noisy scan the
// side lay a noise's width off the seen face, the fill put its points on a second plane there,
// and the assemblers made a thin slab of the two over the part's notches (forty-sixth session:
// noise of 1 % of the diagonal, HD 13.9 -> 11.7 at 25 % missing with the cell complex). On a
// clean scan a face on a side is at the side already, and a face tilted within max_angle spreads
// along the axis by far more than its scatter, so neither moves it.
void putBoxSidesOnSeenFaces(SeenBox& seen, const std::vector<PlanarPrimitive>& observed, std::size_t min_points,
                            double max_angle) {
  if (seen.box.isEmpty()) return;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d axis = seen.axes.col(k);
    std::optional<double> low, high;  // the outermost seen face near each side
    for (const auto& segment : observed) {
      if (!isTrusted(segment, min_points) || std::abs(segment.plane.normal.normalized().dot(axis)) < std::cos(max_angle))
        continue;
      double mean = 0.0;
      for (const auto& p : segment.points) mean += position(p).dot(axis);
      mean /= static_cast<double>(segment.points.size());
      const double reach = kBoxSideNoiseWidths * rmsDistance(segment.points, segment.plane);
      if (mean - seen.box.min()[k] <= reach && (!low || mean < *low)) low = mean;
      if (seen.box.max()[k] - mean <= reach && (!high || mean > *high)) high = mean;
    }
    if (low) seen.box.min()[k] = *low;
    if (high) seen.box.max()[k] = *high;
  }
}

// The same box grown by `margin` times its diagonal on every side.
SeenBox grown(SeenBox seen, double margin) {
  if (!seen.box.isEmpty()) {
    const Eigen::Vector3d grow = Eigen::Vector3d::Constant(margin * seen.box.diagonal().norm());
    seen.box.min() -= grow;
    seen.box.max() += grow;
  }
  return seen;
}

// Keeps, in order, the points whose index `keep` accepts; returns how many went.
template <typename Keep>
std::size_t keepWhere(pcl::PointCloud<pcl::PointNormal>& points, Keep keep) {
  const std::size_t before = points.size();
  std::size_t kept = 0;
  for (std::size_t i = 0; i < before; ++i)
    if (keep(i)) points[kept++] = points[i];
  points.resize(kept);
  return before - kept;
}

// Keeps the points inside the box; returns how many went.
std::size_t keepInside(const SeenBox& seen, pcl::PointCloud<pcl::PointNormal>& points) {
  return keepWhere(points, [&](std::size_t i) { return seen.contains(points[i]); });
}

// Distance of each query point to its nearest point of the clouds (infinity when they are empty).
std::vector<double> nearestDistances(const std::vector<Eigen::Vector3d>& queries,
                                     const std::vector<const pcl::PointCloud<pcl::PointNormal>*>& clouds) {
  std::vector<float> targets;
  for (const auto* cloud : clouds)
    for (const auto& p : *cloud) targets.insert(targets.end(), {p.x, p.y, p.z});
  std::vector<double> distances(queries.size(), std::numeric_limits<double>::infinity());
  if (queries.empty() || targets.empty()) return distances;
  std::vector<float> rows;
  rows.reserve(3 * queries.size());
  for (const auto& q : queries) rows.insert(rows.end(), {float(q.x()), float(q.y()), float(q.z())});
  std::vector<std::int64_t> nearest(queries.size());
  completion::detail::nearestIn(targets.data(), static_cast<std::int64_t>(targets.size() / 3), rows.data(),
                                static_cast<std::int64_t>(queries.size()), nearest.data());
  for (std::size_t i = 0; i < queries.size(); ++i) {
    const float* t = &targets[3 * static_cast<std::size_t>(nearest[i])];
    distances[i] = (queries[i] - Eigen::Vector3d(t[0], t[1], t[2])).norm();
  }
  return distances;
}

// Keeps 1 + floor((n - 1) * fraction) of the n points, evenly spaced from the first, but at least
// min_points (all when n is smaller); returns how many went.
std::size_t thinOut(pcl::PointCloud<pcl::PointNormal>& points, double fraction, std::size_t min_points) {
  const std::size_t before = points.size();
  if (before <= min_points) return 0;
  fraction = std::max(fraction, static_cast<double>(min_points) / static_cast<double>(before));
  return keepWhere(points, [fraction](std::size_t i) {
    return i == 0 || std::floor(static_cast<double>(i) * fraction) > std::floor(static_cast<double>(i - 1) * fraction);
  });
}

// The median distance from a seen point to its nearest other seen point (0 for fewer than two).
double medianSpacing(const std::vector<PlanarPrimitive>& observed) {
  std::vector<float> rows;
  for (const auto& segment : observed)
    for (const auto& p : segment.points) rows.insert(rows.end(), {p.x, p.y, p.z});
  const std::size_t count = rows.size() / 3;
  if (count < 2) return 0.0;
  std::vector<std::int64_t> nearest(count);
  completion::detail::nearestOtherPoint(rows.data(), static_cast<std::int64_t>(count), nearest.data());
  std::vector<double> spacing(count);
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t j = static_cast<std::size_t>(nearest[i]);
    spacing[i] = (Eigen::Map<const Eigen::Vector3f>(&rows[3 * i]).cast<double>() -
                  Eigen::Map<const Eigen::Vector3f>(&rows[3 * j]).cast<double>())
                     .norm();
  }
  std::nth_element(spacing.begin(), spacing.begin() + static_cast<std::ptrdiff_t>(count / 2), spacing.end());
  return spacing[count / 2];
}

// What the scan's trusted segments show along lines of sight: for a point and one of a few
// directions, the first seen point met each way along the line through it (within `radius` of
// the line, and more than `gap` from the point along it). Segments seen edge-on (more than 60
// degrees off the direction) neither show nor block.
class SightLines {
 public:
  struct Met {
    double t;          // along the direction
    bool faces_along;  // its segment's normal points along the direction
  };
  struct FirstMet {
    const Met* ahead = nullptr;   // along +direction
    const Met* behind = nullptr;  // along -direction
  };

  /// One direction per frame: its columns are the direction and two unit vectors across it.
  SightLines(const std::vector<PlanarPrimitive>& observed, std::size_t min_points,
             const std::vector<Eigen::Matrix3d>& frames, double radius, double min_facing = kMinFacing)
      : radius_(radius) {
    directions_.reserve(frames.size());
    for (const Eigen::Matrix3d& frame : frames) {
      // Cells as wide as a line: a line of no width has no cells and meets no point.
      Direction direction{frame.col(0), frame.col(1), frame.col(2), completion::detail::PlaneBins<Met>(radius)};
      for (const auto& segment : observed) {
        if (!isTrusted(segment, min_points)) continue;
        const double facing = segment.plane.normal.normalized().dot(direction.along);
        if (std::abs(facing) < min_facing) continue;
        for (const auto& p : segment.points) {
          const Eigen::Vector3d x = position(p);
          direction.met.insert(x.dot(direction.across), x.dot(direction.up), Met{x.dot(direction.along), facing > 0.0});
        }
      }
      directions_.push_back(std::move(direction));
    }
  }

  std::size_t size() const { return directions_.size(); }
  const Eigen::Vector3d& along(std::size_t k) const { return directions_[k].along; }

  FirstMet firstMet(const Eigen::Vector3d& q, std::size_t k, double gap = 0.0) const {
    FirstMet first;
    const Direction& direction = directions_[k];
    const double qt = q.dot(direction.along);
    direction.met.forEachWithin(q.dot(direction.across), q.dot(direction.up), radius_, [&](const auto& entry) {
      const Met& p = entry.value;
      if (p.t > qt + gap && (!first.ahead || p.t < first.ahead->t)) first.ahead = &p;
      if (p.t < qt - gap && (!first.behind || p.t > first.behind->t)) first.behind = &p;
    });
    return first;
  }

 private:
  static constexpr double kMinFacing = 0.5;  // cos 60 degrees
  struct Direction {
    Eigen::Vector3d along, across, up;
    completion::detail::PlaneBins<Met> met;  // the seen points, binned across the direction
  };

  double radius_;
  std::vector<Direction> directions_;
};

// One frame per box axis, for SightLines: the axis, then the other two.
std::vector<Eigen::Matrix3d> boxAxisFrames(const Eigen::Matrix3d& axes) {
  std::vector<Eigen::Matrix3d> frames(3);
  for (int k = 0; k < 3; ++k) frames[k] << axes.col(k), axes.col((k + 1) % 3), axes.col((k + 2) % 3);
  return frames;
}

// Space the seen faces show to be empty: a point is in front of a seen surface when, looking from
// it along one of the box axes, the first point met belongs to a seen face whose normal faces
// back at it. A box-face point there lies over a seen step, notch or chamfer, or in a gap the
// part does not fill: the part's boundary is that surface, and filling the box face would close
// the concavity. Only the hidden side of a seen surface can hold material. The points are the
// seen ones and the network's points of the seen faces that the scan does not contradict (the
// part of a seen face that the scan missed, such as the rest of a step's floor); with the seen
// points alone, the fill closed the far end of most hidden steps and slots (thirty-third
// session: tuning parts at 75 % missing, PolyFit CD 4.14 -> 3.99).
class SeenFreeSpace {
 public:
  SeenFreeSpace(const std::vector<PlanarPrimitive>& seen_faces, std::size_t min_points, const Eigen::Matrix3d& axes,
                double radius)
      : lines_(seen_faces, min_points, boxAxisFrames(axes), radius) {}

  bool showsEmpty(const Eigen::Vector3d& q) const {
    for (std::size_t k = 0; k < lines_.size(); ++k) {
      const SightLines::FirstMet first = lines_.firstMet(q, k);
      // Looking along +axis, a surface faces back when its normal points along -axis.
      if ((first.ahead && !first.ahead->faces_along) || (first.behind && first.behind->faces_along)) return true;
    }
    return false;
  }

 private:
  SightLines lines_;
};

// What a scanner at a known place saw (ObservedFusionOptions::scanner_direction/position): the
// seen points binned across its lines of sight. A surface nearer to the scanner than every seen
// point within a cell of its line of sight, or on a line of sight that passes none, would have
// been seen.
class ScannerView {
 public:
  ScannerView(const std::vector<PlanarPrimitive>& observed, const ObservedFusionOptions& options, double diagonal)
      : tolerance_(options.scanner_cell * diagonal) {
    std::vector<Eigen::Vector3d> seen;
    for (const auto& segment : observed)
      for (const auto& p : segment.points) seen.push_back(position(p));
    // On a sparse scan a line of sight between two seen points must still count as seen.
    tolerance_ = std::max(tolerance_, kSpacings * medianSpacing(observed));
    if (seen.empty() || !(tolerance_ > 0.0)) return;
    origin_ = seen.front();
    if (options.scanner_position) {
      eye_ = *options.scanner_position;
      Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
      for (const auto& x : seen) centroid += x;
      centroid /= static_cast<double>(seen.size());
      if (!((centroid - *eye_).norm() > tolerance_))
        throw InvalidInputError("fuseWithObserved: the scanner position is at the centre of the seen points; give "
                                "where the scanner stood, outside the object");
      along_ = (centroid - *eye_).normalized();
    } else {
      along_ = -options.scanner_direction.normalized();  // from the scanner towards the object
    }
    across_ = along_.unitOrthogonal();
    up_ = along_.cross(across_);
    double cell = tolerance_;
    if (eye_) {
      // Cells of directions, as wide as a cell at the seen points' median depth.
      std::vector<double> depths;
      for (const auto& x : seen) depths.push_back((x - *eye_).dot(along_));
      std::nth_element(depths.begin(), depths.begin() + static_cast<std::ptrdiff_t>(depths.size() / 2), depths.end());
      median_depth_ = depths[depths.size() / 2];
      if (!(median_depth_ > 0.0))
        throw InvalidInputError("fuseWithObserved: most seen points lie behind the scanner position; give where "
                                "the scanner stood");
      cell = tolerance_ / median_depth_;
    }
    seen_ = completion::detail::PlaneBins<double>(cell);
    for (const auto& x : seen) {
      const Sight s = sight(x);
      if (s.valid) seen_.insert(s.a, s.b, s.distance);
    }
  }

  bool wouldHaveSeen(const Eigen::Vector3d& q) const {
    if (seen_.empty()) return false;
    const Sight s = sight(q);
    if (!s.valid) return false;
    // The nearest seen point to the scanner among those within a cell of the line of sight.
    double nearest = std::numeric_limits<double>::infinity();
    const bool binned = seen_.forEachWithin(s.a, s.b, seen_.cellWidth(),
                                            [&](const auto& entry) { nearest = std::min(nearest, entry.value); });
    if (!binned) return false;  // too far out across the lines of sight: keep
    return s.distance < nearest - tolerance_;  // no seen point near the line: infinity
  }

 private:
  struct Sight {
    double a = 0.0, b = 0.0;  // across the line of sight
    double distance = 0.0;    // from the scanner along it
    bool valid = false;
  };

  Sight sight(const Eigen::Vector3d& q) const {
    Sight s;
    if (eye_) {
      const Eigen::Vector3d r = q - *eye_;
      const double depth = r.dot(along_);
      // Near the scanner's own plane (or behind it) the direction says nothing: keep.
      if (!(depth > 0.01 * median_depth_)) return s;
      s.a = r.dot(across_) / depth;
      s.b = r.dot(up_) / depth;
      s.distance = r.norm();
    } else {
      // Measured from a seen point, so that real points are well inside the grid's range.
      const Eigen::Vector3d r = q - origin_;
      s.a = r.dot(across_);
      s.b = r.dot(up_);
      s.distance = r.dot(along_);
    }
    s.valid = true;
    return s;
  }
  // A line of sight is at least this many of the seen points' median spacings wide.
  static constexpr double kSpacings = 2.0;

  double tolerance_;
  double median_depth_ = 1.0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero(), along_ = Eigen::Vector3d::UnitZ(),
                  across_ = Eigen::Vector3d::UnitX(), up_ = Eigen::Vector3d::UnitY();
  std::optional<Eigen::Vector3d> eye_;
  completion::detail::PlaneBins<double> seen_{0.0};  // distance from the scanner, by line of sight
};

constexpr int kMinFillSteps = 4;

// How far the primitive's plane passes from `at` when it is (nearly) `plane`: within max_angle of
// it and max_offset of `at`; infinity otherwise.
double offsetOnPlane(const PlanarPrimitive& primitive, const Plane& plane, const Eigen::Vector3d& at, double max_angle,
                     double max_offset) {
  if (primitive.plane.unorientedAngleTo(plane) > max_angle) return std::numeric_limits<double>::infinity();
  const double d = std::abs(primitive.plane.signedDistance(at));
  return d <= max_offset ? d : std::numeric_limits<double>::infinity();
}

// Adds grid points on the faces of the seen box where no fused point is near and the scan does
// not show the space empty (SeenFreeSpace; see ObservedFusionOptions::fill_spacing).
// `shown` are the seen faces whose points show free space (SeenFreeSpace).
void fillSeenBox(const SeenBox& seen, const std::vector<PlanarPrimitive>& shown,
                 const ObservedFusionOptions& options, std::vector<PlanarPrimitive>& fused,
                 const std::vector<bool>& seen_face, ObservedFusionReport& counts) {
  if (seen.box.isEmpty()) return;
  const double diagonal = seen.box.diagonal().norm();
  if (!(diagonal > 0.0)) return;
  const double step = options.fill_spacing * diagonal, radius = options.fill_empty_radius * diagonal;
  const double max_angle = degreesToRadians(options.max_angle_degrees);
  const double max_offset = options.max_distance * diagonal;
  const Eigen::Vector3d lo = seen.box.min(), hi = seen.box.max();
  // Grids of all six faces first, all tested against the fused points as they were.
  struct Face {
    Plane plane;
    std::vector<Eigen::Vector3d> points;
    double empty_radius;  // `radius`, capped for a narrow face (below)
  };
  std::vector<Face> faces;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // The points of the faces a box face meets at its edges lie within half its width of its
    // middle: on a face narrower than twice the radius (the rim of a plate or a floor slab, a few
    // percent of the diagonal thick) they would cover it all, and the fill would leave the rim
    // open. A quarter of its width keeps its middle half. A face narrower than the fusion's plane
    // tolerance is no rim: the two sides would be one plane, and a flat scan has no thickness.
    const double width = std::min(hi[u] - lo[u], hi[v] - lo[v]);
    const double narrow_radius = width > max_offset ? std::min(radius, 0.25 * width) : radius;
    // At least four steps across, so that a narrow face keeps rows in its middle half.
    const int nu = std::max(kMinFillSteps, static_cast<int>(std::ceil((hi[u] - lo[u]) / step)));
    const int nv = std::max(kMinFillSteps, static_cast<int>(std::ceil((hi[v] - lo[v]) / step)));
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3d local = Eigen::Vector3d::Zero();
      local[axis] = side ? hi[axis] : lo[axis];
      Face face;
      face.plane = Plane::fromPointAndNormal(seen.axes * local, (side ? 1.0 : -1.0) * seen.axes.col(axis));
      face.empty_radius = narrow_radius;
      for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
          local[u] = lo[u] + (hi[u] - lo[u]) * (i + 0.5) / nu;
          local[v] = lo[v] + (hi[v] - lo[v]) * (j + 0.5) / nv;
          face.points.push_back(seen.axes * local);
        }
      faces.push_back(std::move(face));
    }
  }
  std::vector<const pcl::PointCloud<pcl::PointNormal>*> clouds;
  for (const auto& primitive : fused) clouds.push_back(&primitive.points);
  std::vector<Eigen::Vector3d> all;
  for (const auto& face : faces) all.insert(all.end(), face.points.begin(), face.points.end());
  const std::vector<double> distances = nearestDistances(all, clouds);
  std::size_t next = 0;
  std::optional<SeenFreeSpace> free_space;  // built once some box point is uncovered
  for (const auto& face : faces) {
    std::vector<Eigen::Vector3d> empty;
    for (const auto& q : face.points) {
      if (distances[next++] <= face.empty_radius) continue;
      if (!free_space) free_space.emplace(shown, options.min_observed_points, seen.axes, radius);
      if (free_space->showsEmpty(q)) {
        ++counts.fill_in_seen_free_space;
        continue;
      }
      empty.push_back(q);
    }
    if (empty.empty()) continue;
    // The fused primitive nearest to the face's plane within the fusion tolerances hosts them;
    // without one, a new primitive at index fused.size().
    std::size_t host = fused.size();
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const auto& q : empty) centroid += q;
    centroid /= static_cast<double>(empty.size());
    for (std::size_t f = 0; f < fused.size(); ++f) {
      const double d = offsetOnPlane(fused[f], face.plane, centroid, max_angle, max_offset);
      if (d < best) {
        best = d;
        host = f;
      }
    }
    if (host == fused.size()) {
      fused.emplace_back();
      fused.back().plane = face.plane;
      // Below a seen face (1) but above the network's guesses: the seen extent implies it, and
      // PolyFit's candidate-face budget leaves out the least confident primitives first.
      fused.back().confidence = kImpliedFaceConfidence;
      ++counts.filled_faces;
    } else if (host < seen_face.size() && !seen_face[host]) {
      // The network's guess of this face, a few degrees off: the seen extent fixes the plane, and
      // like a new box face it must outrank the guesses, or the candidate-face budget may leave
      // the hull's face out while it keeps a worse guess.
      takePlane(fused[host], face.plane);
      fused[host].confidence = std::max(fused[host].confidence, kImpliedFaceConfidence);
      ++counts.box_faces_taken;
    }
    PlanarPrimitive& target = fused[host];
    pcl::PointCloud<pcl::PointNormal> added;
    for (const auto& q : empty) {
      pcl::PointNormal p;
      p.x = static_cast<float>(q.x());
      p.y = static_cast<float>(q.y());
      p.z = static_cast<float>(q.z());
      added.push_back(p);
    }
    projectOnto(target.plane, added);
    target.points += added;
    counts.filled_points += added.size();
  }
}

// A raster cell is this many of the seen points' median spacings wide: every cell along a seen
// wall then holds a point, so that the wall's outline has no holes for the flood to leak through.
constexpr double kProfileCellSpacings = 1.5;
// At most this many cells along a side of the raster (a scan with a few far points has a small
// median spacing but a large box).
constexpr int kMaxProfileCells = 1000;

// The box axis every fused plane is parallel to (within max_angle), when there is exactly one:
// the primitives are the sides of a prism along it, and none can close its ends. -1 otherwise
// (also when all planes are parallel to two axes: a flat scan has no thickness to close).
int profileAxis(const SeenBox& seen, const std::vector<PlanarPrimitive>& fused, double max_angle) {
  int found = -1;
  for (int k = 0; k < 3; ++k) {
    const bool all_parallel = std::all_of(fused.begin(), fused.end(), [&](const PlanarPrimitive& primitive) {
      return std::abs(primitive.plane.normal.normalized().dot(seen.axes.col(k))) <= std::sin(max_angle);
    });
    if (!all_parallel) continue;
    if (found >= 0) return -1;
    found = k;
  }
  return found;
}

// Closes the two ends of a prism (profileAxis): a sheet-metal profile whose end faces are a few
// point spacings wide, an extrusion or a building's walls scanned from the side. The box fill
// leaves those ends open: near a thin wall the wall's own points cover the box face. Every fused
// point is projected along the axis onto a raster; the cells the flood from the raster's border
// cannot reach through empty cells are the profile (its walls and what they enclose; a profile
// with an opening, such as an L or a U, lets the flood into the opening). Each end gets a point
// per profile cell, on the box face, as a new primitive.
void capProfileEnds(const SeenBox& seen, const std::vector<PlanarPrimitive>& observed, double max_angle,
                    double max_distance, std::vector<PlanarPrimitive>& fused, ObservedFusionReport& counts) {
  if (seen.box.isEmpty() || fused.empty()) return;
  const double max_offset = max_distance * seen.box.diagonal().norm();
  const int axis = profileAxis(seen, fused, max_angle);
  if (axis < 0) return;
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const Eigen::Vector3d lo = seen.box.min(), hi = seen.box.max();
  const double extent = std::max(hi[u] - lo[u], hi[v] - lo[v]);
  const double cell = std::max(kProfileCellSpacings * medianSpacing(observed), extent / kMaxProfileCells);
  if (!(cell > 0.0)) return;
  // One empty cell of margin all round, so that the flood starts outside the profile.
  const int nu = static_cast<int>(std::ceil((hi[u] - lo[u]) / cell)) + 3;
  const int nv = static_cast<int>(std::ceil((hi[v] - lo[v]) / cell)) + 3;
  const auto index = [&](int i, int j) { return static_cast<std::size_t>(i) * static_cast<std::size_t>(nv) + j; };
  std::vector<char> occupied(static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv), 0);
  for (const auto& primitive : fused)
    for (const auto& p : primitive.points) {
      const Eigen::Vector3d local = seen.axes.transpose() * position(p);
      const int i = static_cast<int>(std::floor((local[u] - lo[u]) / cell)) + 1;
      const int j = static_cast<int>(std::floor((local[v] - lo[v]) / cell)) + 1;
      if (i >= 0 && i < nu && j >= 0 && j < nv) occupied[index(i, j)] = 1;
    }
  // Walls grown by one cell, so that a gap of a cell between seen points does not let the flood in.
  std::vector<char> wall = occupied;
  for (int i = 1; i + 1 < nu; ++i)
    for (int j = 1; j + 1 < nv; ++j)
      if (occupied[index(i, j)])
        for (int di = -1; di <= 1; ++di)
          for (int dj = -1; dj <= 1; ++dj) wall[index(i + di, j + dj)] = 1;
  std::vector<char> outside(occupied.size(), 0);
  std::vector<std::pair<int, int>> stack;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j)
      if ((i == 0 || j == 0 || i == nu - 1 || j == nv - 1) && !wall[index(i, j)]) {
        outside[index(i, j)] = 1;
        stack.emplace_back(i, j);
      }
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    for (const auto& [di, dj] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      const int a = i + di, b = j + dj;
      if (a < 0 || b < 0 || a >= nu || b >= nv || wall[index(a, b)] || outside[index(a, b)]) continue;
      outside[index(a, b)] = 1;
      stack.emplace_back(a, b);
    }
  }
  // The profile: cells the flood did not reach, without the ring the walls grew by (a grown cell
  // next to a reached one).
  const auto nextToOutside = [&](int i, int j) {
    for (int di = -1; di <= 1; ++di)
      for (int dj = -1; dj <= 1; ++dj) {
        const int a = i + di, b = j + dj;
        if (a >= 0 && b >= 0 && a < nu && b < nv && outside[index(a, b)]) return true;
      }
    return false;
  };
  std::vector<char> in_profile(occupied.size(), 0);
  std::size_t profile_cells = 0;
  // Only cells over the box: the margin may hold walls grown into it, but no part of the profile.
  const auto overTheBox = [&](int k, int i) { return i >= 1 && (i - 1) * cell < hi[k] - lo[k]; };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j)
      if (overTheBox(u, i) && overTheBox(v, j) && !outside[index(i, j)] &&
          (occupied[index(i, j)] || !nextToOutside(i, j))) {
        in_profile[index(i, j)] = 1;
        ++profile_cells;
      }
  if (profile_cells == 0) return;
  // The middle of the part of cell i along axis k inside the box: never on the box's faces, where
  // PolyFit's candidate faces meet (a point on an edge between two of them is counted on one side
  // or the other by rounding, which changed meshes from run to run).
  const auto centre = [&](int k, int i) {
    return 0.5 * (std::max(lo[k], lo[k] + (i - 1) * cell) + std::min(hi[k], lo[k] + i * cell));
  };
  const auto addPrimitive = [&](const Plane& plane, const std::vector<Eigen::Vector3d>& locals) {
    PlanarPrimitive face;
    face.plane = plane;
    // As a box face: below a seen face, above the network's guesses.
    face.confidence = kImpliedFaceConfidence;
    for (const Eigen::Vector3d& local : locals) {
      pcl::PointNormal p;
      p.getVector3fMap() = (seen.axes * local).cast<float>();
      p.getNormalVector3fMap() = plane.normal.normalized().cast<float>();
      face.points.push_back(p);
    }
    counts.profile_cap_points += face.points.size();
    fused.push_back(std::move(face));
  };
  for (int side = 0; side < 2; ++side) {
    Eigen::Vector3d local;
    local[axis] = side ? hi[axis] : lo[axis];
    std::vector<Eigen::Vector3d> locals;
    for (int i = 0; i < nu; ++i)
      for (int j = 0; j < nv; ++j)
        if (in_profile[index(i, j)]) {
          local[u] = centre(u, i);
          local[v] = centre(v, j);
          locals.push_back(local);
        }
    addPrimitive(Plane::fromPointAndNormal(seen.axes * local, (side ? 1.0 : -1.0) * seen.axes.col(axis)), locals);
  }
  // Where the profile reaches a side of the box and no plane lies on that side, the box face
  // closes it there: the end of a leg too thin for the segmenter, cut off at the scan's extent.
  const int steps = std::max(1, static_cast<int>(std::ceil((hi[axis] - lo[axis]) / cell)));
  const std::size_t side_planes = fused.size() - 2;  // not the two caps
  for (int across : {u, v}) {
    const int along = across == u ? v : u;
    for (int side = 0; side < 2; ++side) {
      Eigen::Vector3d local = (lo + hi) / 2.0;
      local[across] = side ? hi[across] : lo[across];
      const Plane plane = Plane::fromPointAndNormal(seen.axes * local, (side ? 1.0 : -1.0) * seen.axes.col(across));
      const bool closed = std::any_of(fused.begin(), fused.begin() + static_cast<std::ptrdiff_t>(side_planes),
                                      [&](const PlanarPrimitive& primitive) {
                                        return std::isfinite(
                                            offsetOnPlane(primitive, plane, seen.axes * local, max_angle, max_offset));
                                      });
      if (closed) continue;
      std::vector<Eigen::Vector3d> locals;
      for (int i = 0; i < nu; ++i)
        for (int j = 0; j < nv; ++j) {
          const int cell_across = across == u ? i : j, cell_along = across == u ? j : i;
          if (!in_profile[index(i, j)] || std::abs(centre(across, cell_across) - local[across]) > cell) continue;
          for (int t = 0; t < steps; ++t) {
            local[along] = centre(along, cell_along);
            local[axis] = lo[axis] + (hi[axis] - lo[axis]) * (t + 0.5) / steps;
            locals.push_back(local);
          }
        }
      if (!locals.empty()) addPrimitive(plane, locals);
    }
  }
}

// Seen points farther than this (fraction of the diagonal) along a face's normal count as a
// surface in front of or behind it: beyond the scatter of the face's own seen points about its
// plane (the segmenter's inlier distance is 0.004 by default), so they never do.
constexpr double kContradictionGap = 0.01;

// The checks for solid in front of and air behind a seen face's point (dropContradicted), chosen
// on the tuning parts: the spot's distance in front (behind) and the reach, in contradiction
// radii; how square a surface must be to the line to count (the sight lines along the box axes are
// built with it); how close to the face's plane a box axis must lie.
constexpr double kFrontOffset = 1.5;
constexpr double kFrontReach = 6.0;
constexpr double kSquareFacing = 0.906;  // cos 25 degrees
constexpr double kInPlaneAxisDegrees = 10.0;

// Drops the network's points of a seen face that the scan contradicts (ObservedFusionOptions::
// contradiction_radius); returns how many went. `own` are the face's seen points, `outward` its
// normal as the scan saw it, `to_scan` each predicted point's distance to the nearest observed
// point, `observed` the segments, `along_axes` what they show along the seen box's axes (one
// direction per axis, surfaces within kSquareFacing; none without axes).
std::size_t dropContradicted(pcl::PointCloud<pcl::PointNormal>& predicted, const Plane& plane,
                             const Eigen::Vector3d& outward, const pcl::PointCloud<pcl::PointNormal>& own,
                             const double* to_scan, const std::vector<PlanarPrimitive>& observed,
                             std::size_t min_points, double radius, double gap, const SightLines& along_axes) {
  if (predicted.empty() || !(radius > 0.0)) return 0;
  std::vector<Eigen::Vector3d> queries;
  queries.reserve(predicted.size());
  for (const auto& p : predicted) queries.push_back(position(p));
  const std::vector<double> to_own = nearestDistances(queries, {&own});

  // Looking along the normal both ways, the first seen surface on each side faces away: the
  // point is behind both, in the solid.
  const Eigen::Vector3d n = plane.normal.normalized();
  const Eigen::Vector3d u = n.unitOrthogonal();
  Eigen::Matrix3d frame;
  frame << n, u, n.cross(u);
  const SightLines lines(observed, min_points, {frame}, radius);
  const auto inside = [&](const Eigen::Vector3d& q) {
    const SightLines::FirstMet first = lines.firstMet(q, 0, gap);
    return first.ahead && first.ahead->faces_along && first.behind && !first.behind->faces_along;
  };

  // Just in front of the point, where a face has air, looking along each box axis that lies in
  // the face's plane: a seen surface met first within the reach that faces away (its normal
  // points along the line of sight) puts that spot inside the part. The network carries a
  // pocket's wall on past the pocket's ceiling, through the solid into the hidden side, and the
  // assemblers carved the part out along it (doc/results.md, forty-third session). The spot lies
  // farther in front than the radius, so that lines along the face pass clear of the faces it
  // meets at its own edges; only surfaces within 25 degrees of square to the line count, and only
  // within the reach: farther off, the line may have crossed an unseen surface first.
  // Just behind the point, where the face has solid, the same with a surface that faces back at
  // the spot puts it in air: the network carries a top on over a seen slot's opening, or a side
  // over a seen step, and the assemblers closed them over (forty-fifth session).
  std::vector<std::size_t> in_plane;  // the box axes that lie in the face's plane
  for (std::size_t k = 0; k < along_axes.size(); ++k)
    if (std::abs(n.dot(along_axes.along(k))) < std::sin(degreesToRadians(kInPlaneAxisDegrees))) in_plane.push_back(k);
  const Eigen::Vector3d in_front = kFrontOffset * radius * (n.dot(outward) < 0.0 ? -n : n);
  const double reach = kFrontReach * radius;
  // Whether a surface met first within the reach, along an in-plane axis, faces back at `spot`
  // (air around it) or away from it (solid around it).
  const auto first_met_faces = [&](const Eigen::Vector3d& spot, bool back) {
    for (std::size_t k : in_plane) {
      const SightLines::FirstMet first = along_axes.firstMet(spot, k);
      const double t = along_axes.along(k).dot(spot);
      if (first.ahead && first.ahead->faces_along != back && first.ahead->t - t < reach) return true;
      if (first.behind && first.behind->faces_along == back && t - first.behind->t < reach) return true;
    }
    return false;
  };
  return keepWhere(predicted, [&](std::size_t i) {
    // The scan saw this spot, and not this face there.
    const bool seen_without_the_face = to_scan[i] < radius && to_own[i] >= radius;
    return !seen_without_the_face && !inside(queries[i]) && !first_met_faces(queries[i] + in_front, false) &&
           !first_met_faces(queries[i] - in_front, true);
  });
}

}  // namespace

std::string describe(const ObservedFusionReport& report) {
  return std::to_string(report.snapped) + " primitives took a seen plane, " + std::to_string(report.absorbed) +
         " duplicates absorbed, " + std::to_string(report.added) + " seen faces added" +
         (report.joined ? ", " + std::to_string(report.joined) + " seen segments joined a larger seen face" : "") +
         (report.squared ? ", " + std::to_string(report.squared) +
                               " seen faces squared to the box's axes (off them by less than their fit's error)" : "") +
         (report.aligned ? ", " + std::to_string(report.aligned) + " unseen aligned with seen directions" : "") +
         (report.clipped_points ? ", " + std::to_string(report.clipped_points) + " points outside the seen box dropped (" +
                                      std::to_string(report.clipped) + " unseen primitives with them)"
                                : "") +
         (report.tilted_points ? ", " + std::to_string(report.tilted_points) +
                                     " points of tilted seen faces past the seen box dropped"
                               : "") +
         (report.filled_points ? ", " + std::to_string(report.filled_points) + " points filled on the seen box (" +
                                     std::to_string(report.filled_faces) + " new box faces" +
                                     (report.box_faces_taken ? ", " + std::to_string(report.box_faces_taken) +
                                                                   " unseen primitives turned onto a box face"
                                                             : "") +
                                     (report.box_on_one_plane
                                          ? "; no two seen planes are perpendicular, so the box lies on the largest one"
                                      : report.box_on_mirror_pair
                                          ? "; no two seen planes are perpendicular, so the box lies on the bisectors "
                                            "of mirror-image planes"
                                          : "") +
                                     ")"
                               : "") +
         (report.fill_in_seen_free_space ? ", " + std::to_string(report.fill_in_seen_free_space) +
                                               " box points left out in space the seen faces show empty"
                                         : "") +
         (report.profile_cap_points ? ", " + std::to_string(report.profile_cap_points) +
                                          " points close the two ends of a profile (every plane is parallel to one axis)"
                                    : "") +
         (report.thinned_points
              ? ", " + std::to_string(report.thinned_points) + " points of unseen primitives thinned out"
              : "") +
         (report.contradicted_points ? ", " + std::to_string(report.contradicted_points) +
                                           " points of seen faces dropped where the scan contradicts them"
                                     : "") +
         (report.seen_empty_points ? ", " + std::to_string(report.seen_empty_points) +
                                         " completed points dropped where the scanner would have seen them (" +
                                         std::to_string(report.seen_empty) + " unseen primitives with them)"
                                   : "");
}

std::vector<PlanarPrimitive> fuseWithObserved(std::vector<PlanarPrimitive> completed,
                                              const std::vector<PlanarPrimitive>& observed,
                                              const ObservedFusionOptions& options, ObservedFusionReport* report) {
  if (!std::isfinite(options.max_angle_degrees) || options.max_angle_degrees < 0.0 ||
      !std::isfinite(options.max_distance) || options.max_distance < 0.0 ||
      !std::isfinite(options.join_distance) || options.join_distance < 0.0 ||
      !std::isfinite(options.align_unseen_degrees) || options.align_unseen_degrees < 0.0 ||
      std::isnan(options.clip_margin) || options.clip_margin < 0.0 || std::isnan(options.tilt_margin) ||
      options.tilt_margin < 0.0 || !std::isfinite(options.fill_spacing) ||
      options.fill_spacing < 0.0 || !std::isfinite(options.fill_empty_radius) || options.fill_empty_radius < 0.0 ||
      !std::isfinite(options.contradiction_radius) || options.contradiction_radius < 0.0 ||
      !(options.unseen_point_fraction > 0.0 && options.unseen_point_fraction <= 1.0))
    throw InvalidInputError(
        "fuseWithObserved: max_angle_degrees, max_distance, join_distance, align_unseen_degrees, fill_spacing, "
        "fill_empty_radius and contradiction_radius must be finite and >= 0, clip_margin and tilt_margin >= 0 "
        "(infinity = off), "
        "unseen_point_fraction in (0, 1]");
  // Six faces of (1/spacing)^2 grid points each: below 0.001 that is millions of points.
  if (options.fill_spacing > 0.0 && options.fill_spacing < kMinFillSpacing)
    throw InvalidInputError("fuseWithObserved: fill_spacing must be 0 (off) or at least " +
                            std::to_string(kMinFillSpacing) + " of the diagonal, got " +
                            std::to_string(options.fill_spacing));
  if (!options.scanner_direction.allFinite() || (options.scanner_position && !options.scanner_position->allFinite()))
    throw InvalidInputError("fuseWithObserved: the scanner direction and position must be finite");
  if (options.scanner_position && options.scanner_direction.squaredNorm() > 0.0)
    throw InvalidInputError("fuseWithObserved: give the scanner's direction or its position, not both");
  if (!(options.scanner_cell > 0.0 && std::isfinite(options.scanner_cell)))
    throw InvalidInputError("fuseWithObserved: scanner_cell must be a positive fraction of the diagonal, got " +
                            std::to_string(options.scanner_cell));
  for (std::size_t i = 0; i < options.known_extent_points.size(); ++i)
    if (!options.known_extent_points[i].allFinite())
      throw InvalidInputError("fuseWithObserved: known extent point " + std::to_string(i) + " is not finite");
  ObservedFusionReport counts;
  const double max_angle = degreesToRadians(options.max_angle_degrees);
  // The observed points' diagonal: every tolerance below is a fraction of it.
  const double diagonal = diagonalOf(observed);
  const double max_distance = options.max_distance * diagonal;
  const double join_distance = options.join_distance * diagonal;

  std::vector<std::size_t> order(observed.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return observed[a].points.size() > observed[b].points.size(); });

  std::vector<bool> snapped(completed.size(), false), absorbed(completed.size(), false);
  // The network's points of each seen face, kept apart from its seen points until they are checked.
  std::vector<pcl::PointCloud<pcl::PointNormal>> predicted_points(completed.size());
  // The plane of the seen face each snapped primitive took, oriented as the scan saw it.
  std::vector<Plane> seen_plane(completed.size());
  std::vector<PlanarPrimitive> unmatched;
  std::vector<std::size_t> matches;
  for (std::size_t o : order) {
    const PlanarPrimitive& seen = observed[o];
    if (seen.points.size() < options.min_observed_points) {
      ++counts.ignored;
      continue;
    }
    matches.clear();
    std::size_t best = completed.size();
    double best_distance = std::numeric_limits<double>::infinity();
    for (std::size_t c = 0; c < completed.size(); ++c) {
      if (absorbed[c] || completed[c].plane.unorientedAngleTo(seen.plane) > max_angle) continue;
      const double d = meanDistance(seen.points, completed[c].plane);
      // A snapped primitive's plane is a seen face's: another segment joins it only within join_distance.
      if (d > max_distance || (snapped[c] && d > join_distance)) continue;
      matches.push_back(c);
      if (d < best_distance) {
        best = c;
        best_distance = d;
      }
    }
    if (best == completed.size()) {
      unmatched.push_back(seen);
      unmatched.back().confidence = 1.0f;
      ++counts.added;
      continue;
    }
    PlanarPrimitive& target = completed[best];
    if (!snapped[best]) {
      takePlane(target, seen.plane);
      seen_plane[best] = seen.plane;
      predicted_points[best] = std::move(target.points);
      target.points.clear();
      // A seen face is certain, whatever the network's score: confidence 1, like the unmatched
      // observed segments (the assembler's candidate-face budget never drops those).
      target.confidence = 1.0f;
      snapped[best] = true;
      ++counts.snapped;
    } else {
      ++counts.joined;
    }
    target.points += seen.points;
    // Other predictions of the same seen face are duplicates: their points (which may reach into
    // the unseen part of the face) join the chosen one.
    for (std::size_t c : matches) {
      if (c == best || snapped[c]) continue;
      projectOnto(target.plane, completed[c].points);
      predicted_points[best] += completed[c].points;
      absorbed[c] = true;
      ++counts.absorbed;
    }
  }
  const SeenNormals seen_normals = seenNormals(observed, options.min_observed_points, options.scanner_direction);
  if (seen_normals.axes) {
    const std::vector<Eigen::Vector3d> axes = {seen_normals.axes->col(0), seen_normals.axes->col(1),
                                               seen_normals.axes->col(2)};
    for (std::size_t c = 0; c < completed.size(); ++c)
      if (snapped[c] && squareNoisySeenFace(completed[c], axes, max_angle)) {
        const Plane& turned = completed[c].plane;
        seen_plane[c] = seen_plane[c].normal.dot(turned.normal) < 0.0 ? turned.flipped() : turned;
        projectOnto(turned, predicted_points[c]);
        ++counts.squared;
      }
    for (auto& face : unmatched)
      if (squareNoisySeenFace(face, axes, max_angle)) ++counts.squared;
  }
  if (options.contradiction_radius > 0.0) {
    // One search of the whole scan for the network's points of every seen face (one kd-tree).
    std::vector<const pcl::PointCloud<pcl::PointNormal>*> scan;
    for (const auto& segment : observed) scan.push_back(&segment.points);
    std::vector<Eigen::Vector3d> queries;
    for (std::size_t c = 0; c < completed.size(); ++c)
      if (snapped[c])
        for (const auto& p : predicted_points[c]) queries.push_back(position(p));
    const std::vector<double> to_scan = nearestDistances(queries, scan);
    const SightLines along_axes(observed, options.min_observed_points,
                                seen_normals.axes ? boxAxisFrames(*seen_normals.axes) : std::vector<Eigen::Matrix3d>{},
                                options.contradiction_radius * diagonal, kSquareFacing);
    std::size_t first = 0;
    for (std::size_t c = 0; c < completed.size(); ++c) {
      if (!snapped[c]) continue;
      const std::size_t count = predicted_points[c].size();
      counts.contradicted_points +=
          dropContradicted(predicted_points[c], completed[c].plane, seen_plane[c].normal, completed[c].points,
                           to_scan.data() + first,
                           observed, options.min_observed_points, options.contradiction_radius * diagonal,
                           kContradictionGap * diagonal, along_axes);
      first += count;
    }
  }
  // What the seen faces show for the box fill's free space: the scan's segments, and the
  // network's points of each seen face that the scan did not contradict, facing as the scan saw
  // that face. The clip and the scanner's view below drop the same points from both. Only the
  // fill reads it, so without the fill it stays empty (no copy of the scan).
  const bool fill = options.fill_spacing > 0.0 && !observed.empty();
  constexpr std::size_t kNotShown = std::numeric_limits<std::size_t>::max();
  std::vector<PlanarPrimitive> shown;
  if (fill) shown = observed;
  std::vector<std::size_t> shown_of(completed.size(), kNotShown);
  for (std::size_t c = 0; c < completed.size(); ++c) {
    if (!snapped[c]) continue;
    completed[c].points += predicted_points[c];
    if (!fill) continue;
    PlanarPrimitive network_part;
    network_part.plane = seen_plane[c];
    network_part.points = std::move(predicted_points[c]);
    network_part.confidence = 1.0f;
    shown_of[c] = shown.size();
    shown.push_back(std::move(network_part));
  }
  if (options.align_unseen_degrees > 0.0) {
    const auto directions = seenDirections(seen_normals);
    const double max_align = degreesToRadians(options.align_unseen_degrees);
    for (std::size_t c = 0; c < completed.size(); ++c)
      if (!snapped[c] && !absorbed[c] && alignWithNearest(completed[c], directions, max_align)) ++counts.aligned;
  }
  SeenBox seen_box = seenBox(observed, seen_normals);
  putBoxSidesOnSeenFaces(seen_box, observed, options.min_observed_points, max_angle);
  counts.box_on_one_plane = seen_normals.axes_on_one_plane;
  counts.box_on_mirror_pair = seen_normals.axes_on_mirror_pair;
  if (options.scanner_direction.squaredNorm() > 0.0 && !seen_normals.normals.empty()) {
    const Eigen::Vector3d sight = options.scanner_direction.normalized();
    counts.no_seen_plane_along_sight =
        std::none_of(seen_normals.normals.begin(), seen_normals.normals.end(),
                     [&](const Eigen::Vector3d& n) { return std::abs(n.dot(sight)) < std::sin(max_angle); });
  }
  counts.box_axes = seen_box.axes;
  if (!seen_box.box.isEmpty())
    for (const Eigen::Vector3d& p : options.known_extent_points) seen_box.box.extend(seen_box.axes.transpose() * p);
  if (std::isfinite(options.tilt_margin) && !observed.empty() &&
      (seen_normals.axes_on_mirror_pair || seen_normals.axes_on_one_plane)) {
    // No two seen planes are perpendicular: no seen wall bounds a tilted face (a roof's slope), and
    // the box's walls stand in front of the slopes, where the fill leaves them out as seen empty.
    // Such a face ends at the seen box along the axes it tilts towards: past it, the network's
    // points ran down below the eaves (tens of metres sideways on an airborne roof), and the cell
    // complex closed a solid there. Along an axis it lies parallel to it may run on, like any seen
    // face. With two perpendicular seen planes it is left alone: on MFCAD's chamfers the cell
    // complex lost more than PolyFit gained, and PolyFit's mesh of AHN3_16627 split in two.
    const double sin_tilt = std::sin(max_angle), cos_tilt = std::cos(max_angle);
    const double margin = options.tilt_margin * diagonal;
    for (std::size_t c = 0; c < completed.size(); ++c) {
      if (!snapped[c] || absorbed[c]) continue;
      const Eigen::Vector3d along_axes = (seen_box.axes.transpose() * completed[c].plane.normal).cwiseAbs();
      if (along_axes.maxCoeff() >= cos_tilt) continue;  // on an axis: it does not run down past the box
      SeenBox bounds = seen_box;
      for (int k = 0; k < 3; ++k) {
        if (along_axes[k] > sin_tilt) {
          bounds.box.min()[k] -= margin;
          bounds.box.max()[k] += margin;
        } else {
          bounds.box.min()[k] = -std::numeric_limits<double>::infinity();
          bounds.box.max()[k] = std::numeric_limits<double>::infinity();
        }
      }
      counts.tilted_points += keepInside(bounds, completed[c].points);
      if (shown_of[c] != kNotShown) keepInside(bounds, shown[shown_of[c]].points);
    }
  }
  std::vector<bool> clipped(completed.size(), false);
  if (std::isfinite(options.clip_margin) && !observed.empty()) {
    // Observed points lie inside by construction: only predicted ones go.
    const SeenBox box = grown(seen_box, options.clip_margin);
    for (std::size_t c = 0; c < completed.size(); ++c) {
      if (absorbed[c]) continue;
      const std::size_t before = completed[c].points.size();
      const std::size_t gone = keepInside(box, completed[c].points);
      if (shown_of[c] != kNotShown) keepInside(box, shown[shown_of[c]].points);
      counts.clipped_points += gone;
      if (!snapped[c] && 2 * gone > before) {
        clipped[c] = true;
        ++counts.clipped;
      }
    }
  }
  if ((options.scanner_position || options.scanner_direction.squaredNorm() > 0.0) && !observed.empty()) {
    const ScannerView scanner(observed, options, diagonal);
    // Seen points stay by construction (each is in its own bin, and no nearer than itself).
    for (std::size_t c = 0; c < completed.size(); ++c) {
      if (absorbed[c] || clipped[c]) continue;
      auto& points = completed[c].points;
      const std::size_t before = points.size();
      const std::size_t gone =
          keepWhere(points, [&](std::size_t i) { return !scanner.wouldHaveSeen(position(points[i])); });
      if (shown_of[c] != kNotShown) {
        auto& network_part = shown[shown_of[c]].points;
        keepWhere(network_part, [&](std::size_t i) { return !scanner.wouldHaveSeen(position(network_part[i])); });
      }
      counts.seen_empty_points += gone;
      if (!snapped[c] && 2 * gone > before) {
        clipped[c] = true;
        ++counts.seen_empty;
      }
    }
  }
  std::vector<PlanarPrimitive> fused;
  std::vector<bool> seen_face;
  fused.reserve(completed.size() + unmatched.size());
  for (std::size_t c = 0; c < completed.size(); ++c) {
    if (absorbed[c] || clipped[c]) continue;
    if (!snapped[c])
      counts.thinned_points += thinOut(completed[c].points, options.unseen_point_fraction, options.unseen_min_points);
    fused.push_back(std::move(completed[c]));
    seen_face.push_back(snapped[c]);
  }
  for (auto& primitive : unmatched) {
    fused.push_back(std::move(primitive));
    seen_face.push_back(true);
  }
  if (fill) {
    fillSeenBox(seen_box, shown, options, fused, seen_face, counts);
    capProfileEnds(seen_box, observed, max_angle, options.max_distance, fused, counts);
  }
  if (report) *report = counts;
  return fused;
}

}  // namespace paco
