// paco_complete: stages 1-3 of the pipeline. Segments an incomplete point cloud, encodes its
// planes (stage 2) and completes them (stage 3); writes the completed planar primitives.
//   paco_complete scan.ply -o primitives.vg
//   paco_complete scan.pcd -o primitives.bvg --pcd coloured.pcd --model my_model.pt --threshold 0.5
//   paco_complete labelled.pcd -o primitives.vg --use-labels     # skip segmentation
#include <torch/torch.h>  // before anything that may pull Qt headers (Qt's `slots` breaks LibTorch)

#include "app_support.h"
#include "fusion_step.h"
#include "thinning_step.h"

#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/completion/parametric_completer.h>
#include <paco/encoding/completion_model.h>
#include <paco/io/cloud_io.h>
#include <paco/io/vertex_groups_io.h>
#include <paco/segmentation/segmentation.h>

#include <boost/program_options.hpp>

#include <cstdio>
#include <iostream>
#include <memory>
#include <string>

namespace po = boost::program_options;

namespace {

const char kTool[] = "paco_complete";

// File-scope defaults, shown by --help.
struct Options {
  std::string input, output, pcd, model;
  std::string segmenter = "gocopp";
  double epsilon = 0.004;
  paco::app::ScanSegmentationFlags scan;
  paco::app::CompletionFlags completion;
  int threads = 0;
  int points = 2048;
  bool use_labels = false;
  bool drop_non_finite = false;
};

void printHelp(const po::options_description& visible) {
  std::cout
      << "Usage: " << kTool << " INPUT -o PRIMITIVES.vg [--pcd COLOURED.pcd] [--model FILE] [options]\n\n"
      << "Completes the planar primitives of an incomplete point cloud of a piecewise-planar object\n"
      << "(.pcd .ply .xyz .npy .vg .bvg): segments it into planes (--segmenter; or takes the file's\n"
      << "labels with --use-labels), encodes the planes with the learned model and predicts every\n"
      << "plane of the complete surface with points on it. Writes the primitives whose confidence\n"
      << "exceeds --threshold as PolyFit/Easy3D vertex groups (.vg ascii, .bvg binary; the\n"
      << "confidence is in each group's label) and, with --pcd, their points with a colour and a\n"
      << "label per primitive. Results are in the input's frame and units. Stops before assembly:\n"
      << "paco_assemble (or paco_reconstruct for all stages) makes the mesh.\n\n"
      << visible << std::endl;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("output,o", po::value(&o.output), "completed primitives to write (.vg or .bvg)")
      ("pcd", po::value(&o.pcd), "also write the primitives' points, coloured and labelled (.pcd)")
      ("model", po::value(&o.model), "model file (default: the shipped model, or $PACO_MODEL)")
      ("segmenter", po::value(&o.segmenter)->default_value(o.segmenter), "gocopp, region-growing, ransac or efficient-ransac")
      ("epsilon,e", po::value(&o.epsilon)->default_value(o.epsilon, "0.004"), "segmentation inlier distance, fraction of the bounding-box diagonal")
      ("use-labels", po::bool_switch(&o.use_labels), "use the input file's labels as the segmentation (no segmenter)")
      ("points", po::value(&o.points)->default_value(o.points), "points fed to the network (the training size)")
      ("threads", po::value(&o.threads)->default_value(o.threads), "LibTorch threads (0: one per hardware thread)")
      ("drop-non-finite", po::bool_switch(&o.drop_non_finite), "drop NaN/Inf points instead of failing");
  o.scan.addTo(visible);
  o.completion.addTo(visible, "write the network's primitives alone (the paper's way); by default seen faces keep "
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
  if (o.input.empty()) throw paco::app::UsageError("expected an INPUT point cloud");
  if (o.output.empty()) throw paco::app::UsageError("expected -o PRIMITIVES.vg");
  paco::app::checkOutputPath(o.output, "-o", {".vg", ".bvg"});
  if (!o.pcd.empty()) paco::app::checkOutputPath(o.pcd, "--pcd", {".pcd"});
  paco::app::checkOutputsAreNotInputs(
      {{"INPUT", o.input}, {"--model", o.model}, {"--known-extent", o.completion.knowledge.known_extent},
       {"--extent-head", o.completion.knowledge.extent_head}},
      {{"-o", o.output}, {"--pcd", o.pcd}});
  const paco::app::ScanKnowledge knowledge = o.completion.validate();
  o.scan.validate();
  paco::app::validateThreads("--threads", o.threads, "one per hardware thread");
  if (!(o.epsilon > 0.0 && o.epsilon < 1.0))
    throw paco::app::UsageError("--epsilon must be in (0, 1) (a fraction of the bounding-box diagonal), got " +
                                paco::app::shortNumber(o.epsilon));
  // The network was trained on 2,048 points: many more only cost memory (2e9 took all 24 GB).
  constexpr int kMaxNetworkPoints = 65536;
  if (o.points < 1 || o.points > kMaxNetworkPoints)
    throw paco::app::UsageError("--points must be 1 to " + std::to_string(kMaxNetworkPoints) +
                                " (the shipped model was trained on 2048), got " + std::to_string(o.points));

  // Check everything that can be checked before the slow work: names, model file, input file.
  paco::PlanarSegmenter<pcl::PointNormal>::Ptr segmenter;
  if (!o.use_labels) {
    paco::app::usageErrorIfInvalid([&] {
      segmenter = paco::makePlanarSegmenter<pcl::PointNormal>(o.segmenter);
      segmenter->setDistanceThreshold(o.epsilon);
    });
  }
  if (o.model.empty()) o.model = paco::CompletionModel::findShippedModel();
  if (o.model.empty())
    throw paco::ModelError("no model file found: pass --model FILE (train one with paco_train) or "
                           "set PACO_MODEL");
  // From here on Ctrl-C stops at the next stage boundary with a message; loading the model comes first.
  paco::InterruptGuard interrupt_guard;
  paco::app::StageTimer timer;
  if (o.threads > 0) paco::CompletionModel::setThreads(o.threads);
  timer.start("load model");
  const auto model = paco::CompletionModel::load(o.model);
  const auto extent_head = paco::app::loadExtentHead(knowledge, *model);
  timer.stop();
  std::printf("model '%s': preset %s, %.2f M parameters\n", o.model.c_str(),
              model->config().name.c_str(), model->parameterCount() / 1e6);
  // The encoder groups the points around the model's centres: it needs at least one point each.
  if (o.points < model->config().num_centres)
    throw paco::app::UsageError("--points must be at least " + std::to_string(model->config().num_centres) +
                                " (the model's centres), got " + std::to_string(o.points));

  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");
  timer.start("read");
  paco::io::CloudReadOptions read;
  if (o.drop_non_finite) read.non_finite = paco::io::NonFinitePolicy::Drop;
  paco::io::LabelledCloud scan = paco::io::loadCloud(o.input, read);
  timer.stop();
  if (scan.points.empty()) throw paco::InvalidInputError("'" + o.input + "' holds no points");
  std::printf("read '%s': %zu points%s\n", o.input.c_str(), scan.points.size(),
              scan.has_normals ? ", with normals" : "");
  paco::app::reportCoordinateOffset(scan.coordinate_offset);
  paco::app::ScanKnowledge scan_knowledge = knowledge.inWorkingFrame(scan.coordinate_offset);
  // Labels name input points, so a labelled input keeps every point, in order.
  std::shared_ptr<pcl::PointCloud<pcl::PointNormal>> cloud;
  if (o.use_labels) {
    cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>(scan.points);
    paco::app::reportNormalSides(paco::app::turnInwardNormals(*cloud, o.scan.keep_inward_normals));
  } else {
    cloud = o.scan.workingCloudOf(scan.points, timer);
  }

  paco::PlanarSegmentation segmentation;
  timer.start("segment");
  if (o.use_labels) {
    if (!scan.hasLabels())
      throw paco::InvalidInputError("'" + o.input + "' has no labels; drop --use-labels to segment it");
    segmentation = paco::app::segmentationFromLabels(scan, o.input);
  } else {
    o.scan.configure(*segmenter, cloud->size());
    segmenter->setInputCloud(cloud);
    segmenter->segment(segmentation);
  }
  timer.stop();
  const std::string noisy =
      o.use_labels ? std::string()
                   : paco::app::noisyScanNote(segmenter->getDistanceThreshold(), segmenter->getUsedDistanceThreshold());
  std::printf("segment (%s%s): %zu planes, coverage %.1f %%\n", o.use_labels ? "input labels" : o.segmenter.c_str(),
              noisy.c_str(), segmentation.size(), 100.0 * segmentation.coverage());
  if (segmentation.empty())
    throw paco::InvalidInputError(
        "'" + o.input + "': " +
        (o.use_labels ? std::string("no point has a plane's label (labels below 0 mean none); drop --use-labels to "
                                    "segment the points")
                      : std::string("no planar segment found; is it a piecewise-planar object?")));
  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");

  std::vector<paco::PlanarPrimitive> primitives =
      paco::app::completeScan(model, cloud, segmentation, o.completion.threshold, o.completion.turns, o.points, timer);
  if (extent_head) paco::app::guessHiddenExtent(model, *extent_head, cloud, segmentation, o.completion.turns,
                                                   scan_knowledge, timer);
  if (!o.completion.no_fusion)
    paco::app::fuseWithSeenFaces(primitives, *cloud, segmentation, o.completion.fusion, scan_knowledge, timer);
  if (primitives.empty())
    std::fprintf(stderr, "%s: warning: no primitive is above the threshold; try a lower --threshold\n",
                 kTool);
  if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");

  // Outputs appear only together and only when complete.
  timer.start("write");
  paco::app::PendingOutput vg_out(o.output);
  std::unique_ptr<paco::app::PendingOutput> pcd_out;
  if (!o.pcd.empty()) pcd_out = std::make_unique<paco::app::PendingOutput>(o.pcd);
  paco::io::saveVertexGroups(vg_out.writePath(), paco::io::toVertexGroups(primitives, scan.coordinate_offset));
  if (pcd_out) paco::io::saveCloud(pcd_out->writePath(), paco::io::primitivesToCloud(primitives, scan.coordinate_offset));
  vg_out.commit();
  if (pcd_out) pcd_out->commit();
  timer.stop();
  std::printf("wrote '%s'%s%s\n", o.output.c_str(), o.pcd.empty() ? "" : " and ", o.pcd.c_str());
  timer.print();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  paco::app::exitSkippingTeardown(paco::app::runTool(kTool, [&] { return run(argc, argv); }));
}
