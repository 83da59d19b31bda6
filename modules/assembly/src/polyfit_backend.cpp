// The "polyfit" backend: CGAL's Polygonal_surface_reconstruction (Nan & Wonka, PolyFit, ICCV 2017)
// with COIN-OR CBC or GLPK as the MIP solver. The only translation unit of paco that includes CGAL's
// reconstruction code (it takes a minute and ~2 GB to compile).
#include "backends.h"
#include "mip_traits.h"

#include <paco/common/angles.h>
#include <paco/common/progress.h>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygonal_surface_reconstruction.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/property_map.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <chrono>
#include <limits>
#include <map>
#include <memory>
#include <tuple>
#include <vector>

namespace paco::detail {
namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using PointWithNormalAndPlane = std::tuple<Point, Vector, int>;
using PointMap = CGAL::Nth_of_tuple_property_map<0, PointWithNormalAndPlane>;
using NormalMap = CGAL::Nth_of_tuple_property_map<1, PointWithNormalAndPlane>;
using PlaneIndexMap = CGAL::Nth_of_tuple_property_map<2, PointWithNormalAndPlane>;
using Reconstruction = CGAL::Polygonal_surface_reconstruction<Kernel>;
using CgalMesh = CGAL::Surface_mesh<Point>;

// CGAL 5.5's plane fit returns normals with ~1e-30 components for exactly axis-aligned point sets;
// its three-plane intersections then depend on argument order and candidate generation runs away
// (minutes, gigabytes). Turning the input by a fixed generic rotation avoids exact alignment; the
// result is turned back. The turn is small on purpose: CGAL clips the candidate faces to the
// axis-aligned box of the turned points, enlarged by 2.5 % of its diagonal, and a corner of the
// points' own box that no point reaches (faces sampled short of their edges, corners cut away)
// sticks out of the turned points' box. When each face's points lie around its middle, by about
// half a side times the largest sum of a row's off-diagonal entries of the turn: 0.048 for these
// angles (1.5, 1.2 and 0.85 degrees), so 2.4 % of the side, inside the margin (4.3 % of a cube's
// side). The turn used until 2026-12-04 (31, 24 and 17 degrees) clipped such corners, and
// PolyFit then kept a sliver of the part, or nothing (doc/assembly.md). The angles are fixed, so
// results are reproducible.
Eigen::Matrix3d genericRotation() {
  return (Eigen::AngleAxisd(0.026865, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(0.020935, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(0.014765, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Generalised winding number of a closed polygon mesh at x (about ±1 inside, 0 outside): the
// solid angles of a fan triangulation of every face, over 4π (Van Oosterom & Strackee).
double windingNumber(const SurfaceMesh& solid, const Eigen::Vector3d& x) {
  double total = 0.0;
  for (const auto& face : solid.faces)
    for (std::size_t i = 1; i + 1 < face.size(); ++i) {
      const Eigen::Vector3d a = solid.vertices[face[0]] - x, b = solid.vertices[face[i]] - x,
                            c = solid.vertices[face[i + 1]] - x;
      const double la = a.norm(), lb = b.norm(), lc = c.norm();
      const double numerator = a.dot(b.cross(c));
      const double denominator = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
      total += 2.0 * std::atan2(numerator, denominator);
    }
  return total / (4.0 * kPi);
}

// 1 for each of CGAL's candidate faces (in its order, which is the order of its face variables)
// that separates the inside of `solid` from its outside, 0 otherwise. `back` turns candidate
// coordinates into the solid's frame.
std::vector<double> facesOnSolidBoundary(const CgalMesh& candidates, const SurfaceMesh& solid,
                                         const Eigen::Matrix3d& back) {
  // Far below the spacing of distinct planes (the frame has unit diagonal), far above rounding.
  constexpr double kProbe = 1e-5;
  std::vector<double> selected;
  selected.reserve(candidates.number_of_faces());
  for (auto f : candidates.faces()) {
    std::vector<Eigen::Vector3d> corners;
    for (auto v : CGAL::vertices_around_face(candidates.halfedge(f), candidates)) {
      const Point& p = candidates.point(v);
      corners.push_back(back * Eigen::Vector3d(p.x(), p.y(), p.z()));
    }
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < corners.size(); ++i) {
      centroid += corners[i];
      normal += corners[i].cross(corners[(i + 1) % corners.size()]);  // Newell
    }
    centroid /= static_cast<double>(std::max<std::size_t>(1, corners.size()));
    bool boundary = false;
    if (normal.norm() > 0.0) {
      normal.normalize();
      const bool front = std::abs(windingNumber(solid, centroid + kProbe * normal)) > 0.5;
      const bool rear = std::abs(windingNumber(solid, centroid - kProbe * normal)) > 0.5;
      boundary = front != rear;
    }
    selected.push_back(boundary ? 1.0 : 0.0);
  }
  return selected;
}

// Two rings let CBC complete the start on the validation programs it had rejected; more rings
// leave it too much to complete within its start heuristic, fewer too little room.
constexpr int kReleaseRings = 2;

// PolyFit's program (CGAL's formulation) lets a surface use a candidate edge only where exactly
// four candidate faces meet (two planes crossing), with 0 or 2 of them selected; at any other
// edge every face must stay unselected. CBC rejects a start that breaks this anywhere as a whole
// ("mipstart values could not be used"), and the cell complex's surface can break it: where it
// touches itself along an edge, or near planes that meet in a way CGAL names inconsistently
// (separateConcurrentPlanes() removes most of those). So the faces around each such edge,
// `rings` edge-neighbours deep, are left unspecified (NaN): CBC completes that neighbourhood and
// keeps the rest of the start. Returns how many faces were left unspecified.
std::size_t releaseFacesAtForbiddenEdges(const CgalMesh& candidates, std::vector<double>& start, int rings) {
  // CGAL keys an edge by its end points, each computed once per triplet of planes: keying by
  // their exact coordinates gives the same edges (the copied mesh shares no vertices between
  // planes).
  using Corner = std::array<double, 3>;
  std::map<std::pair<Corner, Corner>, std::vector<std::size_t>> faces_at_edge;
  std::vector<std::vector<const std::vector<std::size_t>*>> edges_of_face(start.size());
  std::size_t index = 0;
  for (auto f : candidates.faces()) {
    for (auto h : CGAL::halfedges_around_face(candidates.halfedge(f), candidates)) {
      const Point& a = candidates.point(candidates.source(h));
      const Point& b = candidates.point(candidates.target(h));
      Corner ca{a.x(), a.y(), a.z()}, cb{b.x(), b.y(), b.z()};
      if (cb < ca) std::swap(ca, cb);
      faces_at_edge[{ca, cb}].push_back(index);
    }
    ++index;
  }
  for (const auto& [edge, faces] : faces_at_edge)
    for (std::size_t f : faces) edges_of_face[f].push_back(&faces);

  std::vector<bool> released(start.size(), false);
  std::vector<std::size_t> frontier;
  for (const auto& [edge, faces] : faces_at_edge) {
    std::size_t selected = 0;
    for (std::size_t f : faces) selected += start[f] == 1.0 ? 1 : 0;
    const bool allowed = selected == 0 || (faces.size() == 4 && selected == 2);
    if (allowed) continue;
    for (std::size_t f : faces)
      if (!released[f]) released[f] = true, frontier.push_back(f);
  }
  for (int ring = 0; ring < rings; ++ring) {
    std::vector<std::size_t> next;
    for (std::size_t f : frontier)
      for (const auto* neighbours : edges_of_face[f])
        for (std::size_t g : *neighbours)
          if (!released[g]) released[g] = true, next.push_back(g);
    frontier = std::move(next);
  }
  std::size_t count = 0;
  for (std::size_t f = 0; f < start.size(); ++f)
    if (released[f]) start[f] = std::numeric_limits<double>::quiet_NaN(), ++count;
  return count;
}

// A plane bounds the hull when its far side holds at most 1 % of the points farther than 1 % of
// their box's diagonal (about twice a segment's inlier distance on MFCAD scans).
constexpr double kHullTolerance = 0.01;
constexpr double kHullStrayFraction = 0.01;

// Which primitives bound the hull of all the primitives' points: their plane has (nearly) every
// point on one side (kHullTolerance, kHullStrayFraction: a guess's scattered points, a few
// outliers). Leaving such a plane out opens the solid on that side, and PolyFit closes it at the
// next plane inward, cutting off the slab between: far worse than losing an interior plane.
std::vector<bool> hullFaces(const std::vector<PlanarPrimitive>& primitives) {
  std::vector<Eigen::Vector3d> points;
  Eigen::AlignedBox3d box;
  for (const auto& primitive : primitives)
    for (const auto& p : primitive.points) box.extend(points.emplace_back(p.x, p.y, p.z));
  const double tolerance = box.isEmpty() ? 0.0 : kHullTolerance * box.diagonal().norm();
  const auto strays_allowed = static_cast<std::size_t>(kHullStrayFraction * static_cast<double>(points.size()));
  std::vector<bool> hull(primitives.size(), false);
  for (std::size_t k = 0; k < primitives.size(); ++k) {
    const Plane& plane = primitives[k].plane;
    const double norm = plane.normal.norm();
    if (!(norm > 0.0)) continue;
    std::size_t above = 0, below = 0;
    for (const auto& x : points) {
      const double distance = (plane.normal.dot(x) + plane.offset) / norm;  // a normal set by hand need not be unit
      above += distance > tolerance ? 1 : 0;
      below += distance < -tolerance ? 1 : 0;
    }
    hull[k] = std::min(above, below) <= strays_allowed;
  }
  return hull;
}

}  // namespace

BackendOutcome runPolyFit(const std::vector<PlanarPrimitive>& primitives, const PolyFitOptions& options,
                          SurfaceMesh& mesh) {
  const auto start = std::chrono::steady_clock::now();
  BackendOutcome outcome;
  mesh = SurfaceMesh{};
  const Eigen::Matrix3d rotation = genericRotation();

  // Candidate generation for the primitives marked in `keep` (plane indices renumbered 0..n-1).
  auto generate = [&](const std::vector<bool>& keep) {
    std::vector<PointWithNormalAndPlane> points;
    int plane = 0;
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      if (!keep[k]) continue;
      for (const auto& p : primitives[k].points) {
        const Eigen::Vector3d x = rotation * Eigen::Vector3d(p.x, p.y, p.z);
        const Eigen::Vector3d n = rotation * Eigen::Vector3d(p.normal_x, p.normal_y, p.normal_z);
        points.emplace_back(Point(x.x(), x.y(), x.z()), Vector(n.x(), n.y(), n.z()), plane);
      }
      ++plane;
    }
    // The constructor generates the candidate faces and their confidences (not interruptible).
    return std::make_unique<Reconstruction>(points, PointMap(), NormalMap(), PlaneIndexMap());
  };
  auto countCandidates = [](const Reconstruction& r) {
    CgalMesh candidates;
    r.output_candidate_faces(candidates);
    return static_cast<std::size_t>(candidates.number_of_faces());
  };

  std::vector<bool> keep(primitives.size(), true);  // what the budget keeps, for the warm start
  std::unique_ptr<Reconstruction> reconstruction = generate(keep);
  if (reconstruction->error_message().empty() && options.max_candidate_faces > 0 &&
      countCandidates(*reconstruction) > options.max_candidate_faces) {
    // Leave out the k least confident predicted primitives (observed ones have confidence 1),
    // with the smallest k that fits the budget, found by bisection (fewer planes give fewer
    // candidates, if not strictly). At least 4 planes stay, and no plane of the hull: when only
    // those are left, the candidates stay over the budget (the solver's time limit still holds).
    const std::vector<bool> on_hull = hullFaces(primitives);
    std::vector<std::size_t> droppable;
    for (std::size_t k = 0; k < primitives.size(); ++k)
      if (primitives[k].confidence < 1.0f && !on_hull[k]) droppable.push_back(k);
    std::stable_sort(droppable.begin(), droppable.end(), [&](std::size_t a, std::size_t b) {
      return primitives[a].confidence < primitives[b].confidence;
    });
    const std::size_t most = std::min(droppable.size(), primitives.size() > 4 ? primitives.size() - 4 : 0);
    auto keepAllBut = [&](std::size_t k) {
      std::vector<bool> mask(primitives.size(), true);
      for (std::size_t i = 0; i < k; ++i) mask[droppable[i]] = false;
      return mask;
    };
    std::size_t lo = 1, hi = most;  // the answer is in [lo, hi]; hi fits or is the most we may drop
    std::unique_ptr<Reconstruction> best;
    if (most > 0) {
      best = generate(keepAllBut(most));
      while (lo < hi && secondsSince(start) < 0.25 * options.seconds) {
        const std::size_t mid = (lo + hi) / 2;
        std::unique_ptr<Reconstruction> trial = generate(keepAllBut(mid));
        if (trial->error_message().empty() && countCandidates(*trial) <= options.max_candidate_faces) {
          hi = mid;
          best = std::move(trial);
        } else {
          lo = mid + 1;
        }
      }
      if (best && best->error_message().empty()) {
        reconstruction = std::move(best);
        outcome.dropped_for_budget.assign(droppable.begin(), droppable.begin() + static_cast<std::ptrdiff_t>(hi));
        keep = keepAllBut(hi);
      }
    }
  }
  if (!reconstruction->error_message().empty()) {
    outcome.status = AssemblyStatus::SolverFailed;
    outcome.message = "PolyFit candidate generation failed: " + reconstruction->error_message();
    return outcome;
  }
  outcome.seconds_partition = secondsSince(start);
  if (interruptRequested()) {
    outcome.status = AssemblyStatus::Interrupted;
    outcome.message = "interrupted after candidate generation";
    return outcome;
  }
  const SurfaceMesh* start_solid = options.make_start ? options.make_start(keep) : nullptr;
  if (interruptRequested()) {
    outcome.status = AssemblyStatus::Interrupted;
    outcome.message = "interrupted while making the warm start";
    return outcome;
  }
  const double left = options.seconds - secondsSince(start);
  if (left <= 0.0) {
    outcome.status = AssemblyStatus::TimeLimit;
    outcome.message = std::string(options.make_start ? "PolyFit candidate generation and its warm start took "
                                                     : "PolyFit candidate generation alone took ") +
                      std::to_string(secondsSince(start)) +
                      " s, more than the " + std::to_string(options.seconds) +
                      " s left of the time limit; raise it or use the cell-complex backend";
    return outcome;
  }

  const double solve_from = secondsSince(start);  // the start's time is in neither part
  mipSettings() = MipSettings{};
  mipSettings().deadline = std::chrono::steady_clock::now() + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                                  std::chrono::duration<double>(left));
  mipSettings().verbose = options.verbose;
  // The candidate faces, copied once for the start and the count (reconstruct() leaves them as they are).
  CgalMesh candidates;
  reconstruction->output_candidate_faces(candidates);
  if (start_solid && !start_solid->faces.empty()) {
    mipSettings().start = facesOnSolidBoundary(candidates, *start_solid, rotation.transpose());
    mipSettings().has_fallback = true;  // the assembler returns the start's surface if CBC gives nothing
    outcome.start_faces_released = releaseFacesAtForbiddenEdges(candidates, mipSettings().start, kReleaseRings);
    outcome.start_faces =
        static_cast<std::size_t>(std::count(mipSettings().start.begin(), mipSettings().start.end(), 1.0));
  }
  mipOutcome() = MipOutcome{};
  CgalMesh result;
  bool solved = false;
  if (options.solver == MipSolver::Cbc)
    solved = reconstruction->reconstruct<Cbc_mixed_integer_program_traits<double>>(
        result, options.wt_fitting, options.wt_coverage, options.wt_complexity);
  else
    solved = reconstruction->reconstruct<Glpk_timed_mixed_integer_program_traits<double>>(
        result, options.wt_fitting, options.wt_coverage, options.wt_complexity);
  outcome.seconds_solve = secondsSince(start) - solve_from;
  const MipOutcome& mip = mipOutcome();
  outcome.optimal = mip.optimal;
  outcome.hit_time_limit = mip.hit_time_limit;
  outcome.num_variables = mip.num_variables;
  outcome.num_constraints = mip.num_constraints;
  outcome.num_candidate_faces = static_cast<std::size_t>(candidates.number_of_faces());
  if (!solved) {
    const bool timed_out = mip.hit_time_limit && !mip.has_solution;
    outcome.status = timed_out ? AssemblyStatus::TimeLimit : AssemblyStatus::SolverFailed;
    outcome.message = !mip.message.empty() ? mip.message : "PolyFit failed: " + reconstruction->error_message();
    return outcome;
  }

  // Surface_mesh indices may have gaps after face removal: renumber the vertices in use.
  const Eigen::Matrix3d back = rotation.transpose();
  std::vector<std::int64_t> index_of(result.number_of_vertices() + result.number_of_removed_vertices(), -1);
  for (auto f : result.faces()) {
    std::vector<std::uint32_t> face;
    for (auto v : CGAL::vertices_around_face(result.halfedge(f), result)) {
      auto& index = index_of[static_cast<std::size_t>(v)];
      if (index < 0) {
        const Point& p = result.point(v);
        index = static_cast<std::int64_t>(mesh.vertices.size());
        mesh.vertices.push_back(back * Eigen::Vector3d(CGAL::to_double(p.x()), CGAL::to_double(p.y()),
                                                       CGAL::to_double(p.z())));
      }
      face.push_back(static_cast<std::uint32_t>(index));
    }
    mesh.faces.push_back(std::move(face));
  }
  if (mesh.faces.empty()) {
    outcome.status = AssemblyStatus::EmptySolution;
    outcome.message = "PolyFit selected no face (the optimal model is empty); check the primitives' points, "
                      "lower the complexity weight (paco_assemble --complexity) or use the cell-complex "
                      "backend";
  }
  return outcome;
}

}  // namespace paco::detail
