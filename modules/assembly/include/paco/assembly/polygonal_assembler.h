#pragma once
// Usage:
//   paco::PolygonalAssembler assembler;                 // backend "polyfit" (CGAL + CBC) by default
//   assembler.setInputPrimitives(primitives); assembler.setBackend("cell-complex");
//   pcl::PolygonMesh mesh; if (!assembler.reconstruct(mesh).ok()) std::cerr << assembler.getResult().message;
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>

#include <pcl/PolygonMesh.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace paco {

/// Why a reconstruction succeeded or failed.
enum class AssemblyStatus {
  Success,           ///< a closed, manifold, outward-oriented mesh was produced
  NotRun,            ///< reconstruct() has not been called yet
  EmptyInput,        ///< no primitives, or no inlier points at all
  InvalidInput,      ///< non-finite coordinates or planes
  TooFewPlanes,      ///< fewer than 4 planes left after merging and dropping
  DegeneratePlanes,  ///< the plane normals do not span 3-D (e.g. all parallel): no closed volume
  EmptySolution,     ///< the optimisation selected no face (or no inside cell)
  SolverFailed,      ///< the MIP solver or the geometry kernel failed
  TimeLimit,         ///< the time budget ran out before any solution was found
  Interrupted,       ///< the user pressed Ctrl-C (paco::interruptRequested())
  NotWatertight,     ///< a mesh was produced but it is not closed, manifold and oriented
};

/// Short name of a status, e.g. "too-few-planes".
std::string toString(AssemblyStatus status);

/// The assembly backends shipped with paco.
enum class AssemblyBackend {
  PolyFit,      ///< CGAL Polygonal_surface_reconstruction: candidate faces + binary program (MIP)
  CellComplex,  ///< adaptive binary space partition of the box + inside/outside s-t min-cut
};
/// The MIP solvers the PolyFit backend can use.
enum class MipSolver { Cbc, Glpk };

/// "polyfit" | "cell-complex" (also "cellcomplex", "cell_complex"); throws InvalidInputError.
AssemblyBackend backendFromString(const std::string& name);
std::string toString(AssemblyBackend backend);
/// "cbc" | "glpk"; throws InvalidInputError.
MipSolver mipSolverFromString(const std::string& name);
std::string toString(MipSolver solver);

/// What happened to one input primitive during pre-processing.
struct PrimitiveFate {
  enum Kind { Kept, MergedInto, Dropped } kind = Kept;
  std::size_t target = 0;  ///< for MergedInto: the index (in the input) of the primitive it joined
  std::string reason;      ///< for MergedInto/Dropped: why, e.g. "12 points < minimum support 20"
};

/// Everything reconstruct() learned: the status with a message that says why it failed, what
/// pre-processing did, the solver's outcome and the mesh's topology.
struct AssemblyResult {
  AssemblyStatus status = AssemblyStatus::NotRun;
  std::string message;                 ///< human-readable reason (empty on plain success)
  std::vector<PrimitiveFate> fates;    ///< one per input primitive
  std::size_t num_input_planes = 0;
  std::size_t num_planes_used = 0;     ///< after merging near-duplicates and dropping weak ones
  std::size_t num_merged = 0, num_dropped = 0;
  std::size_t num_over_budget = 0;     ///< polyfit: of num_dropped, left out for the candidate-face budget (with what merged into them)
  bool solution_is_optimal = false;    ///< polyfit: the MIP was solved to optimality
  bool hit_time_limit = false;         ///< the budget ran out (the best solution found was used)
  std::size_t num_candidate_faces = 0; ///< polyfit: candidate faces; cell-complex: cell faces
  std::size_t num_cells = 0;           ///< cell-complex: cells of the partition
  int num_crossings_resolved = 0;      ///< cell-complex: cells relabelled to remove non-manifold "X" edges
  /// cell-complex (and PolyFit's warm start): the area weight the labelling kept was made with. It
  /// is below setSmoothness()'s when that one labelled every cell outside, as when the points
  /// cover little of each face; `message` then says so.
  double smoothness_used = 0.0;
  std::size_t num_variables = 0, num_constraints = 0;  ///< polyfit: size of the MIP
  std::size_t num_warm_start_faces = 0;  ///< polyfit: candidate faces of the cell-complex start (0: none given)
  /// polyfit: shifts of a plane by 5e-5 of the diagonal, made so that no four planes meet in one
  /// point and no three share a line (CGAL's PolyFit forbids every face around such a meeting).
  std::size_t num_planes_separated = 0;
  /// polyfit: start faces around candidate edges that PolyFit's program forbids to the start
  /// (three planes through one line, or four selected faces at an edge), left to the solver.
  std::size_t num_warm_start_faces_released = 0;
  /// polyfit: the solver found no solution (in time, or at all), PolyFit's optimum was the empty
  /// surface, or it passed far (5 % of the diagonal) from a share of the points at least 10 points
  /// of percentage above the start's; the warm start's surface (the cell complex on the same
  /// planes) was returned instead, and `message` says why.
  bool returned_warm_start = false;
  /// The primitives' normals faced the middle of their points as a whole (a room scanned from
  /// inside, normals turned towards a viewpoint inside the object; paco::NormalSides) and every
  /// plane and normal was turned to face out of it (setTurnInwardNormals).
  bool turned_inward_normals = false;
  double inward_normal_share = 0.0;    ///< paco::NormalSides::inwardShare of the primitives' points
  MeshTopology topology;               ///< of the output mesh
  double seconds = 0.0;                ///< wall time of reconstruct()
  double seconds_partition = 0.0;      ///< polyfit: candidate generation; cell-complex: partition
  double seconds_solve = 0.0;          ///< polyfit: the MIP; cell-complex: votes + min-cut + mesh
  bool ok() const { return status == AssemblyStatus::Success; }
};

/// Stage 4 of the pipeline: planar primitives -> a compact, watertight polygonal mesh in the
/// primitives' own frame and units. Shaped like a PCL algorithm: set the input, set parameters,
/// call reconstruct(). reconstruct() validates and pre-processes the input (initCompute), then
/// calls the protected virtual performReconstruction(), then checks and orients the result.
/// Subclass and override performReconstruction() to add a backend.
class PolygonalAssembler {
 public:
  using Ptr = std::shared_ptr<PolygonalAssembler>;
  using ConstPtr = std::shared_ptr<const PolygonalAssembler>;

  PolygonalAssembler();
  virtual ~PolygonalAssembler();

  /// The primitives to assemble: planes plus inlier points with normals (points without normals,
  /// i.e. zero normals, take the plane's). Any frame and unit.
  void setInputPrimitives(std::vector<PlanarPrimitive> primitives);
  /// Convenience: one primitive per segment of `segmentation` of `cloud` (paco::makePrimitives).
  void setInputCloud(const pcl::PointCloud<pcl::PointNormal>& cloud, const PlanarSegmentation& segmentation);
  const std::vector<PlanarPrimitive>& getInputPrimitives() const { return input_; }

  /// Selects the backend by name: "polyfit" (default) or "cell-complex". Throws InvalidInputError.
  void setBackend(const std::string& name) { backend_ = backendFromString(name); }
  void setBackend(AssemblyBackend backend) { backend_ = backend; }
  AssemblyBackend getBackend() const { return backend_; }

  /// PolyFit: MIP solver, "cbc" (default, COIN-OR CBC) or "glpk".
  void setMipSolver(const std::string& name) { solver_ = mipSolverFromString(name); }
  void setMipSolver(MipSolver solver) { solver_ = solver; }
  MipSolver getMipSolver() const { return solver_; }

  /// PolyFit energy weights (each >= 0, not all 0). Defaults 0.43 / 0.15 / 0.30: PolyFit's, but
  /// coverage 0.15 instead of 0.27, measured on 160 tuning parts with the candidates' tight box
  /// (doc/assembly.md).
  void setFittingWeight(double w);     ///< data fitting: rewards faces supported by many points
  void setCoverageWeight(double w);    ///< coverage: penalises face area not covered by points
  void setComplexityWeight(double w);  ///< complexity: penalises sharp edges
  double getFittingWeight() const { return wt_fitting_; }
  double getCoverageWeight() const { return wt_coverage_; }
  double getComplexityWeight() const { return wt_complexity_; }

  /// Time budget of reconstruct() in seconds (> 0; default 60). PolyFit: the MIP solver stops at
  /// the budget left after candidate generation and the best solution found is used (status
  /// TimeLimit when there is none; GLPK keeps no solution). Cell-complex: checked between steps.
  void setTimeLimit(double seconds);
  double getTimeLimit() const { return time_limit_; }

  /// PolyFit: when the candidate faces exceed this many, the least confident primitives with
  /// confidence < 1 (predicted, not observed) are left out until they fit, but never a plane of
  /// the hull (nearly all points on one side: without it PolyFit would cut off a slab); they are
  /// reported as Dropped in getResult().fates. The binary program grows much faster than the number of planes:
  /// CBC solves ~800 candidate faces in a fraction of a second, ~1,300 in seconds and often finds
  /// no solution at all for ~2,000 within a minute. 0: no limit. Default 1000.
  static constexpr std::size_t kDefaultMaxCandidateFaces = 1000;
  void setMaxCandidateFaces(std::size_t faces) { max_candidate_faces_ = faces; }
  std::size_t getMaxCandidateFaces() const { return max_candidate_faces_; }

  /// PolyFit: first assemble with the cell complex (tens of milliseconds) and hand the candidate
  /// faces on its surface to CBC as a starting solution (default true). CBC then has a closed
  /// surface from the start: where it would find no solution within the budget (common with
  /// many small planes) it returns at least that one, and a good bound prunes its search.
  /// The optimum is unchanged. CBC ignores a start that breaks PolyFit's edge rules (rare);
  /// GLPK takes none.
  void setWarmStart(bool warm_start) { warm_start_ = warm_start; }
  bool getWarmStart() const { return warm_start_; }

  /// Both backends read a face's outward side from its plane's normal and its points' normals.
  /// When those face the middle of the points as a whole (paco::NormalSides::faceInwards: a room
  /// scanned from inside), every plane and normal is turned first, so that the mesh is the
  /// volume the faces enclose; AssemblyResult::turned_inward_normals says so. Default true; false
  /// keeps them as given, and the cell complex then takes the space outside the walls as solid.
  void setTurnInwardNormals(bool turn) { turn_inward_normals_ = turn; }
  bool getTurnInwardNormals() const { return turn_inward_normals_; }

  /// Print the MIP solver's own log to stdout (default false: silent).
  void setVerbose(bool verbose) { verbose_ = verbose; }

  /// Pre-processing: two primitives are merged when their planes differ by less than this angle
  /// (radians, unoriented; default 2 degrees) ...
  void setMergeAngle(double radians);
  double getMergeAngle() const { return merge_angle_; }
  /// ... and each one's points lie on average closer than this to the other's plane, as a
  /// fraction of the bounding-box diagonal of all points (default 0.005). 0 disables merging.
  void setMergeDistance(double fraction_of_diagonal);
  double getMergeDistance() const { return merge_distance_; }
  /// Primitives with fewer inlier points than this are dropped (default 10, minimum 3).
  void setMinSupport(std::size_t points);
  std::size_t getMinSupport() const { return min_support_; }

  /// Cell-complex: weight of the surface-area (smoothness) term relative to the point votes,
  /// > 0, default 0.2. Larger closes holes with fewer, larger faces; smaller follows the points.
  /// When it labels every cell outside (points covering little of their faces) it is halved, down
  /// to 1/64, until a solid clear of the bounding box's walls appears (AssemblyResult::smoothness_used).
  void setSmoothness(double beta);
  double getSmoothness() const { return smoothness_; }
  /// Cell-complex: how far a primitive's plane reaches beyond its points when it splits cells,
  /// as a fraction of the bounding-box diagonal (default 0.02). Larger: more cells, more robust
  /// to missing data; 0: only where the points are. When the result is not a closed manifold,
  /// the backend retries with 2x and then 4x this margin.
  void setExtentMargin(double fraction_of_diagonal);
  double getExtentMargin() const { return extent_margin_; }

  /// Runs pre-processing and the backend. On success `mesh` is closed, manifold and oriented with
  /// outward normals, in the input frame and units. On failure `mesh` is cleared, except for
  /// NotWatertight where the (defective) mesh is kept for inspection. The result is also kept
  /// in getResult().
  const AssemblyResult& reconstruct(SurfaceMesh& mesh);
  const AssemblyResult& reconstruct(pcl::PolygonMesh& mesh);
  const AssemblyResult& getResult() const { return result_; }

  /// The primitives after merging and dropping, in the input frame, turned when
  /// AssemblyResult::turned_inward_normals (valid after reconstruct()).
  const std::vector<PlanarPrimitive>& getUsedPrimitives() const { return used_; }

 protected:
  /// Validates the input and pre-processes it into `used_`; on failure sets result_ and returns
  /// false.
  virtual bool initCompute();
  /// The backend. `primitives` are in a normalised frame (centre at the origin, bounding-box
  /// diagonal 1). Fills `mesh` in that frame and sets result_.status (and message) on failure.
  /// The base class checks, welds and orients the mesh afterwards.
  virtual void performReconstruction(const std::vector<PlanarPrimitive>& primitives, SurfaceMesh& mesh);
  /// What reconstruct() does to the backend's mesh (normalised frame): welds vertices (1e-7),
  /// orients faces consistently and outward, merges coplanar faces per planar region, drops
  /// collinear vertices, separates sheets touching along an edge. Returns the topology.
  static MeshTopology postProcess(SurfaceMesh& mesh);
  /// Reads which way the normals of `primitives` face (result_.inward_normal_share) and, unless
  /// setTurnInwardNormals(false), turns every plane and normal when they face inwards as a whole.
  void turnInwardPrimitives(std::vector<PlanarPrimitive>& primitives);
  /// Seconds left of the time budget.
  double secondsLeft() const;
  void fail(AssemblyStatus status, const std::string& message);

  std::vector<PlanarPrimitive> input_;
  std::vector<PlanarPrimitive> used_;
  AssemblyResult result_;
  AssemblyBackend backend_ = AssemblyBackend::PolyFit;
  MipSolver solver_ = MipSolver::Cbc;
  double wt_fitting_ = 0.43, wt_coverage_ = 0.15, wt_complexity_ = 0.30;
  double time_limit_ = 60.0;
  std::size_t max_candidate_faces_ = kDefaultMaxCandidateFaces;
  bool verbose_ = false;
  bool warm_start_ = true;
  bool turn_inward_normals_ = true;
  double merge_angle_;
  double merge_distance_ = 0.005;
  std::size_t min_support_ = 10;
  double smoothness_ = 0.2;
  double extent_margin_ = 0.02;
  double start_time_ = 0.0;
};

/// Merges near-duplicate planes and drops weakly supported primitives (the pre-processing of
/// PolygonalAssembler, usable on its own). Returns the kept primitives (merged ones refitted to
/// the union of their points) and fills `fates` with one entry per input primitive.
/// `merge_distance` is absolute (same unit as the points); `merge_angle` in radians.
std::vector<PlanarPrimitive> mergeAndFilterPrimitives(const std::vector<PlanarPrimitive>& primitives,
                                                      double merge_angle, double merge_distance,
                                                      std::size_t min_support,
                                                      std::vector<PrimitiveFate>* fates = nullptr);

}  // namespace paco
