#include <paco/assembly/polygonal_assembler.h>

#include "backends.h"
#include "mesh_cleanup.h"
#include "point_coverage.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/normal_sides.h>
#include <paco/common/normalization.h>
#include <paco/common/progress.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <iomanip>
#include <map>
#include <numeric>
#include <sstream>

namespace paco {

namespace {

// The share of the time left that PolyFit's warm start (the cell complex) may use. Three
// quarters: on large complexes (lattices of 36 planes, 2,000 cells) the start needs over 1 s of a
// 2 s budget, and without it CBC finds nothing there; with it PolyFit can always return the start.
constexpr double kWarmStartBudgetShare = 0.75;
// PolyFit's optimum gives way to its warm start when it passes farther than kFarFromSurface (of
// the diagonal) from a share of the primitives' points kMaxPointsGivenUp above the start's. On
// 900 MFCAD validation cases the excess reached 0.097, and where it passed 0.04 the start was no
// better (doc/assembly.md); a building seen from above whose walls PolyFit dropped had 0.33.
constexpr double kFarFromSurface = 0.05;
constexpr double kMaxPointsGivenUp = 0.10;

double nowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string loweredSmoothnessNote(double asked, double used) {
  std::ostringstream note;
  note << "The cell complex labelled every cell outside with smoothness " << asked
       << " (its points cover too little of the planes' faces to outweigh their area); the solid was labelled with "
       << used << ". Check that the points' normals face outwards.";
  return note.str();
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

Eigen::Vector3d position(const pcl::PointNormal& p) { return {p.x, p.y, p.z}; }

double meanAbsDistance(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& plane) {
  if (points.empty()) return 0.0;
  double sum = 0.0;
  for (const auto& p : points) sum += std::abs(plane.signedDistance(position(p)));
  return sum / static_cast<double>(points.size());
}

Plane refit(const pcl::PointCloud<pcl::PointNormal>& points, const Plane& hint) {
  std::vector<Eigen::Vector3d> xs;
  xs.reserve(points.size());
  for (const auto& p : points) xs.push_back(position(p));
  try {
    return Plane::fit(xs, hint.normal);
  } catch (const Error&) {
    return hint;  // collinear points: keep the plane we had
  }
}

// CGAL's PolyFit names each candidate vertex by three of its planes, and a cutting plane that
// passes closer than 1e-5 (in this unit-diagonal frame) to a vertex cuts "at" it. Where a fourth
// plane passes through the vertex of three, or a third plane through the line of two, faces
// around it get edges named differently on each side; its program sees them as open and forbids
// them: a box with a fourth plane through one corner has no solution at all. So planes are moved
// apart before PolyFit sees them, by kSeparation along the normal, points included; the mesh
// moves by as little. Returns how many shifts were made.
constexpr double kConcurrencyTolerance = 2e-5;  // twice CGAL's snapping distance
constexpr double kSeparation = 5e-5;            // moves a plane beyond the tolerance
constexpr int kMaxShiftsPerPlane = 2;           // among near-coincident planes meetings never end
std::size_t separateConcurrentPlanes(std::vector<PlanarPrimitive>& primitives) {
  const std::size_t n = primitives.size();
  std::vector<Plane> planes(n);
  for (std::size_t i = 0; i < n; ++i) planes[i] = refit(primitives[i].points, primitives[i].plane);
  // Only meetings inside CGAL's box matter: the points' box, which it enlarges by 5 % of the
  // diagonal (10 % here, to be safe).
  Eigen::AlignedBox3d box;
  for (const auto& primitive : primitives)
    for (const auto& p : primitive.points) box.extend(position(p));
  const double margin = 0.1 * box.diagonal().norm();
  box.min().array() -= margin;
  box.max().array() += margin;

  // The point of three planes, if they meet in one well-defined point inside the box.
  auto vertexOf = [&](std::size_t a, std::size_t b, std::size_t c, Eigen::Vector3d& x) {
    Eigen::Matrix3d m;
    m << planes[a].normal.transpose(), planes[b].normal.transpose(), planes[c].normal.transpose();
    if (std::abs(m.determinant()) < 1e-3) return false;  // two parallel, or all through one line
    x = m.partialPivLu().solve(Eigen::Vector3d(-planes[a].offset, -planes[b].offset, -planes[c].offset));
    return box.contains(x);
  };
  // The search moves the planes only; their points follow once, by each plane's net shift.
  std::vector<int> times_shifted(n, 0);
  auto shift = [&](std::size_t k, double sign) {
    times_shifted[k] += sign > 0 ? 1 : -1;
    planes[k].offset -= sign * kSeparation;
  };
  // Moves the least supported plane of a meeting if that separates it, else `fallback`, which
  // always does (it is the plane measured against the others' point or line).
  auto separate = [&](const std::vector<std::size_t>& meeting, std::size_t fallback,
                      const std::function<bool()>& still_met) {
    for (std::size_t k : meeting)
      if (times_shifted[k] >= kMaxShiftsPerPlane) return false;
    const std::size_t weakest = *std::min_element(meeting.begin(), meeting.end(), [&](std::size_t a, std::size_t b) {
      return primitives[a].points.size() < primitives[b].points.size();
    });
    shift(weakest, 1.0);
    if (weakest != fallback && still_met()) {
      shift(weakest, -1.0);
      shift(fallback, 1.0);
    }
    return true;
  };

  // A shift can, rarely, make a new meeting: scan again, a few times at most.
  std::size_t shifts = 0;
  for (int pass = 0; pass < 3; ++pass) {
    const std::size_t shifts_before = shifts;
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t b = a + 1; b < n; ++b) {
        // Three planes through one line: c parallel to the line of a and b, and within the
        // tolerance of it (at its point nearest the origin, inside the box).
        const Eigen::Vector3d direction = planes[a].normal.cross(planes[b].normal);
        if (direction.norm() < 1e-3) continue;  // (nearly) parallel: no line
        const Eigen::Vector3d along = direction.normalized();
        for (std::size_t c = 0; c < n; ++c) {
          if (c == a || c == b || std::abs(planes[c].normal.dot(along)) > 1e-3) continue;
          auto met = [&] {
            Eigen::Matrix3d m;
            m << planes[a].normal.transpose(), planes[b].normal.transpose(), along.transpose();
            const Eigen::Vector3d on_line =
                m.colPivHouseholderQr().solve(Eigen::Vector3d(-planes[a].offset, -planes[b].offset, 0.0));
            return box.contains(on_line) && std::abs(planes[c].signedDistance(on_line)) < kConcurrencyTolerance;
          };
          if (met() && separate({a, b, c}, c, met)) ++shifts;
        }
        // Four planes through one point: d within the tolerance of the vertex of a, b, c.
        for (std::size_t c = b + 1; c < n; ++c) {
          Eigen::Vector3d x;
          if (!vertexOf(a, b, c, x)) continue;
          for (std::size_t d = 0; d < n; ++d) {
            if (d == a || d == b || d == c || std::abs(planes[d].signedDistance(x)) >= kConcurrencyTolerance) continue;
            auto met = [&] {
              Eigen::Vector3d y;
              return vertexOf(a, b, c, y) && std::abs(planes[d].signedDistance(y)) < kConcurrencyTolerance;
            };
            if (separate({a, b, c, d}, d, met)) ++shifts;
            if (!vertexOf(a, b, c, x)) break;
          }
        }
      }
    if (shifts == shifts_before) break;
  }
  for (std::size_t k = 0; k < n; ++k) {
    if (times_shifted[k] == 0) continue;
    const double distance = times_shifted[k] * kSeparation;
    primitives[k].plane.offset -= distance;
    const Eigen::Vector3f step = (distance * planes[k].normal).cast<float>();
    for (auto& p : primitives[k].points) p.x += step.x(), p.y += step.y(), p.z += step.z();
  }
  return shifts;
}

// num_merged and num_dropped from the fates.
void countFates(AssemblyResult& result) {
  result.num_merged = result.num_dropped = 0;
  for (const auto& fate : result.fates) {
    result.num_merged += fate.kind == PrimitiveFate::MergedInto;
    result.num_dropped += fate.kind == PrimitiveFate::Dropped;
  }
}

}  // namespace

std::string toString(AssemblyStatus status) {
  switch (status) {
    case AssemblyStatus::Success: return "success";
    case AssemblyStatus::NotRun: return "not-run";
    case AssemblyStatus::EmptyInput: return "empty-input";
    case AssemblyStatus::InvalidInput: return "invalid-input";
    case AssemblyStatus::TooFewPlanes: return "too-few-planes";
    case AssemblyStatus::DegeneratePlanes: return "degenerate-planes";
    case AssemblyStatus::EmptySolution: return "empty-solution";
    case AssemblyStatus::SolverFailed: return "solver-failed";
    case AssemblyStatus::TimeLimit: return "time-limit";
    case AssemblyStatus::Interrupted: return "interrupted";
    case AssemblyStatus::NotWatertight: return "not-watertight";
  }
  return "unknown";
}

AssemblyBackend backendFromString(const std::string& name) {
  const std::string n = lower(name);
  if (n == "polyfit") return AssemblyBackend::PolyFit;
  if (n == "cell-complex" || n == "cellcomplex" || n == "cell_complex") return AssemblyBackend::CellComplex;
  throw InvalidInputError("unknown assembly backend '" + name + "': use 'polyfit' or 'cell-complex'");
}

std::string toString(AssemblyBackend backend) {
  return backend == AssemblyBackend::PolyFit ? "polyfit" : "cell-complex";
}

MipSolver mipSolverFromString(const std::string& name) {
  const std::string n = lower(name);
  if (n == "cbc") return MipSolver::Cbc;
  if (n == "glpk") return MipSolver::Glpk;
  throw InvalidInputError("unknown MIP solver '" + name + "': use 'cbc' or 'glpk'");
}

std::string toString(MipSolver solver) { return solver == MipSolver::Cbc ? "cbc" : "glpk"; }

std::vector<PlanarPrimitive> mergeAndFilterPrimitives(const std::vector<PlanarPrimitive>& primitives,
                                                      double merge_angle, double merge_distance,
                                                      std::size_t min_support, std::vector<PrimitiveFate>* fates) {
  std::vector<PrimitiveFate> local(primitives.size());
  // Largest first, so that small duplicates join the well-supported plane.
  std::vector<std::size_t> order(primitives.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return primitives[a].points.size() > primitives[b].points.size(); });
  std::vector<PlanarPrimitive> kept;
  std::vector<std::size_t> kept_source;  // input index of each kept primitive
  for (std::size_t i : order) {
    const PlanarPrimitive& p = primitives[i];
    if (p.points.size() < min_support) {
      local[i].kind = PrimitiveFate::Dropped;
      local[i].reason = std::to_string(p.points.size()) + " points < minimum support " + std::to_string(min_support);
      continue;
    }
    bool merged = false;
    if (merge_distance > 0.0) {
      for (std::size_t k = 0; k < kept.size() && !merged; ++k) {
        PlanarPrimitive& q = kept[k];
        const double angle = p.plane.unorientedAngleTo(q.plane);
        if (angle > merge_angle) continue;
        const double d_pq = meanAbsDistance(p.points, q.plane), d_qp = meanAbsDistance(q.points, p.plane);
        if (d_pq > merge_distance || d_qp > merge_distance) continue;
        std::ostringstream why;
        why << "angle " << radiansToDegrees(angle) << " deg, mean distance " << std::max(d_pq, d_qp);
        local[i].kind = PrimitiveFate::MergedInto;
        local[i].target = kept_source[k];
        local[i].reason = why.str();
        q.points += p.points;
        q.confidence = std::max(q.confidence, p.confidence);
        q.plane = refit(q.points, q.plane);
        merged = true;
      }
    }
    if (merged) continue;
    kept.push_back(p);
    kept_source.push_back(i);
  }
  // Keep the input order among the survivors, so that plane indices are predictable.
  std::vector<std::size_t> by_input(kept.size());
  std::iota(by_input.begin(), by_input.end(), 0);
  std::sort(by_input.begin(), by_input.end(), [&](std::size_t a, std::size_t b) { return kept_source[a] < kept_source[b]; });
  std::vector<PlanarPrimitive> result;
  result.reserve(kept.size());
  for (std::size_t k : by_input) result.push_back(std::move(kept[k]));
  if (fates) *fates = std::move(local);
  return result;
}

PolygonalAssembler::PolygonalAssembler() : merge_angle_(degreesToRadians(2.0)) {}
PolygonalAssembler::~PolygonalAssembler() = default;

void PolygonalAssembler::setInputPrimitives(std::vector<PlanarPrimitive> primitives) { input_ = std::move(primitives); }

void PolygonalAssembler::setInputCloud(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                       const PlanarSegmentation& segmentation) {
  segmentation.validate(cloud.size());
  input_ = makePrimitives(cloud, segmentation);
}

namespace {
void requireNonNegative(double w, const char* what) {
  if (!(w >= 0.0) || !std::isfinite(w))
    throw InvalidInputError(std::string("PolygonalAssembler: the ") + what + " weight must be a finite value >= 0");
}
}  // namespace

void PolygonalAssembler::setFittingWeight(double w) { requireNonNegative(w, "fitting"), wt_fitting_ = w; }
void PolygonalAssembler::setCoverageWeight(double w) { requireNonNegative(w, "coverage"), wt_coverage_ = w; }
void PolygonalAssembler::setComplexityWeight(double w) { requireNonNegative(w, "complexity"), wt_complexity_ = w; }

void PolygonalAssembler::setTimeLimit(double seconds) {
  if (!(seconds > 0.0)) throw InvalidInputError("PolygonalAssembler: the time limit must be > 0 seconds");
  time_limit_ = seconds;
}

void PolygonalAssembler::setMergeAngle(double radians) {
  if (!(radians >= 0.0 && radians < kPi / 2))
    throw InvalidInputError("PolygonalAssembler: the merge angle must be in [0, pi/2) radians");
  merge_angle_ = radians;
}

void PolygonalAssembler::setMergeDistance(double fraction) {
  if (!(fraction >= 0.0 && fraction < 1.0))
    throw InvalidInputError("PolygonalAssembler: the merge distance must be in [0, 1) of the diagonal");
  merge_distance_ = fraction;
}

void PolygonalAssembler::setMinSupport(std::size_t points) {
  if (points < 3) throw InvalidInputError("PolygonalAssembler: the minimum support must be at least 3 points");
  min_support_ = points;
}

void PolygonalAssembler::setSmoothness(double beta) {
  if (!(beta > 0.0) || !std::isfinite(beta))
    throw InvalidInputError("PolygonalAssembler: the smoothness must be a finite value > 0");
  smoothness_ = beta;
}

void PolygonalAssembler::setExtentMargin(double fraction) {
  if (!(fraction >= 0.0 && fraction <= 1.0))
    throw InvalidInputError("PolygonalAssembler: the extent margin must be in [0, 1] of the diagonal");
  extent_margin_ = fraction;
}

MeshTopology PolygonalAssembler::postProcess(SurfaceMesh& mesh) { return detail::finishAssembledMesh(mesh); }

double PolygonalAssembler::secondsLeft() const { return time_limit_ - (nowSeconds() - start_time_); }

void PolygonalAssembler::fail(AssemblyStatus status, const std::string& message) {
  result_.status = status;
  result_.message = message;
}

void PolygonalAssembler::turnInwardPrimitives(std::vector<PlanarPrimitive>& primitives) {
  // The same rule as for a scan (paco::normalSides), read over every primitive's points with the
  // normals the backends will read (a point without one has just taken its plane's).
  pcl::PointCloud<pcl::PointNormal> points;
  for (const auto& primitive : primitives) points += primitive.points;
  const NormalSides sides = normalSides(points);
  result_.inward_normal_share = sides.inwardShare();
  if (!turn_inward_normals_ || !sides.faceInwards()) return;
  for (auto& primitive : primitives) {
    primitive.plane = primitive.plane.flipped();
    flipNormals(primitive.points);
  }
  result_.turned_inward_normals = true;
}

bool PolygonalAssembler::initCompute() {
  result_.num_input_planes = input_.size();
  if (input_.empty()) {
    fail(AssemblyStatus::EmptyInput, "no primitives: set them with setInputPrimitives() (at least 4 planes)");
    return false;
  }
  std::size_t total_points = 0;
  for (std::size_t k = 0; k < input_.size(); ++k) {
    const Plane& plane = input_[k].plane;
    if (!plane.normal.allFinite() || !std::isfinite(plane.offset) || std::abs(plane.normal.norm() - 1.0) > 1e-6) {
      fail(AssemblyStatus::InvalidInput, "primitive " + std::to_string(k) + " has a non-finite or non-unit plane normal");
      return false;
    }
    for (const auto& p : input_[k].points)
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
        fail(AssemblyStatus::InvalidInput, "primitive " + std::to_string(k) + " has a point with non-finite "
                                           "coordinates: remove NaN/Inf points first");
        return false;
      }
    total_points += input_[k].points.size();
  }
  if (total_points == 0) {
    fail(AssemblyStatus::EmptyInput, "the " + std::to_string(input_.size()) + " primitives have no inlier points");
    return false;
  }

  // Points without normals take their plane's; non-finite normals likewise.
  std::vector<PlanarPrimitive> primitives = input_;
  std::vector<Eigen::Vector3d> all_points;
  all_points.reserve(total_points);
  for (auto& primitive : primitives)
    for (auto& p : primitive.points) {
      Eigen::Vector3f n(p.normal_x, p.normal_y, p.normal_z);
      if (!n.allFinite() || n.norm() < 0.5) {
        p.normal_x = static_cast<float>(primitive.plane.normal.x());
        p.normal_y = static_cast<float>(primitive.plane.normal.y());
        p.normal_z = static_cast<float>(primitive.plane.normal.z());
      }
      all_points.push_back(position(p));
    }
  turnInwardPrimitives(primitives);
  Eigen::Vector3d lo = all_points.front(), hi = all_points.front();
  for (const auto& x : all_points) {
    lo = lo.cwiseMin(x);
    hi = hi.cwiseMax(x);
  }
  const double diagonal = (hi - lo).norm();
  if (!(diagonal > 0.0)) {
    fail(AssemblyStatus::InvalidInput, "all inlier points coincide: the primitives have no extent");
    return false;
  }

  used_ = mergeAndFilterPrimitives(primitives, merge_angle_, merge_distance_ * diagonal, min_support_, &result_.fates);
  result_.num_planes_used = used_.size();
  countFates(result_);
  if (used_.size() < 4) {
    std::ostringstream message;
    message << "at least 4 planes are needed to enclose a volume; " << used_.size() << " left of " << input_.size();
    if (result_.num_merged || result_.num_dropped)
      message << " (" << result_.num_merged << " merged as near-duplicates, " << result_.num_dropped
              << " dropped for fewer than " << min_support_ << " points)";
    fail(AssemblyStatus::TooFewPlanes, message.str());
    return false;
  }
  // A closed volume needs normals in three independent directions.
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : used_) scatter += p.plane.normal * p.plane.normal.transpose();
  const Eigen::Vector3d eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvalues();
  const double tiny = 1e-6 * eigenvalues(2);
  if (eigenvalues(1) < tiny) {
    fail(AssemblyStatus::DegeneratePlanes,
         "all " + std::to_string(used_.size()) + " planes are parallel: they cannot enclose a volume");
    return false;
  }
  if (eigenvalues(0) < tiny) {
    fail(AssemblyStatus::DegeneratePlanes, "all " + std::to_string(used_.size()) +
                                               " planes are parallel to one direction (their normals lie in one "
                                               "plane): they cannot enclose a volume");
    return false;
  }
  return true;
}

void PolygonalAssembler::performReconstruction(const std::vector<PlanarPrimitive>& primitives, SurfaceMesh& mesh) {
  detail::BackendOutcome outcome;
  if (backend_ == AssemblyBackend::PolyFit) {
    detail::PolyFitOptions options;
    options.solver = solver_;
    options.wt_fitting = wt_fitting_;
    options.wt_coverage = wt_coverage_;
    options.wt_complexity = wt_complexity_;
    options.seconds = secondsLeft();
    options.verbose = verbose_;
    options.max_candidate_faces = max_candidate_faces_;
    std::vector<PlanarPrimitive> separated = primitives;
    result_.num_planes_separated = separateConcurrentPlanes(separated);
    SurfaceMesh start_solid;
    double start_smoothness = smoothness_;
    if (warm_start_ && solver_ == MipSolver::Cbc) {
      // The warm start: the cell complex on the planes the budget keeps, refitted to their points
      // as CGAL refits them, so that its faces lie on PolyFit's candidate faces.
      options.make_start = [&](const std::vector<bool>& keep) -> const SurfaceMesh* {
        std::vector<PlanarPrimitive> refitted;
        for (std::size_t k = 0; k < separated.size(); ++k) {
          if (!keep[k]) continue;
          refitted.push_back(separated[k]);
          refitted.back().plane = refit(separated[k].points, separated[k].plane);
        }
        // PolyFit allows no edge with four faces: relabel cells at such edges right away.
        detail::CellComplexOptions cell_options;
        cell_options.smoothness = smoothness_;
        cell_options.extent_margin = extent_margin_;
        cell_options.resolve_crossings = true;
        // Not the whole budget: the start is quick on piecewise-planar inputs, but on others the
        // cell complex can relabel until its time runs out, and PolyFit needs time of its own.
        cell_options.seconds = kWarmStartBudgetShare * secondsLeft();
        const detail::BackendOutcome start_outcome = detail::runCellComplex(refitted, cell_options, start_solid);
        if (start_outcome.status != AssemblyStatus::Success || !postProcess(start_solid).isClosedManifold()) {
          start_solid = SurfaceMesh{};
          return nullptr;
        }
        start_smoothness = start_outcome.smoothness_used;
        return &start_solid;
      };
    }
    outcome = detail::runPolyFit(separated, options, mesh);
    result_.num_warm_start_faces = outcome.start_faces;
    result_.num_warm_start_faces_released = outcome.start_faces_released;
    // A time-out, a solver failure or an empty optimum returns the start rather than nothing,
    // also when CBC could not complete it into a solution of its own program: the start is a
    // closed surface of the same planes. (PolyFit's energy can prefer no face at all, e.g. with a
    // large complexity weight.)
    const bool timed_out = outcome.status == AssemblyStatus::TimeLimit;
    const bool empty = outcome.status == AssemblyStatus::EmptySolution;
    if ((timed_out || empty || outcome.status == AssemblyStatus::SolverFailed) && !start_solid.faces.empty() &&
        !interruptRequested()) {
      const std::string why = outcome.message;
      mesh = start_solid;
      outcome.status = AssemblyStatus::Success;
      outcome.message.clear();
      outcome.hit_time_limit = timed_out;
      result_.returned_warm_start = true;
      if (timed_out)
        result_.message =
            "PolyFit found no solution within the time limit; the surface of its warm start (the cell complex) is "
            "returned; a longer time limit may let PolyFit finish.";
      else if (empty)
        result_.message =
            "PolyFit's optimum is the empty surface (with these weights its energy prefers no face at all); the "
            "surface of its warm start (the cell complex) is returned.";
      else
        result_.message = "PolyFit failed (" + why + "); the surface of its warm start (the cell complex) is returned.";
      result_.smoothness_used = start_smoothness;
      if (start_smoothness < smoothness_) result_.message += " " + loweredSmoothnessNote(smoothness_, start_smoothness);
    }
    // PolyFit's coverage term can outweigh the points of sparsely seen faces: a building scanned
    // from above lost its walls and floor and became a slab of roof. When its optimum passes far
    // from many more of the points than the start does, the start is the better surface.
    if (outcome.status == AssemblyStatus::Success && !result_.returned_warm_start && !start_solid.faces.empty() &&
        !interruptRequested()) {
      std::vector<bool> left_out(separated.size(), false);
      for (std::size_t j : outcome.dropped_for_budget) left_out[j] = true;
      std::vector<PlanarPrimitive> kept;
      for (std::size_t k = 0; k < separated.size(); ++k)
        if (!left_out[k]) kept.push_back(separated[k]);
      const double far_optimum = detail::shareOfPointsFartherThan(mesh, kept, kFarFromSurface);
      const double far_start = detail::shareOfPointsFartherThan(start_solid, kept, kFarFromSurface);
      if (far_optimum - far_start > kMaxPointsGivenUp) {
        std::ostringstream why;
        why << std::fixed << std::setprecision(0) << "PolyFit's optimum passes farther than " << 100 * kFarFromSurface
            << " % of the diagonal from " << 100 * far_optimum << " % of the primitives' points, its warm start (the "
            << "cell complex) from " << 100 * far_start
            << " %: the start's surface is returned (PolyFit's coverage term outweighed the points of sparsely "
               "covered faces; a lower coverage weight keeps them).";
        mesh = start_solid;
        result_.returned_warm_start = true;
        result_.message = why.str();
        result_.smoothness_used = start_smoothness;
        if (start_smoothness < smoothness_) result_.message += " " + loweredSmoothnessNote(smoothness_, start_smoothness);
      }
    }
    if (!outcome.dropped_for_budget.empty()) {
      // used_[j] is the j-th primitive kept by pre-processing, in input order.
      std::vector<std::size_t> input_index;
      for (std::size_t i = 0; i < result_.fates.size(); ++i)
        if (result_.fates[i].kind == PrimitiveFate::Kept) input_index.push_back(i);
      std::vector<bool> dropped(used_.size(), false);
      for (std::size_t j : outcome.dropped_for_budget) {
        dropped[j] = true;
        PrimitiveFate& fate = result_.fates[input_index[j]];
        fate.kind = PrimitiveFate::Dropped;
        std::ostringstream why;
        why << "confidence " << used_[j].confidence << ", among the least confident left out to keep PolyFit within "
            << max_candidate_faces_ << " candidate faces";
        fate.reason = why.str();
        ++result_.num_over_budget;
        // Primitives merged into it go with it.
        for (auto& other : result_.fates)
          if (other.kind == PrimitiveFate::MergedInto && other.target == input_index[j]) {
            other.kind = PrimitiveFate::Dropped;
            other.reason = "merged into a primitive left out for the candidate-face budget";
            ++result_.num_over_budget;
          }
      }
      std::vector<PlanarPrimitive> kept;
      for (std::size_t j = 0; j < used_.size(); ++j)
        if (!dropped[j]) kept.push_back(std::move(used_[j]));
      used_ = std::move(kept);
      result_.num_planes_used = used_.size();
      countFates(result_);
    }
  } else {
    // A sliver cell labelled wrongly where a plane's extent ends can leave two solids touching
    // along an edge. The partition is cheap, so retry with planes reaching further (2x, 4x); as a
    // last resort relabel one cell at each such edge (the least costly one), which changes the
    // solid a little but makes it a manifold.
    detail::CellComplexOptions options;
    options.smoothness = smoothness_;
    const std::pair<double, bool> attempts[] = {{1.0, false}, {2.0, false}, {4.0, false}, {1.0, true}};
    for (const auto& [factor, resolve] : attempts) {
      if (extent_margin_ == 0.0 && factor != 1.0) continue;
      options.extent_margin = extent_margin_ * factor;
      options.resolve_crossings = resolve;
      options.seconds = secondsLeft();
      SurfaceMesh attempt;
      detail::BackendOutcome attempt_outcome = detail::runCellComplex(primitives, options, attempt);
      const bool first = factor == 1.0 && !resolve;
      if (attempt_outcome.status != AssemblyStatus::Success) {
        if (first) outcome = attempt_outcome, mesh = std::move(attempt);
        break;
      }
      SurfaceMesh check = attempt;
      const bool watertight = postProcess(check).isClosedManifold();
      if (first || watertight) outcome = attempt_outcome, mesh = std::move(attempt);
      if (watertight || secondsLeft() <= 0.0) break;
    }
  }
  result_.solution_is_optimal = outcome.optimal;
  result_.hit_time_limit = outcome.hit_time_limit;
  result_.num_candidate_faces = outcome.num_candidate_faces;
  result_.seconds_partition = outcome.seconds_partition;
  result_.seconds_solve = outcome.seconds_solve;
  result_.num_cells = outcome.num_cells;
  result_.num_crossings_resolved = outcome.crossings_resolved;
  if (backend_ == AssemblyBackend::CellComplex) {
    result_.smoothness_used = outcome.smoothness_used;
    if (outcome.status == AssemblyStatus::Success && outcome.smoothness_used < smoothness_)
      result_.message = loweredSmoothnessNote(smoothness_, outcome.smoothness_used);
  }
  result_.num_variables = outcome.num_variables;
  result_.num_constraints = outcome.num_constraints;
  if (outcome.status != AssemblyStatus::Success) fail(outcome.status, outcome.message);
}

const AssemblyResult& PolygonalAssembler::reconstruct(SurfaceMesh& mesh) {
  start_time_ = nowSeconds();
  result_ = AssemblyResult{};
  result_.status = AssemblyStatus::Success;
  used_.clear();
  mesh = SurfaceMesh{};
  auto finish = [&]() -> const AssemblyResult& {
    result_.seconds = nowSeconds() - start_time_;
    return result_;
  };
  if (!initCompute()) return finish();
  if (!(wt_fitting_ + wt_coverage_ + wt_complexity_ > 0.0)) {
    fail(AssemblyStatus::InvalidInput, "the fitting, coverage and complexity weights are all 0");
    return finish();
  }

  // Work at unit diagonal so that tolerances mean the same for every input unit.
  std::vector<Eigen::Vector3d> all_points;
  for (const auto& p : used_)
    for (const auto& q : p.points) all_points.push_back(position(q));
  const Normalization normalization = Normalization::fromBoundingBox(all_points);
  std::vector<PlanarPrimitive> normalised = used_;
  normalization.apply(normalised);

  SurfaceMesh work;
  performReconstruction(normalised, work);
  if (result_.status == AssemblyStatus::Success && interruptRequested())
    fail(AssemblyStatus::Interrupted, "interrupted by the user");
  if (result_.status != AssemblyStatus::Success) return finish();
  if (work.faces.empty()) {
    fail(AssemblyStatus::EmptySolution, "the " + toString(backend_) + " backend produced no face");
    return finish();
  }

  result_.topology = postProcess(work);
  normalization.applyInverse(work);
  mesh = std::move(work);
  if (mesh.faces.empty()) {
    fail(AssemblyStatus::EmptySolution, "every face of the " + toString(backend_) + " result was degenerate");
  } else if (!result_.topology.isClosedManifold()) {
    fail(AssemblyStatus::NotWatertight,
         "the " + toString(backend_) + " result is not a closed oriented manifold: " + result_.topology.describe());
  } else if (!(signedVolume(mesh) > 0.0)) {
    fail(AssemblyStatus::EmptySolution, "the " + toString(backend_) + " result encloses no volume");
  }
  if (result_.status != AssemblyStatus::Success && result_.status != AssemblyStatus::NotWatertight) mesh = SurfaceMesh{};
  return finish();
}

const AssemblyResult& PolygonalAssembler::reconstruct(pcl::PolygonMesh& mesh) {
  SurfaceMesh surface;
  reconstruct(surface);
  mesh = toPolygonMesh(surface);
  return result_;
}

}  // namespace paco
