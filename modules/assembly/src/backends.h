#pragma once
// The two assembly backends, as plain functions on primitives in a normalised frame (centre at
// the origin, bounding-box diagonal 1). Private to paco::assembly: CGAL and CBC stay in the .cpp.
#include <paco/assembly/polygonal_assembler.h>

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace paco::detail {

struct BackendOutcome {
  AssemblyStatus status = AssemblyStatus::Success;
  std::string message;
  bool optimal = false;
  bool hit_time_limit = false;
  double seconds_partition = 0.0, seconds_solve = 0.0;
  std::size_t num_candidate_faces = 0, num_cells = 0, num_variables = 0, num_constraints = 0;
  int crossings_resolved = 0;  ///< cell-complex: cells relabelled to remove non-manifold "X" edges
  /// cell-complex: the area weight of the labelling kept (below the one asked for when that one
  /// labelled every cell outside).
  double smoothness_used = 0.0;
  /// polyfit: primitives left out to keep the candidate faces within the budget (indices into
  /// the backend's input, least confident first).
  std::vector<std::size_t> dropped_for_budget;
  /// polyfit: how many candidate faces the start solution selected (0: no start given).
  std::size_t start_faces = 0;
  /// polyfit: candidate faces around edges the start may not use, left for the solver to choose.
  std::size_t start_faces_released = 0;
};

struct PolyFitOptions {
  MipSolver solver = MipSolver::Cbc;
  double wt_fitting = 0.43, wt_coverage = 0.15, wt_complexity = 0.30;
  double seconds = 60.0;  ///< budget for the whole backend call
  bool verbose = false;
  /// When the candidate faces exceed this (0: no limit), the least confident primitives with
  /// confidence < 1 are left out until they fit: the MIP grows much faster than the planes.
  std::size_t max_candidate_faces = 0;
  /// Makes the warm start once the budget has chosen the primitives (keep[k]: primitives[k]
  /// stays): a closed solid bounded by (some of) the kept planes, in the same frame, or null for
  /// none. The candidate faces that separate its inside from its outside are given to CBC as a
  /// starting solution, so that a time-out still returns at least that surface. A start made
  /// from every plane is no solution of the program when the budget left one out, and CBC then
  /// has no incumbent at all.
  std::function<const SurfaceMesh*(const std::vector<bool>& keep)> make_start;
};

BackendOutcome runPolyFit(const std::vector<PlanarPrimitive>& primitives, const PolyFitOptions& options,
                          SurfaceMesh& mesh);

struct CellComplexOptions {
  double smoothness = 0.2;
  double extent_margin = 0.02;  ///< in normalised units (diagonal 1)
  bool resolve_crossings = false;  ///< relabel cells to remove non-manifold "X" edges
  double seconds = 60.0;
};

BackendOutcome runCellComplex(const std::vector<PlanarPrimitive>& primitives, const CellComplexOptions& options,
                              SurfaceMesh& mesh);

}  // namespace paco::detail
