#include <paco/evaluation/methods.h>

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/point_types.h>
#include <paco/common/normalization.h>

#ifdef PACO_EVALUATION_WITH_ASSEMBLY
#include <paco/assembly/polygonal_assembler.h>
#endif
#ifdef PACO_EVALUATION_WITH_SEGMENTATION
#include <paco/common/normal_sides.h>
#include <paco/segmentation/planar_segmenter.h>
#include <paco/segmentation/thinning.h>
#endif
#ifdef PACO_EVALUATION_WITH_COMPLETION
#include <paco/completion/hidden_extent.h>
#include <paco/completion/observed_fusion.h>
#include <paco/completion/parametric_completer.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/encoding/plane_proxy_encoder.h>
#endif

#include <pcl/kdtree/kdtree_flann.h>

#include <boost/algorithm/string/join.hpp>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <mutex>
#include <sstream>

namespace paco::evaluation {

#ifdef PACO_EVALUATION_WITH_SEGMENTATION
static_assert(kMinInputPointBudget == kMinPointBudget, "the evaluation's budget floor is the thinning's");
static_assert(kDefaultInputPointBudget == kDefaultScanPointBudget, "the evaluation thins as paco_reconstruct");
static_assert(kDefaultNoiseAdaptation == kScanNoiseMultiple, "the evaluation segments as the tools");
#endif

namespace {

void checkCompletionFrame(const std::string& frame) {
  if (frame != "own" && frame != "complete")
    throw InvalidInputError("completion frame '" + frame + "' is not one of: own, complete");
}

// oracle-seen-hull: a GT face counts as seen from this many of its points in the scan on.
constexpr std::size_t kMinSeenOraclePoints = 3;

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Entry {
  MethodFunction function;
  bool uses_assembler = true;
  /// Reads the dataset's label of every input point, so the input reaches it as it is: not
  /// thinned, no repeats left out (runMethod).
  bool reads_input_labels = false;
};

std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}
std::map<std::string, Entry>& registry() {
  static std::map<std::string, Entry> r;
  return r;
}

// Segmentation of the visible points: from the dataset's labels or from a PlanarSegmenter.
[[maybe_unused]] PlanarSegmentation visibleSegmentation(const MethodInput& in, const MethodOptions& options, MethodOutput& out) {
  const auto start = std::chrono::steady_clock::now();
  PlanarSegmentation seg;
  if (options.use_dataset_labels) {
    if (in.input_labels.size() != in.input.size())
      throw InvalidInputError("the sample has " + std::to_string(in.input_labels.size()) + " input labels for " +
                              std::to_string(in.input.size()) + " points; rebuild the dataset");
    seg = PlanarSegmentation::fromLabels(in.input, in.input_labels);
  } else {
#ifdef PACO_EVALUATION_WITH_SEGMENTATION
    auto segmenter = makePlanarSegmenter<pcl::PointNormal>(options.segmenter);
    segmenter->setInputCloud(in.input.makeShared());
    segmenter->setNumberOfThreads(1);
    setScanDefaults(*segmenter, in.input.size(), options.segment_min_points, options.segment_min_parallel_points,
                    options.segment_noise_adaptation);
    segmenter->segment(seg);
#else
    throw InvalidInputError("this build has no paco::segmentation; use the dataset's labels (--dataset-labels)");
#endif
  }
  out.seconds["segment"] = secondsSince(start);
  return seg;
}

[[maybe_unused]] std::vector<PlanarPrimitive> visiblePrimitives(const MethodInput& in, const MethodOptions& options, MethodOutput& out) {
  return makePrimitives(in.input, visibleSegmentation(in, options, out));
}

// One primitive per GT plane (by index), with the GT points labelled with it; some may be empty.
[[maybe_unused]] std::vector<PlanarPrimitive> oraclePrimitivesByPlane(const MethodInput& in) {
  if (in.gt_labels.size() != in.gt_points.size())
    throw InvalidInputError("the sample's GT labels do not match its GT points");
  std::vector<PlanarPrimitive> primitives(in.gt_planes.size());
  for (std::size_t p = 0; p < in.gt_planes.size(); ++p) primitives[p].plane = in.gt_planes[p];
  for (std::size_t i = 0; i < in.gt_points.size(); ++i) {
    const int l = in.gt_labels[i];
    if (l < 0 || static_cast<std::size_t>(l) >= primitives.size()) continue;
    pcl::PointNormal pt = in.gt_points[i];
    const Eigen::Vector3d n = in.gt_planes[static_cast<std::size_t>(l)].normal;
    pt.normal_x = static_cast<float>(n.x());
    pt.normal_y = static_cast<float>(n.y());
    pt.normal_z = static_cast<float>(n.z());
    primitives[static_cast<std::size_t>(l)].points.push_back(pt);
  }
  return primitives;
}

[[maybe_unused]] std::vector<PlanarPrimitive> oraclePrimitives(const MethodInput& in) {
  std::vector<PlanarPrimitive> primitives = oraclePrimitivesByPlane(in);
  primitives.erase(std::remove_if(primitives.begin(), primitives.end(), [](const PlanarPrimitive& p) { return p.points.empty(); }),
                   primitives.end());
  return primitives;
}

// A GT plane is on the part's convex hull when all GT points lie on one side of it.
[[maybe_unused]] bool onConvexHull(const Plane& plane, const pcl::PointCloud<pcl::PointNormal>& gt_points, double tolerance) {
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (const auto& p : gt_points) {
    const double d = plane.signedDistance(p.getVector3fMap().cast<double>());
    lowest = std::min(lowest, d);
    highest = std::max(highest, d);
  }
  return lowest >= -tolerance || highest <= tolerance;
}

// The GT planes of the faces the scan sees and of the GT's convex hull, each with all its GT
// points: a perfect completion of every seen face and of the part's hull that guesses no hidden
// concavity (pocket, step, slot). What a method that infers nothing it cannot see can score.
[[maybe_unused]] std::vector<PlanarPrimitive> seenAndHullOraclePrimitives(const MethodInput& in) {
  if (in.input_labels_from_segmenter)
    throw InvalidInputError("oracle-seen-hull needs the GT face of every input point, and this dataset's input labels "
                            "come from a PlanarSegmenter; build the dataset without --segment");
  if (in.input_labels.size() != in.input.size())
    throw InvalidInputError("oracle-seen-hull needs the GT face of every input point; the sample has " +
                            std::to_string(in.input_labels.size()) + " labels for " + std::to_string(in.input.size()) +
                            " points");
  std::vector<std::size_t> seen(in.gt_planes.size(), 0);
  for (int l : in.input_labels)
    if (l >= 0 && static_cast<std::size_t>(l) < seen.size()) ++seen[static_cast<std::size_t>(l)];
  Eigen::AlignedBox3d box;
  for (const auto& p : in.gt_points) box.extend(p.getVector3fMap().cast<double>());
  // GT points lie on their faces up to float rounding; 1e-4 of the diagonal is far above that
  // and far below any MFCAD feature.
  const double tolerance = 1e-4 * (box.isEmpty() ? 1.0 : box.diagonal().norm());
  std::vector<PlanarPrimitive> all = oraclePrimitivesByPlane(in);
  std::vector<PlanarPrimitive> kept;
  for (std::size_t p = 0; p < all.size(); ++p)
    if (!all[p].points.empty() && (seen[p] >= kMinSeenOraclePoints || onConvexHull(in.gt_planes[p], in.gt_points, tolerance)))
      kept.push_back(std::move(all[p]));
  return kept;
}

// Assembles primitives and fills the output (mesh, status, times).
[[maybe_unused]] void assemble(const std::vector<PlanarPrimitive>& primitives, const MethodOptions& options, MethodOutput& out) {
  out.has_planes = true;
  out.planes.clear();
  for (const auto& p : primitives) out.planes.push_back(p.plane);
#ifdef PACO_EVALUATION_WITH_ASSEMBLY
  PolygonalAssembler assembler;
  assembler.setBackend(options.assembler);
  assembler.setTimeLimit(options.time_limit);
  assembler.setMaxCandidateFaces(options.max_candidate_faces);
  assembler.setWarmStart(options.polyfit_warm_start);
  assembler.setFittingWeight(options.polyfit_fitting);
  assembler.setCoverageWeight(options.polyfit_coverage);
  assembler.setComplexityWeight(options.polyfit_complexity);
  assembler.setInputPrimitives(primitives);
  SurfaceMesh mesh;
  const auto start = std::chrono::steady_clock::now();
  const AssemblyResult& result = assembler.reconstruct(mesh);
  out.seconds["assemble"] = secondsSince(start);
  switch (result.status) {
    case AssemblyStatus::Success:
      out.has_mesh = true;
      out.mesh = std::move(mesh);
      if (!result.message.empty())
        out.message = result.message;
      else if (result.hit_time_limit)
        out.message = "time limit hit; the best solution found was used";
      break;
    case AssemblyStatus::NotWatertight:
      out.has_mesh = true;
      out.mesh = std::move(mesh);
      out.message = result.message;
      break;
    case AssemblyStatus::TimeLimit:
      out.reason = FailureReason::TimeLimit;
      out.message = result.message;
      break;
    case AssemblyStatus::Interrupted:
      throw InterruptedError("assembly interrupted");
    default:
      out.reason = FailureReason::NoMesh;
      out.message = toString(result.status) + ": " + result.message;
      break;
  }
#else
  (void)options;
  throw InvalidInputError("this build has no paco::assembly");
#endif
}

[[maybe_unused]] MethodOutput runDirect(const MethodInput& in, const MethodOptions& options) {
  MethodOutput out;
  assemble(visiblePrimitives(in, options, out), options, out);
  return out;
}

[[maybe_unused]] MethodOutput runOracle(const MethodInput& in, const MethodOptions& options) {
  MethodOutput out;
  assemble(oraclePrimitives(in), options, out);
  return out;
}

[[maybe_unused]] MethodOutput runSeenAndHullOracle(const MethodInput& in, const MethodOptions& options) {
  MethodOutput out;
  assemble(seenAndHullOraclePrimitives(in), options, out);
  return out;
}

[[maybe_unused]] MethodOutput runBoxPrior(const MethodInput& in, const MethodOptions& options) {
  MethodOutput out;
  std::vector<PlanarPrimitive> visible = visiblePrimitives(in, options, out);
  const auto start = std::chrono::steady_clock::now();
  std::vector<PlanarPrimitive> completed =
      addBoundingBoxPrior(in.input, std::move(visible), options.prior_spacing, options.prior_empty_radius);
  out.seconds["prior"] = secondsSince(start);
  assemble(completed, options, out);
  return out;
}

[[maybe_unused]] MethodOutput runPoissonQem(const MethodInput& in, const MethodOptions& options) {
  MethodOutput out;
  out.mesh = reconstructPoissonQem(in.input, options.qem_target_faces, &out.seconds);
  out.has_mesh = !out.mesh.empty();
  if (!out.has_mesh) {
    out.reason = FailureReason::NoMesh;
    out.message = "Poisson reconstruction produced no surface";
  }
  return out;
}

#if defined(PACO_EVALUATION_WITH_COMPLETION) && defined(PACO_EVALUATION_WITH_ASSEMBLY)
// One loaded model per file for the whole run (loading costs far more than one inference).
CompletionModel::ConstPtr cachedModel(const std::string& path, int threads) {
  static std::mutex mutex;
  static std::map<std::string, CompletionModel::ConstPtr> models;
  std::lock_guard<std::mutex> lock(mutex);
  auto& model = models[path];
  if (!model) {
    if (threads > 0) CompletionModel::setThreads(threads);
    model = CompletionModel::load(path);
  }
  return model;
}

// One loaded hidden-extent head per file for the whole run.
HiddenExtentModel::ConstPtr cachedExtentHead(const std::string& path) {
  static std::mutex mutex;
  static std::map<std::string, HiddenExtentModel::ConstPtr> heads;
  std::lock_guard<std::mutex> lock(mutex);
  auto& head = heads[path];
  if (!head) head = HiddenExtentModel::load(path);
  return head;
}

static_assert(kMaxEnsembleTurns == paco::kMaxEnsembleTurns, "evaluation restates the completion module's limit");

MethodOutput runPaco(const MethodInput& in, const MethodOptions& options) {
  checkCompletionFrame(options.completion_frame);
  const std::string path = options.model.empty() ? CompletionModel::findShippedModel() : options.model;
  if (path.empty())
    throw ModelError("the paco method needs a model: none is shipped in this tree; pass --model FILE (paco_train "
                     "writes best.pt)");
  const CompletionModel::ConstPtr model = cachedModel(path, options.completion_threads);
  MethodOutput out;
  const PlanarSegmentation segmentation = visibleSegmentation(in, options, out);
  if (segmentation.empty()) {
    out.reason = FailureReason::NoMesh;
    out.message = "no planar segment in the input";
    return out;
  }
  const auto start = std::chrono::steady_clock::now();
  std::vector<PlanarPrimitive> primitives;
  if (options.completion_frame == "complete") {  // already the complete frame: no own box, no turns
    PlaneProxyEncoder encoder;
    encoder.setModel(model);
    encoder.setInputCloud(in.input.makeShared());
    encoder.setSegmentation(segmentation);
    encoder.setFrame(Normalization{});
    PlaneProxies proxies;
    encoder.encode(proxies);
    ParametricCompleter completer;
    completer.setModel(model);
    completer.setConfidenceThreshold(options.confidence_threshold);
    completer.setInputProxies(proxies);
    completer.complete(primitives);
  } else {
    TurnEnsembleOptions ensemble;
    ensemble.turns = options.ensemble_turns;
    ensemble.threshold = options.confidence_threshold;
    primitives = completeWithTurns(model, in.input.makeShared(), segmentation, ensemble);
  }
  std::vector<Eigen::Vector3d> guessed_extent;
  if (!options.extent_head.empty()) {
    if (!options.fuse_observed)
      throw InvalidInputError("the hidden-extent head works through the box fill of observed fusion; turn fusion on");
    guessed_extent =
        estimateHiddenExtent(model, *cachedExtentHead(options.extent_head), in.input.makeShared(), segmentation,
                             options.completion_frame == "own" ? options.ensemble_turns : 1)
            .corners();
  }
  out.seconds["complete"] = secondsSince(start);
  if (options.fuse_observed) {
    const auto fuse_start = std::chrono::steady_clock::now();
    ObservedFusionOptions fusion;
    fusion.align_unseen_degrees = options.align_unseen_degrees;
    fusion.clip_margin = options.clip_margin;
    fusion.tilt_margin = options.tilt_margin;
    fusion.fill_spacing = options.fill_box_spacing;
    fusion.unseen_point_fraction = options.unseen_point_fraction;
    fusion.contradiction_radius = options.contradiction_radius;
    fusion.join_distance = options.join_distance;
    fusion.known_extent_points = guessed_extent;
    if (options.known_extent_oracle) fusion.known_extent_points = positionsOf(in.gt_points);
    if (options.use_scanner_position) {
      if (!in.scanner_position)
        throw InvalidInputError("the paco method was asked to use the scanner's position, and this input has none");
      fusion.scanner_position = *in.scanner_position;
    }
    primitives = fuseWithObserved(std::move(primitives), makePrimitives(in.input, segmentation), fusion);
    out.seconds["fuse"] = secondsSince(fuse_start);
  }
  if (primitives.empty()) {
    out.reason = FailureReason::NoMesh;
    out.message = "no completed primitive above the confidence threshold";
    return out;
  }
  assemble(primitives, options, out);
  return out;
}
#endif

MethodOutput runSanity(const MethodInput&, const MethodOptions&) {
  MethodOutput out;
  out.reason = FailureReason::Sanity;
  out.message = "every case is scored as the failure box";
  return out;
}

void registerBuiltins(std::map<std::string, Entry>& r) {
  static bool done = false;
  if (done) return;
  done = true;
#ifdef PACO_EVALUATION_WITH_ASSEMBLY
  r.emplace("direct", Entry{runDirect, true});
  r.emplace("oracle", Entry{runOracle, true});
  r.emplace("oracle-seen-hull", Entry{runSeenAndHullOracle, true, true});
  r.emplace("box-prior", Entry{runBoxPrior, true});
#endif
#if defined(PACO_EVALUATION_WITH_COMPLETION) && defined(PACO_EVALUATION_WITH_ASSEMBLY)
  r.emplace("paco", Entry{runPaco, true});
#endif
#ifdef PACO_EVALUATION_WITH_CGAL
  r.emplace("poisson-qem", Entry{runPoissonQem, false});
#endif
  r.emplace("sanity", Entry{runSanity, false});
}

}  // namespace

void registerMethod(const std::string& name, MethodFunction method, bool uses_assembler) {
  std::lock_guard<std::mutex> lock(registryMutex());
  registerBuiltins(registry());
  registry()[name] = Entry{std::move(method), uses_assembler};
}

std::vector<std::string> availableMethods() {
  std::lock_guard<std::mutex> lock(registryMutex());
  registerBuiltins(registry());
  std::vector<std::string> names;
  for (const auto& [name, e] : registry()) names.push_back(name);
  return names;
}

std::vector<std::string> knownMethods() { return {"direct", "oracle", "oracle-seen-hull", "poisson-qem", "box-prior", "paco", "sanity"}; }

bool methodUsesAssembler(const std::string& name) {
  std::lock_guard<std::mutex> lock(registryMutex());
  registerBuiltins(registry());
  auto it = registry().find(name);
  if (it != registry().end()) return it->second.uses_assembler;
  return name != "poisson-qem" && name != "sanity";
}

void validateMethodOptions(const MethodOptions& options) {
#ifdef PACO_EVALUATION_WITH_SEGMENTATION
  makePlanarSegmenter<pcl::PointNormal>(options.segmenter);  // throws, naming the known ones
#endif
  checkCompletionFrame(options.completion_frame);
  if (!(options.confidence_threshold >= 0.0 && options.confidence_threshold <= 1.0)) {
    std::ostringstream threshold;
    threshold << options.confidence_threshold;
    throw InvalidInputError("the confidence threshold must be in [0, 1], got " + threshold.str());
  }
  if (options.qem_target_faces < 4)
    throw InvalidInputError("poisson-qem needs a target of at least 4 faces, got " +
                            std::to_string(options.qem_target_faces));
}

MethodOutput runMethod(const std::string& name, const MethodInput& input, const MethodOptions& options) {
  MethodFunction function;
  bool reads_input_labels = false;
  {
    std::lock_guard<std::mutex> lock(registryMutex());
    registerBuiltins(registry());
    auto it = registry().find(name);
    if (it == registry().end()) {
      std::string why = "method '" + name + "' is not available in this build";
      if (name == "paco") why += ": it needs paco::completion and paco::assembly (the learned stages and the assembler)";
      else if (name == "direct" || name == "oracle" || name == "oracle-seen-hull" || name == "box-prior")
        why += ": it needs paco::assembly (and paco::segmentation)";
      else if (name == "poisson-qem") why += ": it needs CGAL (PACO_WITH_CGAL=ON)";
      else why += "; known methods: " + boost::algorithm::join(knownMethods(), ", ");
      throw InvalidInputError(why);
    }
    function = it->second.function;
    reads_input_labels = it->second.reads_input_labels;
  }
  const auto start = std::chrono::steady_clock::now();
  MethodOutput out;
  try {
#ifdef PACO_EVALUATION_WITH_SEGMENTATION
    // As paco_reconstruct: repeated points left out, dense inputs thinned (not with dataset
    // labels, which name the input's points), and normals that face the middle as a whole turned
    // outwards (which keeps every point). The time counts as the segmentation's.
    pcl::PointCloud<pcl::PointNormal> working;
    const bool points_changed = !options.use_dataset_labels && !reads_input_labels &&
                                prepareScanPoints(input.input, options.max_input_points, working).changed();
    const bool inwards = normalSides(points_changed ? working : input.input).faceInwards();
    if (points_changed || inwards) {
      MethodInput prepared = input;
      if (points_changed) {
        prepared.input = std::move(working);
        prepared.input_labels.clear();
      }
      if (inwards) flipNormals(prepared.input);
      const double preparation_seconds = secondsSince(start);
      out = function(prepared, options);
      out.seconds["segment"] += preparation_seconds;
    } else {
      out = function(input, options);
    }
#else
    out = function(input, options);
#endif
  } catch (const InterruptedError&) {
    throw;
  } catch (const std::exception& e) {
    out = MethodOutput{};
    out.reason = FailureReason::Threw;
    out.message = e.what();
  }
  out.seconds["total"] = secondsSince(start);
  return out;
}

std::vector<PlanarPrimitive> addBoundingBoxPrior(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                                 std::vector<PlanarPrimitive> visible, double spacing,
                                                 double empty_radius) {
  if (cloud.size() < 4) throw InvalidInputError("addBoundingBoxPrior: the cloud needs at least 4 points");
  if (!(spacing > 0.0) || !(empty_radius > 0.0))
    throw InvalidInputError("addBoundingBoxPrior: spacing and empty_radius must be > 0");
  // Oriented bounding box from the principal axes of the points.
  std::vector<Eigen::Vector3d> points;
  points.reserve(cloud.size());
  for (const auto& p : cloud) points.push_back(p.getVector3fMap().cast<double>());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  for (const auto& p : points) covariance += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  Eigen::Matrix3d axes = eigen.eigenvectors();
  // CAD parts: align the box with the dominant visible planes rather than with the principal
  // axes, which tilt by a few degrees whenever the visible part is not symmetric. The largest
  // primitive gives the first axis, the largest one nearly perpendicular to it the second.
  std::vector<std::size_t> by_size(visible.size());
  for (std::size_t i = 0; i < by_size.size(); ++i) by_size[i] = i;
  std::sort(by_size.begin(), by_size.end(),
            [&](std::size_t a, std::size_t b) { return visible[a].points.size() > visible[b].points.size(); });
  if (!by_size.empty()) {
    const Eigen::Vector3d first = visible[by_size[0]].plane.normal.normalized();
    for (std::size_t k = 1; k < by_size.size(); ++k) {
      const Eigen::Vector3d n = visible[by_size[k]].plane.normal.normalized();
      if (std::abs(n.dot(first)) > std::sin(degreesToRadians(10.0))) continue;
      const Eigen::Vector3d second = (n - n.dot(first) * first).normalized();
      axes.col(0) = first;
      axes.col(1) = second;
      axes.col(2) = first.cross(second);
      break;
    }
  }
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
  for (const auto& p : points) {
    const Eigen::Vector3d q = axes.transpose() * (p - centroid);
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const double diagonal = 1.0 / Normalization::fromBoundingBox(points).scale;
  const double step = spacing * diagonal, radius = empty_radius * diagonal;

  pcl::KdTreeFLANN<pcl::PointNormal> tree;
  tree.setInputCloud(cloud.makeShared());
  std::vector<int> index(1);
  std::vector<float> squared(1);
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const Eigen::Vector3d normal = (side ? 1.0 : -1.0) * axes.col(axis);
      const double coordinate = side ? hi[axis] : lo[axis];
      const Eigen::Vector3d on_plane = centroid + axes.col(axis) * coordinate;
      const Plane plane = Plane::fromPointAndNormal(on_plane, normal);
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      pcl::PointCloud<pcl::PointNormal> added;
      const int nu = std::max(1, static_cast<int>(std::ceil((hi[u] - lo[u]) / step)));
      const int nv = std::max(1, static_cast<int>(std::ceil((hi[v] - lo[v]) / step)));
      // Cell centres, not corners: a point on the box's edge lies on an edge between PolyFit's
      // candidate faces, where rounding decides which one counts it (doc/results.md, thirtieth
      // session).
      for (int i = 0; i < nu; ++i) {
        for (int j = 0; j < nv; ++j) {
          Eigen::Vector3d local;
          local[axis] = coordinate;
          local[u] = lo[u] + (hi[u] - lo[u]) * (i + 0.5) / nu;
          local[v] = lo[v] + (hi[v] - lo[v]) * (j + 0.5) / nv;
          const Eigen::Vector3d x = centroid + axes * local;
          pcl::PointNormal pt;
          pt.x = static_cast<float>(x.x());
          pt.y = static_cast<float>(x.y());
          pt.z = static_cast<float>(x.z());
          pt.normal_x = static_cast<float>(normal.x());
          pt.normal_y = static_cast<float>(normal.y());
          pt.normal_z = static_cast<float>(normal.z());
          if (tree.nearestKSearch(pt, 1, index, squared) > 0 && std::sqrt(squared[0]) <= radius) continue;
          added.push_back(pt);
        }
      }
      if (added.empty()) continue;
      // Join a visible primitive on (nearly) the same plane, else add the box face as a new one.
      PlanarPrimitive* host = nullptr;
      for (auto& p : visible) {
        if (p.plane.normal.dot(normal) < std::cos(degreesToRadians(10.0))) continue;
        if (std::abs(p.plane.signedDistance(on_plane)) > 0.02 * diagonal) continue;
        host = &p;
        break;
      }
      if (host) {
        for (auto pt : added) {
          const Eigen::Vector3d projected = host->plane.project(pt.getVector3fMap().cast<double>());
          pt.x = static_cast<float>(projected.x());
          pt.y = static_cast<float>(projected.y());
          pt.z = static_cast<float>(projected.z());
          host->points.push_back(pt);
        }
      } else {
        PlanarPrimitive prior;
        prior.plane = plane;
        prior.points = std::move(added);
        prior.confidence = 0.5f;
        visible.push_back(std::move(prior));
      }
    }
  }
  return visible;
}

}  // namespace paco::evaluation
