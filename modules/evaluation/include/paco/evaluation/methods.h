#pragma once
// Usage:
//   paco::evaluation::MethodInput in; in.input = partial; in.gt_points = ...; in.gt_planes = ...;
//   paco::evaluation::MethodOptions opt; opt.assembler = "cell-complex";
//   paco::evaluation::MethodOutput out = paco::evaluation::runMethod("direct", in, opt);
#include <paco/common/plane.h>
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>
#include <paco/evaluation/report.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstddef>
#include <functional>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace paco::evaluation {

/// What a method sees of one sample (everything in the sample's normalised frame).
struct MethodInput {
  pcl::PointCloud<pcl::PointNormal> input;  ///< the partial scan, with normals
  std::vector<int> input_labels;            ///< per input point: its segment in the dataset (-1 none); may be empty
  /// The dataset's input labels come from a PlanarSegmenter, not from the GT faces of the points
  /// (`paco_dataset --segment`); oracle-seen-hull needs GT faces.
  bool input_labels_from_segmenter = false;
  pcl::PointCloud<pcl::PointNormal> gt_points;  ///< GT surface points (oracle only)
  std::vector<int> gt_labels;               ///< per GT point: index into gt_planes (oracle only)
  std::vector<Plane> gt_planes;             ///< the complete set of GT planes (oracle only)
  /// Where the scanner stood, in the input's frame, when known (a dataset built with
  /// `--mode visibility --single-scanner`); used by paco with MethodOptions::use_scanner_position.
  std::optional<Eigen::Vector3d> scanner_position;
};

/// The smallest MethodOptions::max_input_points other than 0 (paco::kMinPointBudget), and its
/// default (paco::kDefaultScanPointBudget, as paco_reconstruct's).
constexpr std::size_t kMinInputPointBudget = 256;
constexpr std::size_t kDefaultInputPointBudget = 20000;

/// The most test-time turns of `paco` (MethodOptions::ensemble_turns; paco::kMaxEnsembleTurns,
/// restated so that tools built without the completion module can check their options).
constexpr int kMaxEnsembleTurns = 24;
/// The segmenter's default noise adaptation (MethodOptions::segment_noise_adaptation;
/// paco::kScanNoiseMultiple, restated since paco::segmentation is optional here).
constexpr double kDefaultNoiseAdaptation = 2.8;

/// Parameters shared by every method.
struct MethodOptions {
  /// Assembler backend: "polyfit" (PolyFit + CBC, default) or "cell-complex".
  std::string assembler = "polyfit";
  /// Time budget of one assembly or reconstruction, in seconds (> 0; default 60).
  double time_limit = 60.0;
  /// PolyFit candidate-face budget (PolygonalAssembler::setMaxCandidateFaces, whose default this
  /// is; 0: none).
  std::size_t max_candidate_faces = 1000;
  /// PolyFit: start CBC from the cell complex's surface (PolygonalAssembler::setWarmStart, whose
  /// default this is).
  bool polyfit_warm_start = true;
  /// PolyFit's data-fitting, coverage and complexity weights (PolygonalAssembler::setFittingWeight
  /// and the others, whose defaults these are; each >= 0, not all 0).
  double polyfit_fitting = 0.43, polyfit_coverage = 0.15, polyfit_complexity = 0.30;
  /// Planar segmenter backend for the visible points of `direct`, `box-prior` and `paco`
  /// (default "gocopp").
  std::string segmenter = "gocopp";
  /// The segmenter's fewest points per plane (PlanarSegmenter::setMinPointsPerPlane): 0 (default)
  /// for the tools' rule (paco::setScanMinimums: paco::scanMinPointsPerPlane of the input's
  /// points, fewer on an exact scan), as paco_reconstruct, else >= 3 on every scan.
  int segment_min_points = 0;
  /// Smaller planes parallel to a kept one (PlanarSegmenter::setMinPointsPerParallelPlane), as
  /// paco::scanMinPointsPerParallelPlane reads it: 0 (default, as the tools) for
  /// paco::kScanMinParallelPlaneFraction of the input's points; > 0 (>= 3) a count; -1 none.
  int segment_min_parallel_points = 0;
  /// Noise adaptation of the segmenter (PlanarSegmenter::setNoiseAdaptation): on a noisy input ε
  /// widens to this many times the estimated noise; default paco::kScanNoiseMultiple, as the
  /// tools; 0 off.
  double segment_noise_adaptation = kDefaultNoiseAdaptation;
  /// Use the dataset's labels of the input points instead of running the segmenter (default
  /// false). The dataset's labels are GT face labels unless it was built with the segmenter.
  bool use_dataset_labels = false;
  /// Inputs with more points are thinned to about this many (paco::thinToPointBudget), and
  /// repeated points are left out (paco::removeRepeatedPoints), before any method sees them, as
  /// paco_reconstruct does; not with dataset labels, which name the input's points. 0: keep
  /// all, else >= kMinInputPointBudget.
  std::size_t max_input_points = kDefaultInputPointBudget;
  /// poisson-qem: triangles kept by the Garland–Heckbert simplification (default 40, close to the
  /// 39 triangles of the paper's Table 3).
  std::size_t qem_target_faces = 40;
  /// box-prior: spacing of the points sampled on empty parts of the bounding-box faces, and the
  /// distance to the nearest input point beyond which a part counts as empty, both as fractions
  /// of the input's bounding-box diagonal (defaults 0.02 and 0.05).
  double prior_spacing = 0.02;
  double prior_empty_radius = 0.05;
  /// paco: the model file (empty: the shipped one, paco::CompletionModel::findShippedModel()).
  std::string model;
  /// paco: the frame the network sees. "own" (default): the partial input's own bounding box, as
  /// paco_reconstruct does for a user's scan. "complete": the sample's frame, i.e. the complete
  /// shape's box (the paper's protocol, which tells the network where the unseen part ends).
  std::string completion_frame = "own";
  /// paco: keep the completed primitives whose confidence is above this (default 0.7, as
  /// paco::ParametricCompleter and the paper).
  double confidence_threshold = 0.7;
  /// paco: test-time turns of the input (paco::TurnEnsembleOptions::turns, whose default this is;
  /// 1: the network once, as before the fifteenth session).
  int ensemble_turns = 4;
  /// paco: fuse the completed primitives with the observed segments (paco::fuseWithObserved):
  /// seen faces keep their fitted planes and points, the network supplies the unseen ones.
  bool fuse_observed = true;
  /// paco, with fusion: paco::ObservedFusionOptions::align_unseen_degrees (0 = off).
  double align_unseen_degrees = 0.0;
  /// paco, with fusion: paco::ObservedFusionOptions::clip_margin (infinity = off).
  double clip_margin = std::numeric_limits<double>::infinity();
  /// paco, with fusion: paco::ObservedFusionOptions::tilt_margin (infinity = off).
  double tilt_margin = 0.02;
  /// paco, with fusion: paco::ObservedFusionOptions::fill_spacing (0 = off).
  double fill_box_spacing = 0.02;
  /// paco, with fusion: paco::ObservedFusionOptions::unseen_point_fraction (1 = all).
  double unseen_point_fraction = 0.25;
  /// paco, with fusion: paco::ObservedFusionOptions::contradiction_radius (0 = off).
  double contradiction_radius = 0.03;
  /// paco, with fusion: paco::ObservedFusionOptions::join_distance.
  double join_distance = 0.02;
  /// paco, with fusion: give the box fill the GT's points as the object's known extent
  /// (paco::ObservedFusionOptions::known_extent_points). An oracle for analysis: what the
  /// pipeline scores when the part's extent is known (default false).
  bool known_extent_oracle = false;
  /// paco, with fusion: a hidden-extent head file (paco::HiddenExtentModel, trained for `model`);
  /// the box fill reaches as far beyond the scan as it guesses. Empty (default): no head.
  std::string extent_head;
  /// paco, with fusion: drop the completed points that a scanner at MethodInput::scanner_position
  /// would have seen (paco::ObservedFusionOptions::scanner_position), as `paco_reconstruct
  /// --seen-from-point` does (default false).
  bool use_scanner_position = false;
  /// paco: LibTorch threads (process-wide, set when the model is first loaded; default 1, since
  /// the evaluation runs samples in parallel with --jobs).
  int completion_threads = 1;
};

/// What a method produced; runMethod never throws for a failure of the method itself.
struct MethodOutput {
  bool has_mesh = false;     ///< a mesh was produced (it may still be defective)
  SurfaceMesh mesh;          ///< in the sample's normalised frame
  bool has_planes = false;   ///< the method produced planar primitives (for NC_prim)
  std::vector<Plane> planes; ///< the primitives' planes given to the assembler
  FailureReason reason = FailureReason::None;  ///< set when the method failed before a mesh existed
  std::string message;       ///< why it failed (or notes, e.g. "time limit hit, best solution used")
  std::map<std::string, double> seconds;       ///< wall time per stage (names from stageNames())
};

/// A method: input + options -> output. Must not throw for a failed reconstruction; runMethod
/// turns an exception into FailureReason::Threw anyway.
using MethodFunction = std::function<MethodOutput(const MethodInput&, const MethodOptions&)>;

/// Adds (or replaces) a method by name, e.g. the full pipeline "paco" once paco::completion is
/// built: registerMethod("paco", runPaco, true). `uses_assembler`: it is run once per assembler.
void registerMethod(const std::string& name, MethodFunction method, bool uses_assembler);
/// Names of the methods this build can run: direct, oracle, oracle-seen-hull, box-prior (need
/// paco::segmentation and paco::assembly), paco (also needs paco::completion), poisson-qem (needs
/// CGAL), sanity, plus registered ones.
std::vector<std::string> availableMethods();
/// The methods the evaluation knows of, built or not (for messages).
std::vector<std::string> knownMethods();
/// True when the method runs once per assembler; false for poisson-qem and sanity.
bool methodUsesAssembler(const std::string& name);
/// Throws InvalidInputError, saying which option and why, for options no case could run with: an
/// unknown segmenter (or one this build lacks), a completion frame other than own or complete, a
/// confidence threshold outside [0, 1], fewer than 4 poisson-qem faces. runBenchmark calls it
/// first, so that a typo fails at once rather than as a failure in every case.
void validateMethodOptions(const MethodOptions& options);
/// Runs a method; throws InvalidInputError for a name not in availableMethods() (saying what the
/// build lacks), never for a failure of the method (that is in MethodOutput::reason).
MethodOutput runMethod(const std::string& name, const MethodInput& input, const MethodOptions& options);

/// The poisson-qem baseline on its own: normals of `points` estimated (PCA, 18 neighbours) and
/// oriented (minimum spanning tree), CGAL Poisson surface reconstruction, then CGAL
/// Garland–Heckbert edge collapse (plane quadrics) down to `target_faces` triangles. Throws
/// InvalidInputError for fewer than 10 points; returns an empty mesh when Poisson fails.
/// `seconds` receives "reconstruct" and "simplify" times.
SurfaceMesh reconstructPoissonQem(const pcl::PointCloud<pcl::PointNormal>& points, std::size_t target_faces,
                                  std::map<std::string, double>* seconds = nullptr);

/// box-prior's completion on its own: `visible` primitives plus the six planes of the oriented
/// bounding box of `cloud`, with points (the centres of a grid of cells `spacing` wide) sampled on
/// the parts of those faces that have no input point within `empty_radius` (fractions of the
/// cloud's bounding-box diagonal). A box face that
/// coincides with a visible primitive (within 10 degrees and 2 % of the diagonal) adds its points
/// to that primitive instead of a new one.
std::vector<PlanarPrimitive> addBoundingBoxPrior(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                                 std::vector<PlanarPrimitive> visible, double spacing = 0.02,
                                                 double empty_radius = 0.05);

}  // namespace paco::evaluation
