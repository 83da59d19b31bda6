// paco_eval: the paper's metrics (CD, HD, NC, #f, #v) for one predicted mesh against its ground
// truth, or a whole evaluation of methods and assemblers on a dataset split (CSV + tables).
//   paco_eval --pred result.obj --gt part.obj
//   paco_eval --dataset data/mfcad --split val --methods direct,oracle,poisson-qem -o out/eval
#include "app_support.h"
#include "plane_size_options.h"

#include <paco/common/error.h>
#include <paco/common/point_types.h>
#include <paco/common/progress.h>
#include <paco/common/scan_shares.h>
#include <paco/evaluation/benchmark.h>
#include <paco/evaluation/metrics.h>
#include <paco/evaluation/report.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>

#include <boost/algorithm/string.hpp>
#include <boost/program_options.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

namespace po = boost::program_options;
namespace ev = paco::evaluation;

namespace {

const char kTool[] = "paco_eval";

paco::app::FusionFlags fusionFlagsOf(const ev::MethodOptions& method) {
  return {method.align_unseen_degrees, method.clip_margin, method.tilt_margin, method.fill_box_spacing,
          method.unseen_point_fraction, method.contradiction_radius, method.join_distance};
}

struct Options {
  std::string pred, gt, input;
  bool same_seed = false;
  bool score_failure = false;
  std::string dataset, split = "val", methods = "direct,oracle,poisson-qem", assemblers = "polyfit,cell-complex";
  std::string levels = "0,1,2", views = "0", output_dir, failure_box = "bbox", segmenter = "gocopp";
  int segment_min_points = 0;
  int segment_min_parallel_points = 0;
  double segment_noise_adaptation = paco::evaluation::MethodOptions().segment_noise_adaptation;
  std::size_t limit = 0, samples = 10000, qem_faces = 40;
  unsigned jobs = 1;
  double time_limit = 60.0;
  std::size_t max_candidate_faces = paco::evaluation::MethodOptions().max_candidate_faces;
  bool no_warm_start = false;
  double fitting = paco::evaluation::MethodOptions().polyfit_fitting;
  double coverage = paco::evaluation::MethodOptions().polyfit_coverage;
  double complexity = paco::evaluation::MethodOptions().polyfit_complexity;
  bool dataset_labels = false;
  std::size_t max_points = paco::evaluation::MethodOptions().max_input_points;
  bool quiet = false;
  std::string model, completion_frame = "own", observed_fusion = "on";
  // The paco method's defaults, as the library has them.
  paco::app::FusionFlags fusion = fusionFlagsOf(ev::MethodOptions());
  double threshold = ev::MethodOptions().confidence_threshold;
  int turns = ev::MethodOptions().ensemble_turns;
  int threads = 1;
  bool no_normals = false;
  bool known_extent_oracle = false;
  std::string extent_head;
  bool scanner_at_viewpoint = false;
  std::vector<std::string> compare;
};

void printHelp(const po::options_description& visible) {
  std::cout << "Usage:\n"
            << "  " << kTool << " --pred MESH --gt MESH [--input SCAN]  metrics of one mesh\n"
            << "  " << kTool << " --dataset DIR -o OUT_DIR [options]      evaluate methods on a dataset split\n"
            << "  " << kTool << " --compare BEFORE AFTER                  compare two dataset-mode runs case by case\n\n"
            << "Single mode prints CD, HD (both x 100, in the GT's normalised frame of unit bounding-box\n"
            << "diagonal), NC, #f, #v, whether the prediction is a closed solid and its volume / the GT's;\n"
            << "with --input, GT->pred also over the GT surface the scan saw and the surface it did not.\n"
            << "Dataset mode writes OUT_DIR/eval.csv (one row per case; an existing one is resumed: its\n"
            << "cases are skipped) and OUT_DIR/results.md (tables per level and overall). A case fails when\n"
            << "it has no mesh, an empty, open, non-manifold or non-oriented one, runs out of time or\n"
            << "throws; it is then scored as the failure box. Methods: direct, oracle, oracle-seen-hull,\n"
            << "poisson-qem, box-prior, sanity (every case scored as failed), paco (when the learned\n"
            << "stages are built).\n"
            << "--compare reads two eval.csv files (or the folders that hold them) and prints, per method,\n"
            << "assembler and level, the means of CD, HD, NC and NC_prim in each run and the mean of the\n"
            << "paired differences with its standard error, over the cases both runs have.\n"
            << "Available in this build: " << boost::algorithm::join(ev::availableMethods(), ", ") << "\n\n"
            << visible << std::endl;
}

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  boost::algorithm::split(items, text, boost::is_any_of(","), boost::token_compress_on);
  items.erase(std::remove_if(items.begin(), items.end(), [](const std::string& s) { return s.empty(); }), items.end());
  for (auto& s : items) boost::algorithm::trim(s);
  return items;
}

std::vector<int> intList(const std::string& text, const char* option) {
  std::vector<int> values;
  for (const auto& item : splitList(text)) {
    try {
      std::size_t used = 0;
      values.push_back(std::stoi(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw paco::app::UsageError(std::string("--") + option + " takes a comma-separated list of integers, got '" + text + "'");
    }
  }
  if (values.empty()) throw paco::app::UsageError(std::string("--") + option + " is empty");
  return values;
}

ev::FailureBox failureBoxFromName(const std::string& name) {
  if (name == "bbox") return ev::FailureBox::ReferenceBoundingBox;
  if (name == "cube") return ev::FailureBox::UnitDiagonalCube;
  throw paco::app::UsageError("--failure-box must be bbox or cube");
}

paco::SurfaceMesh loadForEvaluation(const std::string& path, const char* what) {
  paco::SurfaceMesh mesh = paco::io::loadMesh(path, /*allow_no_faces=*/true);
  if (mesh.faces.empty())
    throw paco::InvalidInputError(std::string(what) + " mesh '" + path +
                                  "' has no faces; give a polygon mesh (a point cloud cannot be scored)");
  return mesh;
}

// What a failed case scores against this GT (the failure box), and the sampling floor.
int scoreFailure(const Options& o) {
  const paco::SurfaceMesh gt = loadForEvaluation(o.gt, "ground-truth");
  ev::MetricOptions options;
  options.num_samples = o.samples;
  const ev::MeshMetrics f = ev::evaluateFailure(gt, options, failureBoxFromName(o.failure_box));
  const ev::MeshMetrics floor = ev::evaluateMesh(gt, gt, options);
  std::printf("failure: CD=%.4f HD=%.4f NC=%.4f\nfloor: CD=%.4f HD=%.4f NC=%.4f\n", f.chamfer, f.hausdorff,
              f.normal_consistency, floor.chamfer, floor.hausdorff, floor.normal_consistency);
  return 0;
}

int single(const Options& o) {
  paco::app::StageTimer timer;
  timer.start("load");
  const paco::SurfaceMesh pred = loadForEvaluation(o.pred, "predicted");
  const paco::SurfaceMesh gt = loadForEvaluation(o.gt, "ground-truth");
  std::vector<Eigen::Vector3d> seen;
  if (!o.input.empty()) {
    const paco::io::LabelledCloud input = paco::io::loadCloud(o.input);
    if (input.points.empty())
      throw paco::InvalidInputError("input cloud '" + o.input + "' has no points; give the partial scan the mesh was made from");
    seen = paco::positionsOf(input.points);
    for (Eigen::Vector3d& p : seen) p += input.coordinate_offset;  // the meshes' coordinates
  }
  timer.stop();
  ev::MetricOptions options;
  options.num_samples = o.samples;
  if (o.same_seed) options.reference_seed = options.prediction_seed;
  timer.start("evaluate");
  const ev::MeshMetrics m = o.input.empty() ? ev::evaluateMesh(pred, gt, options) : ev::evaluateMesh(pred, gt, seen, options);
  timer.stop();
  const ev::FailureReason reason = ev::classifyMesh(pred);
  std::printf("CD=%.4f (pred->GT %.4f, GT->pred %.4f) HD=%.4f (pred->GT %.4f, GT->pred %.4f) NC=%.4f (pred->GT "
              "%.4f, GT->pred %.4f) #f=%zu #v=%zu closed=%s",
              m.chamfer, m.chamfer_pred_to_gt, m.chamfer_gt_to_pred, m.hausdorff, m.hausdorff_pred_to_gt,
              m.hausdorff_gt_to_pred, m.normal_consistency, m.normal_consistency_pred_to_gt,
              m.normal_consistency_gt_to_pred, m.num_faces, m.num_vertices, m.closed ? "yes" : "no");
  if (!std::isnan(m.volume_ratio)) std::printf(" volume_ratio=%.4f", m.volume_ratio);
  std::printf("\n");
  if (!o.input.empty()) {
    // A GT surface all seen or all hidden has no value for the empty part.
    const auto value = [](double v) {
      char text[32];
      std::snprintf(text, sizeof(text), "%.4f", v);
      return std::isnan(v) ? std::string("none") : std::string(text);
    };
    std::printf("GT->pred over the seen GT surface %s, over the hidden %s (%.1f %% of the GT surface is farther "
                "than %.3g from every input point); its NC over the seen %s, over the hidden %s\n",
                value(m.chamfer_gt_to_pred_seen).c_str(), value(m.chamfer_gt_to_pred_hidden).c_str(),
                100.0 * m.hidden_fraction, options.seen_radius, value(m.normal_consistency_gt_to_pred_seen).c_str(),
                value(m.normal_consistency_gt_to_pred_hidden).c_str());
  }
  if (reason != ev::FailureReason::None) {
    const ev::MeshMetrics f = ev::evaluateFailure(gt, options, failureBoxFromName(o.failure_box));
    std::printf("note: in a dataset evaluation this mesh counts as failed (%s) and scores as the failure box: "
                "CD=%.4f HD=%.4f NC=%.4f\n",
                ev::toString(reason).c_str(), f.chamfer, f.hausdorff, f.normal_consistency);
  }
  if (!o.quiet) timer.print();
  return 0;
}

// An eval.csv, or the folder paco_eval wrote it into.
std::string evaluationCsv(const std::string& path) {
  return std::filesystem::is_directory(path) ? (std::filesystem::path(path) / "eval.csv").string() : path;
}

int compare(const Options& o) {
  if (o.compare.size() != 2)
    throw paco::app::UsageError("--compare takes two runs, BEFORE and AFTER (eval.csv files or the folders that "
                                "hold them), got " + std::to_string(o.compare.size()));
  std::vector<std::vector<ev::EvaluationRecord>> runs;
  for (const auto& given : o.compare) {
    const std::string path = evaluationCsv(given);
    if (!std::filesystem::is_regular_file(path))
      throw paco::IoError("no evaluation results at '" + path + "'; give an eval.csv written by paco_eval --dataset, "
                          "or its output folder");
    std::size_t skipped = 0;
    try {
      runs.push_back(ev::readRecords(path, &skipped));
    } catch (const paco::IoError&) {  // the header is not ours; its message is worded for a resumed run
      throw paco::IoError("'" + path + "' is not an eval.csv of this version of paco_eval (its header differs); give "
                          "the eval.csv of a paco_eval --dataset run");
    }
    if (runs.back().empty())
      throw paco::InvalidInputError("'" + path + "' holds no evaluated case" +
                                    (skipped > 0 ? " (" + std::to_string(skipped) +
                                                       " incomplete or malformed lines skipped: a metric that is not "
                                                       "a number, or a line cut short)"
                                                 : std::string()));
    if (skipped > 0)
      std::fprintf(stderr, "%s: note: skipped %zu incomplete or malformed lines of '%s'\n", kTool, skipped, path.c_str());
  }
  const auto comparisons = ev::comparePaired(runs[0], runs[1]);
  if (comparisons.empty())
    throw paco::InvalidInputError("the two runs have no case in common (the same method, assembler, part, level and "
                                  "view); compare runs of the same dataset and methods");
  std::cout << ev::markdownComparison(comparisons, o.compare[0], o.compare[1]);
  return 0;
}

int dataset(const Options& o) {
  if (o.output_dir.empty()) throw paco::app::UsageError("dataset mode needs an output folder: -o OUT_DIR");
  ev::BenchmarkOptions b;
  b.dataset = o.dataset;
  b.split = o.split;
  b.methods = splitList(o.methods);
  b.assemblers = splitList(o.assemblers);
  b.levels = intList(o.levels, "levels");
  b.views = intList(o.views, "views");
  for (int level : b.levels)
    if (level < 0 || level > 2)
      throw paco::app::UsageError("--levels takes missing levels 0 (25 %), 1 (50 %) and 2 (75 %), got " +
                                  std::to_string(level));
  for (int view : b.views)
    if (view < 0) throw paco::app::UsageError("--views takes view indices >= 0, got " + std::to_string(view));
  paco::app::validateMinPoints(o.segment_min_points);
  paco::app::validateMinParallelPoints(o.segment_min_parallel_points);
  b.limit = o.limit;
  paco::app::validateThreads("--jobs", o.jobs);
  paco::app::validateThreads("--threads", o.threads, "one per hardware thread");
  if (!(o.time_limit > 0.0))
    throw paco::app::UsageError("--time-limit must be more than 0 seconds, got " + paco::app::shortNumber(o.time_limit));
  paco::app::validateNoiseAdaptation(o.segment_noise_adaptation);
  if (o.observed_fusion != "on" && o.observed_fusion != "off")
    throw paco::app::UsageError("--observed-fusion must be on or off, got '" + o.observed_fusion + "'");
  b.jobs = o.jobs;
  b.output_dir = o.output_dir;
  b.progress = !o.quiet;
  b.method.time_limit = o.time_limit;
  b.method.max_candidate_faces = o.max_candidate_faces;
  b.method.polyfit_warm_start = !o.no_warm_start;
  if (!(o.fitting >= 0.0 && o.coverage >= 0.0 && o.complexity >= 0.0) || o.fitting + o.coverage + o.complexity <= 0.0)
    throw paco::app::UsageError("--fitting, --coverage and --complexity must be >= 0 and not all 0");
  b.method.polyfit_fitting = o.fitting;
  b.method.polyfit_coverage = o.coverage;
  b.method.polyfit_complexity = o.complexity;
  b.method.segmenter = o.segmenter;
  b.method.segment_min_points = o.segment_min_points;
  b.method.segment_min_parallel_points = o.segment_min_parallel_points;
  b.method.segment_noise_adaptation = o.segment_noise_adaptation;
  b.method.use_dataset_labels = o.dataset_labels;
  if (o.max_points != 0 && o.max_points < paco::evaluation::kMinInputPointBudget)
    throw paco::app::UsageError("--max-points must be 0 (keep all) or at least " +
                                std::to_string(paco::evaluation::kMinInputPointBudget));
  b.method.max_input_points = o.max_points;
  b.method.qem_target_faces = o.qem_faces;
  b.method.model = o.model;
  b.method.completion_frame = o.completion_frame;
  b.method.confidence_threshold = o.threshold;
  if (o.turns < 1 || o.turns > ev::kMaxEnsembleTurns)
    throw paco::app::UsageError("--turns must be 1 to " + std::to_string(ev::kMaxEnsembleTurns) + ", got " +
                                std::to_string(o.turns));
  b.method.ensemble_turns = o.turns;
  b.method.fuse_observed = o.observed_fusion == "on";
  if (o.known_extent_oracle && !b.method.fuse_observed)
    throw paco::app::UsageError("--known-extent-oracle works through the box fill of observed fusion: drop --observed-fusion off");
  b.method.align_unseen_degrees = o.fusion.align_unseen_degrees;
  b.method.clip_margin = o.fusion.clipMargin();
  b.method.tilt_margin = o.fusion.tiltMargin();
  b.method.fill_box_spacing = o.fusion.fill_box_spacing;
  b.method.unseen_point_fraction = o.fusion.unseen_point_fraction;
  b.method.contradiction_radius = o.fusion.contradiction_radius;
  b.method.join_distance = o.fusion.join_distance;
  b.method.completion_threads = o.threads;
  b.drop_input_normals = o.no_normals;
  b.method.known_extent_oracle = o.known_extent_oracle;
  if (!o.extent_head.empty() && !b.method.fuse_observed)
    throw paco::app::UsageError("--extent-head works through the box fill of observed fusion: drop --observed-fusion off");
  if (!o.extent_head.empty() && o.known_extent_oracle)
    throw paco::app::UsageError("--extent-head guesses the extent that --known-extent-oracle gives: choose one");
  b.method.extent_head = o.extent_head;
  if (o.scanner_at_viewpoint && !b.method.fuse_observed)
    throw paco::app::UsageError("--scanner-at-viewpoint works through observed fusion: drop --observed-fusion off");
  b.method.use_scanner_position = o.scanner_at_viewpoint;
  // A typo here would otherwise fail every case, one by one.
  paco::app::usageErrorIfInvalid([&] { ev::validateMethodOptions(b.method); });
  b.metrics.num_samples = o.samples;
  b.failure_box = failureBoxFromName(o.failure_box);
  paco::InterruptGuard guard;
  const ev::BenchmarkRun run = ev::runBenchmark(b);
  std::printf("%zu cases: %zu evaluated now (%zu failed), %zu already in the CSV", run.cases_total, run.cases_evaluated,
              run.cases_failed, run.cases_resumed);
  if (run.samples_unreadable) std::printf(", %zu unreadable samples", run.samples_unreadable);
  std::printf("\nwrote '%s' and '%s'\n", run.csv_path.c_str(), run.report_path.c_str());
  if (run.interrupted) {
    std::printf("interrupted: run the same command again to resume\n");
    return 130;
  }
  return 0;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("pred", po::value(&o.pred), "single mode: predicted mesh (.obj .off .ply .stl)")
      ("gt", po::value(&o.gt), "single mode: ground-truth mesh")
      ("input", po::value(&o.input),
       "single mode: the partial scan the prediction was made from, in the GT's frame; GT->pred is then also split into the seen and the hidden GT surface")
      ("score-failure", po::bool_switch(&o.score_failure), "with --gt only: print what a failed case scores (the failure box) and the sampling floor (the GT against itself)")
      ("same-seed", po::bool_switch(&o.same_seed), "single mode: sample both meshes with the same seed (a mesh against itself scores exactly 0)")
      ("dataset", po::value(&o.dataset), "dataset mode: folder written by paco_dataset")
      ("compare", po::value(&o.compare)->multitoken(),
       "compare two dataset-mode runs case by case: --compare BEFORE AFTER (eval.csv files or their folders)")
      ("split", po::value(&o.split)->default_value(o.split), "train, val or test")
      ("methods", po::value(&o.methods)->default_value(o.methods), "comma-separated: direct, oracle, oracle-seen-hull, poisson-qem, box-prior, sanity, paco")
      ("assemblers", po::value(&o.assemblers)->default_value(o.assemblers), "comma-separated: polyfit, cell-complex")
      ("levels", po::value(&o.levels)->default_value(o.levels), "missing levels: 0 (25 %), 1 (50 %), 2 (75 %)")
      ("views", po::value(&o.views)->default_value(o.views), "view indices")
      ("limit", po::value(&o.limit)->default_value(o.limit), "at most this many parts (first by name); 0: all")
      ("jobs,j", po::value(&o.jobs)->default_value(o.jobs), "samples evaluated in parallel")
      ("output,o", po::value(&o.output_dir), "dataset mode: output folder (eval.csv, results.md)")
      ("time-limit", po::value(&o.time_limit)->default_value(o.time_limit), "seconds per assembly; past it the case fails as time-limit")
      ("max-candidate-faces", po::value(&o.max_candidate_faces)->default_value(o.max_candidate_faces),
       "polyfit: leave out the least confident predicted primitives until the candidate faces fit (0: no limit)")
      ("no-warm-start", po::bool_switch(&o.no_warm_start), "polyfit: do not start the MIP solver from the cell complex's surface (a time-out then leaves no mesh)")
      ("fitting", po::value(&o.fitting)->default_value(o.fitting, paco::app::shortNumber(o.fitting)),
       "polyfit data-fitting weight (>= 0)")
      ("coverage", po::value(&o.coverage)->default_value(o.coverage, paco::app::shortNumber(o.coverage)),
       "polyfit coverage weight (>= 0)")
      ("complexity", po::value(&o.complexity)->default_value(o.complexity, paco::app::shortNumber(o.complexity)),
       "polyfit complexity weight (>= 0)")
      ("segmenter", po::value(&o.segmenter)->default_value(o.segmenter), "planar segmenter of direct, box-prior and paco");
  // As paco_reconstruct's, in the same words.
  paco::app::addMinPointsOption(visible, o.segment_min_points);
  paco::app::addMinParallelPointsOption(visible, o.segment_min_parallel_points);
  visible.add_options()
      ("dataset-labels", po::bool_switch(&o.dataset_labels), "direct/box-prior: use the dataset's input labels instead of the segmenter")
      ("max-points", po::value(&o.max_points)->default_value(o.max_points),
       "thin denser inputs to about this many evenly spread points first, as paco_reconstruct (0: keep all)")
      ("qem-faces", po::value(&o.qem_faces)->default_value(o.qem_faces), "poisson-qem: triangles after simplification")
      ("model", po::value(&o.model), "paco: model file (default: the shipped model)")
      ("completion-frame", po::value(&o.completion_frame)->default_value(o.completion_frame),
       "paco: own (the input's own box, as for a user's scan) or complete (the complete shape's frame, the paper's protocol)")
      ("threshold", po::value(&o.threshold)->default_value(o.threshold, paco::app::shortNumber(o.threshold)), "paco: keep completed primitives with confidence above this")
      ("turns", po::value(&o.turns)->default_value(o.turns),
       "paco, own frame: run the network on this many 90-degree turns of the input and keep the planes most turns predict (1 to 24; 1: once)")
      ("threads", po::value(&o.threads)->default_value(o.threads), "paco: LibTorch threads")
      ("observed-fusion", po::value(&o.observed_fusion)->default_value(o.observed_fusion),
       "paco: on (seen faces keep their fitted planes and points, the network adds the unseen) or off (the network's primitives alone, as the paper)")
      ("no-normals", po::bool_switch(&o.no_normals), "give the methods the input points without normals (they are estimated)")
      ("known-extent-oracle", po::bool_switch(&o.known_extent_oracle),
       "paco, with fusion: the box fill knows the part's extent from the GT (an oracle: what completion scores when the extent is known)")
      ("extent-head", po::value(&o.extent_head),
       "paco, with fusion: a hidden-extent head for the model (paco_train --extent-head-for); the box fill reaches "
       "as far beyond the scan as it guesses")
      ("scanner-at-viewpoint", po::bool_switch(&o.scanner_at_viewpoint),
       "paco, with fusion: the scanner stood at each sample's viewpoint, as paco_reconstruct --seen-from-point says "
       "(needs a dataset built with --mode visibility --single-scanner)")
      ("samples", po::value(&o.samples)->default_value(o.samples), "points sampled on each mesh")
      ("failure-box", po::value(&o.failure_box)->default_value(o.failure_box), "what a failure scores as: bbox (the GT's normalised bounding box) or cube (diagonal 1)")
      ("quiet,q", po::bool_switch(&o.quiet), "no progress bar or timings");
  paco::app::addNoiseAdaptationOption(visible, o.segment_noise_adaptation);  // direct, box-prior, paco
  o.fusion.addTo(visible);  // paco, with fusion
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, visible, {});
  if (vm.count("help")) {
    printHelp(visible);
    return 0;
  }
  if (o.samples < 1) throw paco::app::UsageError("--samples must be at least 1");
  const bool single_mode = !o.pred.empty() || !o.gt.empty() || !o.input.empty();
  if (single_mode && !o.dataset.empty()) throw paco::app::UsageError("give either --pred/--gt or --dataset, not both");
  if (!o.compare.empty()) {
    if (single_mode || !o.dataset.empty() || o.score_failure)
      throw paco::app::UsageError("--compare reads two finished runs; it takes no --pred, --gt, --input or --dataset");
    return compare(o);
  }
  if (o.score_failure) {
    if (o.gt.empty() || !o.pred.empty() || !o.dataset.empty())
      throw paco::app::UsageError("--score-failure takes --gt MESH only");
    return scoreFailure(o);
  }
  if (single_mode) {
    if (o.pred.empty() || o.gt.empty()) throw paco::app::UsageError("single mode needs both --pred MESH and --gt MESH");
    return single(o);
  }
  if (!o.dataset.empty()) return dataset(o);
  throw paco::app::UsageError("nothing to do: give --pred MESH --gt MESH, or --dataset DIR -o OUT_DIR");
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
