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

#include <cstdio>
#include <filesystem>
#include <iostream>
#include <string>

namespace po = boost::program_options;

namespace {

const char kTool[] = "paco_reconstruct";

struct Options {
  std::string input, output, vg_output, pcd_output;
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
      << "Usage: " << kTool << " INPUT -o MESH [options]\n\n"
      << "Turns an incomplete point cloud of a piecewise-planar object (.pcd .ply .xyz .npy, with or\n"
      << "without normals, any units and frame) into a watertight polygonal mesh (.obj .off .ply .stl):\n"
      << "  1. segment the points into planes          (--segmenter)\n"
      << "  2-3. complete the set of planar primitives  (--model; --no-completion skips this)\n"
      << "  4. assemble the primitives into a mesh      (--assembler, --solver, --time-limit)\n"
      << "All outputs are in the input's own frame and units. Besides the mesh it writes the\n"
      << "primitives as PolyFit vertex groups (--vg) and as a PCD coloured by primitive (--pcd).\n\n"
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

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("output,o", po::value(&o.output), "output mesh (.obj, .off, .ply or .stl)")
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
  all.add(visible).add_options()("input", po::value(&o.input));
  po::positional_options_description positional;
  positional.add("input", 1);
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, all, positional);
  if (vm.count("help")) {
    printHelp(visible);
    return 0;
  }
  if (o.input.empty()) throw paco::app::UsageError("expected an INPUT cloud");
  if (o.output.empty()) throw paco::app::UsageError("expected -o MESH");
  const paco::app::ScanKnowledge knowledge = o.completion.validate();
  if (!knowledge.empty() && o.no_completion)
    throw paco::app::UsageError("--known-extent, --extent-head, --seen-from and --seen-from-point bound the completed scan: drop "
                                "--no-completion");
  o.scan.validate();
  paco::app::validateThreads("--threads", o.threads, "all cores");
  if (!(o.time_limit > 0.0))
    throw paco::app::UsageError("--time-limit must be more than 0 seconds, got " + paco::app::shortNumber(o.time_limit));
  if (o.vg_output.empty()) o.vg_output = defaultSibling(o.output, ".vg");
  if (o.pcd_output.empty()) o.pcd_output = defaultSibling(o.output, "_primitives.pcd");
  paco::app::checkOutputPath(o.output, "-o", {".obj", ".off", ".ply", ".stl"});
  paco::app::checkOutputPath(o.vg_output, "--vg", {".vg", ".bvg"});
  paco::app::checkOutputPath(o.pcd_output, "--pcd", {".pcd"});
  paco::app::checkOutputsAreNotInputs(
      {{"INPUT", o.input}, {"--model", o.model}, {"--known-extent", o.completion.knowledge.known_extent},
       {"--extent-head", o.completion.knowledge.extent_head}},
      {{"-o", o.output}, {"--vg", o.vg_output}, {"--pcd", o.pcd_output}});

  // Check everything that can be checked before the slow work: names, model file, input file.
  auto segmenter = paco::makePlanarSegmenter<pcl::PointNormal>(o.segmenter);
  paco::PolygonalAssembler assembler;
  assembler.setBackend(o.assembler);
  assembler.setMipSolver(o.solver);
  assembler.setTimeLimit(o.time_limit);
  assembler.setMaxCandidateFaces(o.max_candidate_faces);
  assembler.setWarmStart(!o.no_warm_start);
  assembler.setTurnInwardNormals(!o.scan.keep_inward_normals);
  // From here on Ctrl-C stops at the next stage boundary with a message; loading the model comes first.
  paco::InterruptGuard interrupt_guard;
  paco::CompletionModel::ConstPtr model;
  paco::HiddenExtentModel::ConstPtr extent_head;
  paco::app::StageTimer timer;
  if (!o.no_completion) {
    if (o.model.empty()) o.model = paco::CompletionModel::findShippedModel();
    if (o.model.empty())
      throw paco::ModelError("no model file found: pass --model FILE (train one with paco_train), set "
                             "PACO_MODEL, or run with --no-completion for the direct baseline");
    if (o.threads > 0) paco::CompletionModel::setThreads(o.threads);
    timer.start("load model");
    model = paco::CompletionModel::load(o.model);
    extent_head = paco::app::loadExtentHead(knowledge, *model);
    timer.stop();
  }

  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");
  timer.start("read");
  paco::io::CloudReadOptions read;
  if (o.drop_non_finite) read.non_finite = paco::io::NonFinitePolicy::Drop;
  paco::io::LabelledCloud scan = paco::io::loadCloud(o.input, read);
  timer.stop();
  if (scan.points.empty()) throw paco::InvalidInputError("'" + o.input + "' holds no points");
  std::printf("read '%s': %zu points%s\n", o.input.c_str(), scan.points.size(),
              scan.has_normals ? ", with normals" : " (normals will be estimated)");
  paco::app::reportCoordinateOffset(scan.coordinate_offset);
  paco::app::ScanKnowledge scan_knowledge = knowledge.inWorkingFrame(scan.coordinate_offset);
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
    throw paco::InvalidInputError("'" + o.input + "': no planar segment found; is it a piecewise-planar object?");
  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");

  std::vector<paco::PlanarPrimitive> primitives;
  Eigen::Matrix3d box_axes = Eigen::Matrix3d::Identity();  // of the box that closes the hidden side
  if (o.no_completion) {
    primitives = paco::makePrimitives(*cloud, segmentation);
  } else {
    primitives = paco::app::completeScan(model, cloud, segmentation, o.completion.threshold, o.completion.turns,
                                         paco::TurnEnsembleOptions().num_points, timer);
    if (extent_head) paco::app::guessHiddenExtent(model, *extent_head, cloud, segmentation, o.completion.turns,
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
  if (!o.no_completion && knowledge.empty()) {
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
  paco::app::PendingOutput mesh_out(o.output), vg_out(o.vg_output), pcd_out(o.pcd_output);
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
  std::printf("wrote mesh '%s', primitives '%s' and '%s'\n", o.output.c_str(), o.vg_output.c_str(),
              o.pcd_output.c_str());
  timer.print();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
