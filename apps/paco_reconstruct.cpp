// paco_reconstruct: incomplete point cloud -> watertight polygonal mesh, the whole pipeline:
// segment (stage 1), encode + complete with the learned model (stages 2-3), assemble (stage 4).
//   paco_reconstruct scan.pcd -o part.obj
//   paco_reconstruct scan.ply -o part.off --assembler cell-complex --model my_model.pt
//   paco_reconstruct scan.xyz -o part.obj --no-completion        # the "direct" baseline
#include <torch/torch.h>  // before anything that may pull Qt headers (Qt's `slots` breaks LibTorch)

#include "app_support.h"
#include "fusion_step.h"
#include "thinning_step.h"

#include <paco/assembly/polygonal_assembler.h>
#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/completion/parametric_completer.h>
#include <paco/encoding/completion_model.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>
#include <paco/io/vertex_groups_io.h>
#include <paco/segmentation/planar_segmenter.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <string>

namespace po = boost::program_options;

namespace {

const char kTool[] = "paco_reconstruct";

struct Options {
  std::vector<std::string> inputs;
  std::string output, output_dir, format = "obj", vg_output, pcd_output;
  bool no_completion = false;
  std::string segmenter = "gocopp";
  paco::app::ScanSegmentationFlags scan;
  std::string model;
  paco::app::CompletionFlags completion;
  std::string assembler = "polyfit";
  std::string solver = "cbc";
  double time_limit = 60.0;
  std::size_t max_candidate_faces = paco::PolygonalAssembler::kDefaultMaxCandidateFaces;
  bool no_warm_start = false;
  bool drop_non_finite = false;
  int threads = 0;
};

void printHelp(const po::options_description& visible) {
  std::cout
      << "Usage: " << kTool << " INPUT -o MESH [options]\n"
      << "       " << kTool << " INPUT... --output-dir DIR [--format obj] [options]\n\n"
      << "Turns an incomplete point cloud of a piecewise-planar object (.pcd .ply .xyz .npy, with or\n"
      << "without normals, any units and frame) into a watertight polygonal mesh (.obj .off .ply .stl):\n"
      << "  1. segment the points into planes          (--segmenter)\n"
      << "  2-3. complete the set of planar primitives  (--model; --no-completion skips this)\n"
      << "  4. assemble the primitives into a mesh      (--assembler, --solver, --time-limit)\n"
      << "All outputs are in the input's own frame and units. Besides the mesh it writes the\n"
      << "primitives as PolyFit vertex groups (--vg) and as a PCD coloured by primitive (--pcd).\n"
      << "With --output-dir it reconstructs every INPUT in turn with the model loaded once (each\n"
      << "tool run spends about a second starting LibTorch and loading the model); a scan that\n"
      << "fails is reported and skipped, and the exit code is 1 if any failed.\n\n"
      << visible << std::endl;
}

// What to try after the assembler failed with `status` (empty when nothing in the tool helps).
std::string assemblyAdvice(paco::AssemblyStatus status, const std::string& assembler) {
  const std::string other = assembler == "polyfit" ? "cell-complex" : "polyfit";
  switch (status) {
    case paco::AssemblyStatus::TooFewPlanes:
    case paco::AssemblyStatus::DegeneratePlanes:
      return "the scan's planes do not enclose a volume (a flat object, or one side of one): scan more of the "
             "object's sides, or keep smaller planes with --min-points N";
    case paco::AssemblyStatus::TimeLimit:
      return "raise --time-limit, or use --assembler cell-complex, which needs no solver";
    case paco::AssemblyStatus::SolverFailed:
      return assembler == "polyfit" ? "try --solver glpk, or --assembler cell-complex" : "try --assembler polyfit";
    case paco::AssemblyStatus::EmptySolution:
    case paco::AssemblyStatus::NotWatertight:
      return "try --assembler " + other;
    default:
      return "";
  }
}

std::string defaultSibling(const std::string& mesh_path, const std::string& suffix) {
  const std::filesystem::path p(mesh_path);
  return (p.parent_path() / (p.stem().string() + suffix)).string();
}

// What every scan of a run shares: the settings, and the model loaded once.
struct SharedWork {
  const Options& options;
  paco::app::ScanKnowledge knowledge;  // as given, in the input's frame
  paco::CompletionModel::ConstPtr model;
  paco::HiddenExtentModel::ConstPtr extent_head;
};

// One scan and where its three outputs go.
struct ScanJob {
  std::string input, mesh, vg, pcd;
};

// Segments, completes and assembles one scan, then writes its three outputs together (or none).
void reconstructScan(const SharedWork& shared, const ScanJob& job, paco::app::StageTimer& timer) {
  const Options& o = shared.options;
  auto segmenter = paco::makePlanarSegmenter<pcl::PointNormal>(o.segmenter);
  paco::PolygonalAssembler assembler;
  assembler.setBackend(o.assembler);
  assembler.setMipSolver(o.solver);
  assembler.setTimeLimit(o.time_limit);
  assembler.setMaxCandidateFaces(o.max_candidate_faces);
  assembler.setWarmStart(!o.no_warm_start);
  assembler.setTurnInwardNormals(!o.scan.keep_inward_normals);

  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");
  timer.start("read");
  paco::io::CloudReadOptions read;
  if (o.drop_non_finite) read.non_finite = paco::io::NonFinitePolicy::Drop;
  paco::io::LabelledCloud scan = paco::io::loadCloud(job.input, read);
  timer.stop();
  if (scan.points.empty()) throw paco::InvalidInputError("'" + job.input + "' holds no points");
  std::printf("read '%s': %zu points%s\n", job.input.c_str(), scan.points.size(),
              scan.has_normals ? ", with normals" : " (normals will be estimated)");
  paco::app::reportCoordinateOffset(scan.coordinate_offset);
  paco::app::ScanKnowledge scan_knowledge = shared.knowledge.inWorkingFrame(scan.coordinate_offset);
  // A file without normals reads as zero normals, which the segmenter estimates.
  const auto cloud = o.scan.workingCloudOf(scan.points, timer);

  timer.start("segment");
  paco::PlanarSegmentation segmentation;
  o.scan.configure(*segmenter, cloud->size());
  segmenter->setInputCloud(cloud);
  segmenter->segment(segmentation);
  timer.stop();
  const int parallel_points = segmenter->getUsedMinPointsPerParallelPlane();
  const std::string parallel =
      parallel_points > 0 ? ", parallel to a larger one >= " + std::to_string(parallel_points) : std::string();
  const std::string noisy =
      paco::app::noisyScanNote(segmenter->getDistanceThreshold(), segmenter->getUsedDistanceThreshold());
  const std::string exact =
      paco::app::exactScanNote(segmenter->getMinPointsPerPlane(), segmenter->getUsedMinPointsPerPlane());
  std::printf("segment (%s, planes of >= %d points%s%s%s): %zu planes, coverage %.1f %%\n", o.segmenter.c_str(),
              segmenter->getUsedMinPointsPerPlane(), exact.c_str(), parallel.c_str(), noisy.c_str(),
              segmentation.size(), 100.0 * segmentation.coverage());
  if (segmentation.empty())
    throw paco::InvalidInputError("'" + job.input + "': no planar segment found; is it a piecewise-planar object?");
  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");

  std::vector<paco::PlanarPrimitive> primitives;
  Eigen::Matrix3d box_axes = Eigen::Matrix3d::Identity();  // of the box that closes the hidden side
  if (o.no_completion) {
    primitives = paco::makePrimitives(*cloud, segmentation);
  } else {
    primitives = paco::app::completeScan(shared.model, cloud, segmentation, o.completion.threshold,
                                         o.completion.turns, paco::TurnEnsembleOptions().num_points, timer);
    if (shared.extent_head)
      paco::app::guessHiddenExtent(shared.model, *shared.extent_head, cloud, segmentation, o.completion.turns,
                                   scan_knowledge, timer);
    if (!o.completion.no_fusion)
      box_axes = paco::app::fuseWithSeenFaces(primitives, *cloud, segmentation, o.completion.fusion, scan_knowledge,
                                              timer);
  }
  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");

  if (primitives.empty())  // as a rule only with --no-fusion: fusion keeps the seen faces
    throw paco::InvalidInputError("nothing to assemble: no completed primitive has confidence above --threshold " +
                                  paco::app::shortNumber(o.completion.threshold) + "; lower --threshold" +
                                  (o.completion.no_fusion ? ", or drop --no-fusion to keep the seen faces" : ""));
  timer.start("assemble");
  assembler.setInputPrimitives(primitives);
  paco::SurfaceMesh mesh;
  const paco::AssemblyResult& result = assembler.reconstruct(mesh);
  timer.stop();
  if (result.status == paco::AssemblyStatus::Interrupted) throw paco::InterruptedError(result.message);
  if (!result.ok()) {
    const std::string advice = assemblyAdvice(result.status, o.assembler);
    throw paco::Error("assembly (" + o.assembler + ") failed: " + paco::toString(result.status) +
                      (result.message.empty() ? "" : ": " + result.message) +
                      (advice.empty() ? "" : "; " + advice));
  }
  std::printf("assemble (%s): %zu faces, %zu vertices, %s\n", o.assembler.c_str(), mesh.faces.size(),
              mesh.vertices.size(), result.topology.describe().c_str());
  if (result.turned_inward_normals)
    std::printf("  the primitives' normals faced their middle (%.0f %%) and were turned outwards\n",
                100.0 * result.inward_normal_share);
  if (!result.message.empty()) std::printf("  note: %s\n", result.message.c_str());
  else if (result.hit_time_limit)
    std::printf("  note: the MIP solver stopped at --time-limit %s s with its best solution so far, not proven "
                "optimal; a longer limit may give a better mesh\n",
                paco::app::shortNumber(o.time_limit).c_str());
  if (!o.no_completion && shared.knowledge.empty()) {
    // Along the fill's axes the fill's box lies within the scan's: only the network's guesses reach past it.
    Eigen::AlignedBox3d scan_box;
    for (const auto& p : cloud->points)
      scan_box.extend(Eigen::Vector3d(box_axes.transpose() * p.getVector3fMap().cast<double>()));
    const std::string far =
        paco::app::farReachNote(paco::app::reachBeyondBox(mesh, scan_box, box_axes), scan_box.diagonal().norm());
    if (!far.empty()) std::printf("  note: %s\n", far.c_str());
  }
  if (result.num_merged || result.num_dropped) {
    // Say why primitives were not used, so that a surprising mesh can be traced to its cause.
    std::printf("  %zu of %zu primitives used: %zu merged as near-duplicates, %zu with too few points dropped, "
                "%zu least confident left out for --max-candidate-faces %zu\n",
                result.num_planes_used, result.num_input_planes, result.num_merged, result.num_dropped - result.num_over_budget,
                result.num_over_budget, o.max_candidate_faces);
  }

  // Outputs appear only together and only when complete.
  timer.start("write");
  paco::app::PendingOutput mesh_out(job.mesh), vg_out(job.vg), pcd_out(job.pcd);
  paco::app::moveToFileCoordinates(mesh, scan.coordinate_offset);
  paco::io::saveMesh(mesh_out.writePath(), mesh);
  paco::io::saveVertexGroups(vg_out.writePath(), paco::io::toVertexGroups(primitives, scan.coordinate_offset));
  paco::io::CloudWriteOptions compressed;
  compressed.pcd_encoding = paco::io::PcdEncoding::BinaryCompressed;
  paco::io::saveCloud(pcd_out.writePath(), paco::io::primitivesToCloud(primitives, scan.coordinate_offset), compressed);
  mesh_out.commit();
  vg_out.commit();
  pcd_out.commit();
  timer.stop();
  std::printf("wrote mesh '%s', primitives '%s' and '%s'\n", job.mesh.c_str(), job.vg.c_str(), job.pcd.c_str());
}

// Where each input's outputs go in --output-dir: "<stem>.<format>", "<stem>.vg" and
// "<stem>_primitives.pcd". Two inputs with one stem would overwrite each other: refused.
std::vector<ScanJob> jobsInFolder(const std::vector<std::string>& inputs, const std::string& folder,
                                  const std::string& format) {
  std::vector<ScanJob> jobs;
  std::map<std::string, std::string> input_of_stem;
  for (const std::string& input : inputs) {
    const std::string stem = std::filesystem::path(input).stem().string();
    const auto [it, fresh] = input_of_stem.emplace(stem, input);
    if (!fresh && it->second == input) throw paco::app::UsageError("INPUT '" + input + "' is given twice");
    if (!fresh)
      throw paco::app::UsageError("'" + it->second + "' and '" + input + "' would both be written as '" + stem +
                                  "." + format + "' in --output-dir: rename one, or run them into two folders");
    const std::filesystem::path base = std::filesystem::path(folder) / stem;
    jobs.push_back({input, base.string() + "." + format, base.string() + ".vg", base.string() + "_primitives.pcd"});
  }
  return jobs;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("output,o", po::value(&o.output), "output mesh (.obj, .off, .ply or .stl), for one INPUT")
      ("output-dir", po::value(&o.output_dir),
       "folder for the outputs of one or more INPUTs, each named after its input (created if missing)")
      ("format", po::value(&o.format)->default_value(o.format), "with --output-dir: obj, off, ply or stl")
      ("vg", po::value(&o.vg_output), "primitives as PolyFit vertex groups (default: MESH stem + .vg)")
      ("pcd", po::value(&o.pcd_output), "primitives as a PCD coloured by primitive (default: MESH stem + _primitives.pcd)")
      ("segmenter", po::value(&o.segmenter)->default_value(o.segmenter), "gocopp, region-growing, ransac or efficient-ransac")
      ("model", po::value(&o.model), "model file (default: the shipped model, or $PACO_MODEL)")
      ("no-completion", po::bool_switch(&o.no_completion), "assemble the segments of the input as they are (the direct baseline)")
      ("assembler", po::value(&o.assembler)->default_value(o.assembler), "polyfit or cell-complex")
      ("solver", po::value(&o.solver)->default_value(o.solver), "MIP solver of polyfit: cbc or glpk")
      ("time-limit", po::value(&o.time_limit)->default_value(o.time_limit), "assembly time budget in seconds")
      ("max-candidate-faces", po::value(&o.max_candidate_faces)->default_value(o.max_candidate_faces),
       "polyfit: leave out the least confident unseen primitives until the candidate faces fit (0: no limit)")
      ("no-warm-start", po::bool_switch(&o.no_warm_start), "polyfit: do not start the MIP solver from the cell complex's surface (a time-out then leaves no mesh)")
      ("threads", po::value(&o.threads)->default_value(o.threads), "threads for the network (0: all cores)")
      ("drop-non-finite", po::bool_switch(&o.drop_non_finite), "drop input points with NaN/Inf coordinates (default: fail)");
  o.scan.addTo(visible);
  o.completion.addTo(visible, "use the network's primitives alone (the paper's way); by default seen faces keep "
                              "their fitted planes and points");
  po::options_description all;
  all.add(visible).add_options()("input", po::value(&o.inputs));
  po::positional_options_description positional;
  positional.add("input", -1);
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, all, positional);
  if (vm.count("help")) {
    printHelp(visible);
    return 0;
  }
  if (o.inputs.empty()) throw paco::app::UsageError("expected an INPUT cloud");
  const bool batch = !o.output_dir.empty();
  if (batch && !o.output.empty()) throw paco::app::UsageError("give -o MESH or --output-dir DIR, not both");
  if (!batch && o.output.empty())
    throw paco::app::UsageError(o.inputs.size() == 1 ? "expected -o MESH" : "expected --output-dir DIR for " +
                                                                                std::to_string(o.inputs.size()) +
                                                                                " INPUTs");
  if (o.inputs.size() > 1 && !batch)
    throw paco::app::UsageError("-o names one mesh, but " + std::to_string(o.inputs.size()) +
                                " INPUTs were given: use --output-dir DIR, which names each mesh after its input");
  if (batch && (!o.vg_output.empty() || !o.pcd_output.empty()))
    throw paco::app::UsageError("--vg and --pcd name one scan's outputs: with --output-dir each is named after its input");
  if (!batch && vm.count("format") && !vm["format"].defaulted())
    throw paco::app::UsageError("--format goes with --output-dir; -o takes the format from its extension");
  const paco::app::ScanKnowledge knowledge = o.completion.validate();
  if (!knowledge.empty() && o.no_completion)
    throw paco::app::UsageError("--known-extent, --extent-head, --seen-from and --seen-from-point bound the completed scan: drop "
                                "--no-completion");
  if (o.inputs.size() > 1 && !o.completion.knowledge.known_extent.empty())
    throw paco::app::UsageError("--known-extent says where one object reaches: run each of the " +
                                std::to_string(o.inputs.size()) + " INPUTs on its own with its own extent");
  o.scan.validate();
  paco::app::validateThreads("--threads", o.threads, "all cores");
  if (!(o.time_limit > 0.0))
    throw paco::app::UsageError("--time-limit must be more than 0 seconds, got " + paco::app::shortNumber(o.time_limit));

  std::vector<ScanJob> jobs;
  bool created_output_dir = false;
  if (batch) {
    if (o.format != "obj" && o.format != "off" && o.format != "ply" && o.format != "stl")
      throw paco::app::UsageError("--format must be obj, off, ply or stl, got '" + o.format + "'");
    std::error_code ec;
    if (std::filesystem::exists(o.output_dir, ec) && !std::filesystem::is_directory(o.output_dir, ec))
      throw paco::app::UsageError("--output-dir '" + o.output_dir + "' is a file, not a folder");
    jobs = jobsInFolder(o.inputs, o.output_dir, o.format);
    if (!std::filesystem::exists(o.output_dir, ec)) {
      created_output_dir = std::filesystem::create_directories(o.output_dir, ec);
      if (ec)
        throw paco::app::UsageError("--output-dir '" + o.output_dir + "': cannot create the folder: " + ec.message());
    }
  } else {
    if (o.vg_output.empty()) o.vg_output = defaultSibling(o.output, ".vg");
    if (o.pcd_output.empty()) o.pcd_output = defaultSibling(o.output, "_primitives.pcd");
    jobs.push_back({o.inputs.front(), o.output, o.vg_output, o.pcd_output});
  }
  // Removes the folder this run created when no scan's outputs went into it (an error or Ctrl-C).
  struct EmptyFolderCleanup {
    std::string folder;
    ~EmptyFolderCleanup() {
      std::error_code ec;
      if (!folder.empty() && std::filesystem::is_empty(folder, ec)) std::filesystem::remove(folder, ec);
    }
  } cleanup{created_output_dir ? o.output_dir : std::string()};

  std::vector<paco::app::FileArgument> inputs{{"--model", o.model},
                                              {"--known-extent", o.completion.knowledge.known_extent},
                                              {"--extent-head", o.completion.knowledge.extent_head}},
      outputs;
  // Errors name the option that chose the path.
  const std::string mesh_option = batch ? "--output-dir" : "-o", vg_option = batch ? "--output-dir" : "--vg",
                    pcd_option = batch ? "--output-dir" : "--pcd";
  for (const ScanJob& job : jobs) {
    paco::app::checkOutputPath(job.mesh, mesh_option, {".obj", ".off", ".ply", ".stl"});
    paco::app::checkOutputPath(job.vg, vg_option, {".vg", ".bvg"});
    paco::app::checkOutputPath(job.pcd, pcd_option, {".pcd"});
    inputs.push_back({"INPUT", job.input});
    outputs.push_back({mesh_option, job.mesh});
    outputs.push_back({vg_option, job.vg});
    outputs.push_back({pcd_option, job.pcd});
  }
  paco::app::checkOutputsAreNotInputs(inputs, outputs);

  // Check everything that can be checked before the slow work: names, model file, input file.
  paco::makePlanarSegmenter<pcl::PointNormal>(o.segmenter);
  {
    paco::PolygonalAssembler names_check;
    names_check.setBackend(o.assembler);
    names_check.setMipSolver(o.solver);
  }
  // From here on Ctrl-C stops at the next stage boundary with a message; loading the model comes first.
  paco::InterruptGuard interrupt_guard;
  SharedWork shared{o, knowledge, nullptr, nullptr};
  paco::app::StageTimer run_timer;
  if (!o.no_completion) {
    if (o.model.empty()) o.model = paco::CompletionModel::findShippedModel();
    if (o.model.empty())
      throw paco::ModelError("no model file found: pass --model FILE (train one with paco_train), set "
                             "PACO_MODEL, or run with --no-completion for the direct baseline");
    if (o.threads > 0) paco::CompletionModel::setThreads(o.threads);
    run_timer.start("load model");
    shared.model = paco::CompletionModel::load(o.model);
    shared.extent_head = paco::app::loadExtentHead(knowledge, *shared.model);
    run_timer.stop();
  }

  if (!batch) {
    reconstructScan(shared, jobs.front(), run_timer);
    run_timer.print();
    return 0;
  }

  // Many scans: one that fails is reported and skipped; the others still get their outputs.
  std::vector<std::string> failed;
  std::size_t done = 0;
  std::string interrupted_at;
  const auto started = std::chrono::steady_clock::now();
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    std::string pace;
    if (i > 0)
      pace = ", " + paco::ProgressBar::formatDuration(elapsed / static_cast<double>(i)) + " per scan, about " +
             paco::ProgressBar::formatDuration(elapsed / static_cast<double>(i) * static_cast<double>(jobs.size() - i)) +
             " left";
    std::printf("[%zu/%zu%s] '%s'\n", i + 1, jobs.size(), pace.c_str(), jobs[i].input.c_str());
    std::fflush(stdout);  // before a failure's message on stderr, so that a terminal shows them in order
    paco::app::StageTimer scan_timer;
    try {
      reconstructScan(shared, jobs[i], scan_timer);
      ++done;
      std::printf("  took %.3f s\n", scan_timer.total());
    } catch (const paco::InterruptedError&) {
      interrupted_at = jobs[i].input;
      run_timer.add(scan_timer);
      break;
    } catch (...) {
      failed.push_back(jobs[i].input);
      std::fflush(stdout);
      paco::app::reportCurrentException(kTool, jobs[i].input);
    }
    run_timer.add(scan_timer);
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  const std::size_t finished = done + failed.size();  // an interrupted scan's time counts, not its number
  std::printf("reconstructed %zu of %zu scans into '%s' in %s (%s per scan)\n", done, jobs.size(),
              o.output_dir.c_str(), paco::ProgressBar::formatDuration(elapsed).c_str(),
              paco::ProgressBar::formatDuration(elapsed / static_cast<double>(std::max<std::size_t>(finished, 1))).c_str());
  run_timer.print();
  std::fflush(stdout);
  if (!interrupted_at.empty()) {
    // Ctrl-C: the scans done keep their outputs; the one in flight and the rest have none.
    std::fprintf(stderr, "%s: interrupted at '%s'; it and the %zu scans after it were not written\n", kTool,
                 interrupted_at.c_str(), jobs.size() - done - failed.size() - 1);
    return 130;
  }
  if (failed.empty()) return 0;
  std::string list;
  for (std::size_t i = 0; i < failed.size(); ++i) list += (i ? ", '" : "'") + failed[i] + "'";
  std::fflush(stdout);
  std::fprintf(stderr, "%s: error: %zu of %zu scans failed (their messages are above): %s\n", kTool, failed.size(),
               jobs.size(), list.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  paco::app::exitSkippingTeardown(paco::app::runTool(kTool, [&] { return run(argc, argv); }));
}
