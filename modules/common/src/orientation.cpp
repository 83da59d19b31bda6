#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/orientation.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <string>

namespace paco {

namespace {

// The frame with `first` exactly as its first axis and `second` made perpendicular to it.
Eigen::Matrix3d frameOf(const Eigen::Vector3d& first, const Eigen::Vector3d& second) {
  Eigen::Matrix3d axes;
  axes.col(0) = first;
  axes.col(1) = (second - second.dot(first) * first).normalized();
  axes.col(2) = axes.col(0).cross(axes.col(1));
  return axes;
}

constexpr std::size_t kFrameCandidates = 64;

// The planes that count (a finite, non-zero normal and a positive weight), heaviest first; stable,
// so that equal weights keep the given order and the result is reproducible.
std::vector<std::size_t> heaviestFirst(const std::vector<Eigen::Vector3d>& normals,
                                       const std::vector<double>& weights) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < normals.size(); ++i)
    if (normals[i].allFinite() && normals[i].norm() > 0.0 && weights[i] > 0.0) order.push_back(i);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return weights[a] > weights[b]; });
  return order;
}

// True when some pair of the planes `order` lists satisfies `test(|cos|)` of their normals' angle.
template <typename Test>
bool anyPair(const std::vector<Eigen::Vector3d>& normals, const std::vector<std::size_t>& order, Test test) {
  for (std::size_t a = 0; a < order.size(); ++a)
    for (std::size_t b = a + 1; b < order.size(); ++b)
      if (test(std::abs(normals[order[a]].normalized().dot(normals[order[b]].normalized())))) return true;
  return false;
}

// How close two unit directions are, given |cos| of their angle: 1 when parallel (either way),
// falling linearly with the angle to 0 at `radians`. A zero tolerance takes only exact matches, in
// full. Callers skip pairs beyond the tolerance.
double closeness(double cosine, double radians) {
  return radians > 0.0 ? 1.0 - std::acos(std::min(1.0, cosine)) / radians : 1.0;
}

// The largest plane's normal with the coordinate axis least aligned with it, made perpendicular:
// dominantPlaneAxes' frame when no two planes are perpendicular.
Eigen::Matrix3d largestPlaneFrame(const Eigen::Vector3d& largest) {
  Eigen::Index least = 0;
  largest.cwiseAbs().minCoeff(&least);
  return frameOf(largest, Eigen::Vector3d::Unit(least));
}

void checkSameLength(const char* function, const std::vector<Eigen::Vector3d>& normals,
                     const std::vector<double>& weights) {
  if (normals.size() != weights.size())
    throw InvalidInputError(std::string(function) + ": " + std::to_string(normals.size()) + " normals but " +
                            std::to_string(weights.size()) + " weights");
}

}  // namespace

bool hasPlanesAtAnAngle(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights,
                        double tolerance_degrees) {
  checkSameLength("hasPlanesAtAnAngle", normals, weights);
  const double min_cosine = std::cos(degreesToRadians(tolerance_degrees));
  return anyPair(normals, heaviestFirst(normals, weights), [&](double cosine) { return cosine < min_cosine; });
}

bool hasPerpendicularPlanes(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights,
                            double tolerance_degrees) {
  checkSameLength("hasPerpendicularPlanes", normals, weights);
  std::vector<std::size_t> order = heaviestFirst(normals, weights);
  if (order.size() > kFrameCandidates) order.resize(kFrameCandidates);
  const double max_cosine = std::sin(degreesToRadians(tolerance_degrees));
  return anyPair(normals, order, [&](double cosine) { return cosine <= max_cosine; });
}

std::optional<Eigen::Matrix3d> dominantPlaneAxes(const std::vector<Eigen::Vector3d>& normals,
                                                 const std::vector<double>& weights, double tolerance_degrees) {
  checkSameLength("dominantPlaneAxes", normals, weights);
  const std::vector<std::size_t> order = heaviestFirst(normals, weights);
  if (order.empty()) return std::nullopt;
  std::vector<Eigen::Vector3d> unit;
  for (std::size_t i : order) unit.push_back(normals[i].normalized());
  const double radians = degreesToRadians(tolerance_degrees);
  const double max_cosine = std::sin(radians), min_cosine = std::cos(radians);
  // A plane supports a frame by the square root of its weight times its closeness to the nearest
  // axis (1 on it, falling linearly to 0 at the tolerance).
  // - The square root: a frame needs several faces, so one large chamfer does not outvote the
  //   many smaller faces on the part's own axes. With plain weights, MFCAD part 0-13-13-14-14-23
  //   at 75 % missing took the frame of its chamfer (626 points) and the faces perpendicular to it
  //   (708 points in 3 faces) over the part's axes (1,227 points in 8 faces), and the box fill
  //   then closed a box turned by 33 degrees. Counting planes alone lets many small segments
  //   outvote the large faces.
  // - The closeness: a frame turned a few degrees onto one slanted face keeps every plane of the
  //   part's axes within the tolerance. Counted in full, they made it as good as the part's own
  //   frame (MFCAD part 1-4-7-11-13-23, 7.4 degrees off), and the box fill added tilted faces.
  const auto support = [&](const Eigen::Matrix3d& axes) {
    double total = 0.0;
    for (std::size_t k = 0; k < unit.size(); ++k) {
      const double cosine = (axes.transpose() * unit[k]).cwiseAbs().maxCoeff();
      if (cosine >= min_cosine) total += std::sqrt(weights[order[k]]) * closeness(cosine, radians);
    }
    return total;
  };
  // Every pair of perpendicular planes spans a frame, the heavier plane's normal exactly on its
  // axis; the frame that carries the most weight wins, the heavier pairs on ties. Taking the
  // largest plane's frame instead fails on chamfered parts, where a chamfer can be the largest
  // seen face although most of the part lies on the axes the chamfer cuts.
  // Frames from the 64 largest planes only: the search grows with the cube of their number, and a
  // real scan can have hundreds of small segments.
  const std::size_t candidates = std::min(unit.size(), kFrameCandidates);
  std::optional<Eigen::Matrix3d> best;
  double best_support = -1.0;
  for (std::size_t a = 0; a < candidates; ++a)
    for (std::size_t b = a + 1; b < candidates; ++b) {
      if (std::abs(unit[b].dot(unit[a])) > max_cosine) continue;
      const Eigen::Matrix3d axes = frameOf(unit[a], unit[b]);
      const double s = support(axes);
      if (s > best_support) {
        best_support = s;
        best = axes;
      }
    }
  // The largest plane with the coordinate axis least aligned with it competes too: the only
  // frame when no two planes are perpendicular, and the better one when the largest plane
  // outweighs every perpendicular pair that leaves it off their axes.
  const Eigen::Matrix3d largest = largestPlaneFrame(unit[0]);
  if (!best || support(largest) > best_support) best = largest;
  return best;
}

std::optional<Eigen::Matrix3d> mirrorPlaneAxes(const std::vector<Eigen::Vector3d>& normals,
                                               const std::vector<double>& weights, double tolerance_degrees) {
  checkSameLength("mirrorPlaneAxes", normals, weights);
  if (hasPerpendicularPlanes(normals, weights, tolerance_degrees)) return std::nullopt;
  std::vector<std::size_t> order = heaviestFirst(normals, weights);
  // The 64 heaviest only, as dominantPlaneAxes: each frame's support compares every plane with
  // every other, for every pair's frame.
  if (order.size() > kFrameCandidates) order.resize(kFrameCandidates);
  if (order.size() < 2) return std::nullopt;  // no pair
  const Eigen::Index n = static_cast<Eigen::Index>(order.size());
  Eigen::Matrix3Xd unit(3, n);
  Eigen::VectorXd weight(n);
  for (Eigen::Index k = 0; k < n; ++k) {
    unit.col(k) = normals[order[static_cast<std::size_t>(k)]].normalized();
    weight(k) = weights[order[static_cast<std::size_t>(k)]];
  }
  const double radians = degreesToRadians(tolerance_degrees);
  const double max_cosine = std::sin(radians), min_cosine = std::cos(radians);
  // A plane's support: near an axis, as in dominantPlaneAxes; or mirrored across one of the
  // frame's planes onto another plane, by the smaller weight: a face and a small chamfer are
  // mirror images across their bisector, but the frame belongs to the face.
  const auto support = [&](const Eigen::Matrix3d& axes) {
    const Eigen::Matrix3Xd local = axes.transpose() * unit;
    double total = 0.0;
    for (Eigen::Index k = 0; k < n; ++k) {
      double best = 0.0;
      const double on_axis = local.col(k).cwiseAbs().maxCoeff();
      if (on_axis >= min_cosine) best = std::sqrt(weight(k)) * closeness(on_axis, radians);
      for (int mirror = 0; mirror < 3; ++mirror) {
        // Nearly in that mirror plane already: its image is itself.
        if (std::abs(local(mirror, k)) < max_cosine) continue;
        Eigen::Vector3d image = local.col(k);
        image(mirror) = -image(mirror);
        for (Eigen::Index l = 0; l < n; ++l) {
          const double cosine = std::abs(image.dot(local.col(l)));
          if (l == k || cosine < min_cosine) continue;
          best = std::max(best, std::sqrt(std::min(weight(k), weight(l))) * closeness(cosine, radians));
        }
      }
      total += best;
    }
    return total;
  };
  std::optional<Eigen::Matrix3d> best;
  double best_support = support(largestPlaneFrame(unit.col(0)));
  for (Eigen::Index a = 0; a < n; ++a)
    for (Eigen::Index b = a + 1; b < n; ++b) {
      if (std::abs(unit.col(a).dot(unit.col(b))) >= min_cosine) continue;  // parallel: no bisector
      // Sum and difference of two unit vectors are perpendicular; a flipped normal swaps them.
      const Eigen::Matrix3d axes =
          frameOf((unit.col(a) + unit.col(b)).normalized(), unit.col(a) - unit.col(b));
      const double s = support(axes);
      if (s > best_support) {
        best_support = s;
        best = axes;
      }
    }
  return best;
}

Eigen::Matrix3d dominantPlaneAxesAround(const Eigen::Vector3d& axis, const std::vector<Eigen::Vector3d>& normals,
                                        const std::vector<double>& weights, double tolerance_degrees) {
  checkSameLength("dominantPlaneAxesAround", normals, weights);
  if (!axis.allFinite() || axis.norm() == 0.0)
    throw InvalidInputError("dominantPlaneAxesAround: the axis must be finite and not zero");
  const Eigen::Vector3d first = axis.normalized();
  // `first` outweighs every plane, so each frame dominantPlaneAxes weighs has it as an axis: its
  // pairs with a projection put it first, two perpendicular projections have it as their cross
  // product, and the fallback frame starts from the largest plane.
  std::vector<Eigen::Vector3d> directions = {first};
  std::vector<double> direction_weights = {1.0};
  const double min_length = std::sin(degreesToRadians(2.0));
  for (std::size_t i = 0; i < normals.size(); ++i) {
    if (!normals[i].allFinite() || normals[i].norm() == 0.0 || !(weights[i] > 0.0)) continue;
    const Eigen::Vector3d unit = normals[i].normalized();
    const Eigen::Vector3d across = unit - unit.dot(first) * first;
    if (across.norm() < min_length) continue;
    directions.push_back(across.normalized());
    direction_weights.push_back(weights[i] * across.norm());
    direction_weights[0] += weights[i];
  }
  const Eigen::Matrix3d axes = *dominantPlaneAxes(directions, direction_weights, tolerance_degrees);
  // Put `first` in the first column, exactly and with its sign, keeping a proper rotation.
  Eigen::Index column = 0;
  (axes.transpose() * first).cwiseAbs().maxCoeff(&column);
  return frameOf(first, axes.col((column + 1) % 3));
}

Eigen::Matrix3d rotationOntoAxesClosestToIdentity(const Eigen::Matrix3d& axes) {
  // R = P Aᵀ maps column j of A onto column j of the signed permutation P; det R = det P.
  std::array<int, 3> permutation = {0, 1, 2};
  Eigen::Matrix3d best = Eigen::Matrix3d::Identity();
  double best_trace = -std::numeric_limits<double>::infinity();
  do {
    for (int signs = 0; signs < 8; ++signs) {
      Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
      for (int j = 0; j < 3; ++j) P(permutation[j], j) = (signs >> j) & 1 ? -1.0 : 1.0;
      if (P.determinant() * axes.determinant() < 0.0) continue;
      const Eigen::Matrix3d R = P * axes.transpose();
      if (R.trace() > best_trace + 1e-12) {
        best_trace = R.trace();
        best = R;
      }
    }
  } while (std::next_permutation(permutation.begin(), permutation.end()));
  return best;
}

ClosingBoxAxes closingBoxAxes(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights,
                              const Eigen::Vector3d& scanner_direction) {
  checkSameLength("closingBoxAxes", normals, weights);
  if (!scanner_direction.allFinite())
    throw InvalidInputError("closingBoxAxes: the scanner's direction must be finite (zero when unknown)");
  ClosingBoxAxes result;
  if (scanner_direction.squaredNorm() > 0.0) {
    result.axes = dominantPlaneAxesAround(scanner_direction, normals, weights);
    return result;
  }
  result.axes = dominantPlaneAxes(normals, weights);
  // Parallel planes only (a plate seen on both sides, a flat roof) leave no doubt about the box's
  // first axis; planes at an angle without a perpendicular pair do (a gable roof).
  if (result.axes && !hasPerpendicularPlanes(normals, weights) && hasPlanesAtAnAngle(normals, weights)) {
    if (const auto mirrored = mirrorPlaneAxes(normals, weights)) {
      result.axes = mirrored;
      result.on_mirror_pair = true;
    } else {
      result.on_one_plane = true;
    }
  }
  return result;
}

Eigen::Matrix3d seenPlanesRotation(const std::vector<Eigen::Vector3d>& normals, const std::vector<double>& weights) {
  const auto axes = dominantPlaneAxes(normals, weights);
  return axes ? rotationOntoAxesClosestToIdentity(*axes) : Eigen::Matrix3d::Identity();
}

Eigen::Matrix3d seenPlanesRotation(const PlanarSegmentation& segmentation) {
  const std::vector<std::size_t> counts = segmentation.pointsPerSegment();
  const std::vector<double> sizes(counts.begin(), counts.end());
  std::vector<Eigen::Vector3d> normals;
  for (const auto& plane : segmentation.planes) normals.push_back(plane.normal);
  return seenPlanesRotation(normals, sizes);
}

}  // namespace paco
