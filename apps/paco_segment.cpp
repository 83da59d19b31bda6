// paco_segment: stage 1 on its own. Groups a point cloud into planar segments and writes a
// labelled PCD (field "label", -1 for no plane) and, optionally, PolyFit/Easy3D vertex groups.
//   paco_segment scan.ply -o labelled.pcd --vg planes.vg
//   paco_segment scan.xyz -o labelled.pcd --backend ransac --epsilon 0.01
#include "app_support.h"
#include "thinning_step.h"

#include <paco/common/error.h>
#include <paco/io/cloud_io.h>
#include <paco/io/vertex_groups_io.h>
#include <paco/common/progress.h>
#include <paco/segmentation/segmentation.h>
#include <paco/segmentation/thinning.h>

#include <boost/program_options.hpp>

#include <cstdio>
#include <iostream>
#include <limits>
#include <memory>
#include <string>
#include <utility>

namespace po = boost::program_options;

namespace {

const char kTool[] = "paco_segment";

// File-scope defaults, shown by --help.
struct Options {
  std::string input, output, vg;
  std::string backend = "gocopp";
  double epsilon = 0.004;
  double normal_threshold = 0.85;
  int min_points = 50;
  int min_parallel_points = 0;
  int neighbours = 20;
  // The class's default (off); paco_reconstruct and paco_complete widen by kScanNoiseMultiple.
  double noise_adaptation = 0.0;
  unsigned int threads = 0;
  bool ignore_normals = false;
  bool keep_inward_normals = false;
  // Above this many points a thinned copy is segmented and every point labelled from it:
  // segmenting 1 million points took 29 s, 10 million more than 2 minutes.
  std::size_t max_points = 1000000;
  // gocopp
  double lambda_simplicity = 1.0;
  double lambda_completeness = 1.0;
  int max_rounds = 7;
  // region-growing
  double curvature = 0.05;
  // ransac
  int max_iterations = 1000;
  // efficient-ransac
  double probability = 0.01;
  double cluster_epsilon = 0.0;
};

void printHelp(const po::options_description& visible) {
  std::string backends;
  for (const auto& name : paco::availablePlanarSegmenters()) backends += (backends.empty() ? "" : ", ") + name;
  std::cout << "Usage: " << kTool << " INPUT -o LABELLED.pcd [--vg PLANES.vg] [--backend NAME] [options]\n\n"
            << "Groups a point cloud (.pcd .ply .xyz .npy .vg .bvg) into planar segments. Writes the cloud\n"
            << "with a per-point \"label\" field (-1: no plane) and, with --vg, the planes and their point\n"
            << "groups for PolyFit / Easy3D (.vg ascii, .bvg binary). Distances are fractions of the\n"
            << "bounding-box diagonal, so the same settings work in any unit. Points with NaN/Inf\n"
            << "coordinates are dropped with a warning; missing normals are estimated; given normals that\n"
            << "face the scan's middle as a whole (a room scanned from inside) are turned outwards, as the\n"
            << "other tools do, and written so (--keep-inward-normals keeps them). On a noisy scan,\n"
            << "--noise-adaptation " << paco::app::shortNumber(paco::kScanNoiseMultiple)
            << " widens --epsilon to the noise, as paco_reconstruct does by default.\n\n"
            << "Backends: " << backends << " (default gocopp).\n\n"
            << visible << std::endl;
}

template <typename Segmenter>
Segmenter* as(const paco::PlanarSegmenter<pcl::PointNormal>::Ptr& segmenter) {
  return dynamic_cast<Segmenter*>(segmenter.get());
}

// The segmenters' ranges, checked here to name the options.
void validateOptions(const Options& o) {
  using paco::app::shortNumber;
  using paco::app::UsageError;
  const auto fraction = [](const char* option, double value, bool zero_allowed) {
    if (!((zero_allowed ? value >= 0.0 : value > 0.0) && value < 1.0))
      throw UsageError(std::string(option) + " must be in " + (zero_allowed ? "[0, 1)" : "(0, 1)") +
                       " (a fraction of the bounding-box diagonal), got " + shortNumber(value));
  };
  fraction("--epsilon", o.epsilon, false);
  fraction("--cluster-epsilon", o.cluster_epsilon, true);
  if (!(o.normal_threshold >= 0.0 && o.normal_threshold <= 1.0))
    throw UsageError("--normal-threshold must be in [0, 1] (a |cosine|), got " + shortNumber(o.normal_threshold));
  if (o.min_points < 3) throw UsageError("--min-points must be at least 3, got " + std::to_string(o.min_points));
  if (o.min_parallel_points != 0 && o.min_parallel_points < 3)
    throw UsageError("--min-parallel-points must be 0 (none) or at least 3, got " +
                     std::to_string(o.min_parallel_points));
  if (o.neighbours < 3) throw UsageError("--neighbours must be at least 3, got " + std::to_string(o.neighbours));
  paco::app::validateThreads("--threads", o.threads, "all cores");
  paco::app::validateNoiseAdaptation(o.noise_adaptation);
  for (const auto& [option, lambda] : {std::pair<const char*, double>{"--lambda-simplicity", o.lambda_simplicity},
                                       {"--lambda-completeness", o.lambda_completeness}})
    if (!(lambda >= 0.0 && lambda < 3.0))
      throw UsageError(std::string(option) + " must be in [0, 3), got " + shortNumber(lambda));
  if (o.max_rounds < 0) throw UsageError("--max-rounds must be >= 0, got " + std::to_string(o.max_rounds));
  if (o.max_points != 0 && o.max_points < paco::kMinPointBudget)
    throw UsageError("--max-points must be 0 (every point) or at least " + std::to_string(paco::kMinPointBudget) +
                     ", got " + std::to_string(o.max_points));
  if (!(o.curvature >= 0.0 && o.curvature <= 1.0 / 3.0))
    throw UsageError("--curvature must be in [0, 1/3] (a surface variation), got " + shortNumber(o.curvature));
  if (o.max_iterations < 1)
    throw UsageError("--max-iterations must be at least 1, got " + std::to_string(o.max_iterations));
  if (!(o.probability > 0.0 && o.probability < 1.0))
    throw UsageError("--probability must be in (0, 1), got " + shortNumber(o.probability));
}

paco::PlanarSegmenter<pcl::PointNormal>::Ptr makeSegmenter(const Options& o) {
  auto segmenter = paco::makePlanarSegmenter<pcl::PointNormal>(o.backend);
  segmenter->setDistanceThreshold(o.epsilon);
  segmenter->setNormalThreshold(o.normal_threshold);
  segmenter->setMinPointsPerPlane(o.min_points);
  segmenter->setMinPointsPerParallelPlane(o.min_parallel_points);
  segmenter->setNumberOfNeighbours(o.neighbours);
  segmenter->setNumberOfThreads(o.threads);
  segmenter->setNoiseAdaptation(o.noise_adaptation);
  if (auto* g = as<paco::GoCoPPSegmenter<pcl::PointNormal>>(segmenter)) {
    g->setLambdaSimplicity(o.lambda_simplicity);
    g->setLambdaCompleteness(o.lambda_completeness);
    g->setMaxRounds(o.max_rounds);
  } else if (auto* r = as<paco::RegionGrowingSegmenter<pcl::PointNormal>>(segmenter)) {
    r->setCurvatureThreshold(o.curvature);
  } else if (auto* s = as<paco::RansacSegmenter<pcl::PointNormal>>(segmenter)) {
    s->setMaxIterations(o.max_iterations);
  } else if (auto* e = as<paco::EfficientRansacSegmenter<pcl::PointNormal>>(segmenter)) {
    e->setProbability(o.probability);
    e->setClusterEpsilon(o.cluster_epsilon);
  }
  return segmenter;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description general("Options");
  general.add_options()
      ("help,h", "print this help")
      ("output,o", po::value(&o.output), "labelled point cloud to write (.pcd; .ply .xyz .npy also work)")
      ("vg", po::value(&o.vg), "also write the planes and groups as vertex groups (.vg or .bvg)")
      ("backend,b", po::value(&o.backend)->default_value(o.backend), "gocopp, region-growing, ransac or efficient-ransac")
      ("epsilon,e", po::value(&o.epsilon)->default_value(o.epsilon, "0.004"), "inlier distance to a plane, fraction of the bounding-box diagonal")
      ("normal-threshold", po::value(&o.normal_threshold)->default_value(o.normal_threshold, "0.85"), "min |cos| between a point normal and its plane normal")
      ("min-points", po::value(&o.min_points)->default_value(o.min_points), "fewest points of a plane")
      ("min-parallel-points", po::value(&o.min_parallel_points)->default_value(o.min_parallel_points),
       "fewest points of a plane parallel to a larger one (0: none, else >= 3)")
      ("neighbours,k", po::value(&o.neighbours)->default_value(o.neighbours), "neighbours for normal estimation and region growing")
      ("threads", po::value(&o.threads)->default_value(o.threads), "threads for normal estimation, and for labelling above --max-points (0: all cores)")
      ("ignore-normals", po::bool_switch(&o.ignore_normals), "estimate normals even when the file has them")
      ("max-points", po::value(&o.max_points)->default_value(o.max_points),
       "segment a thinned copy of a larger cloud (evenly spread points) and give every point the label of the "
       "nearest of its 8 nearest kept points whose plane it lies within the inlier distance of; 0: segment every "
       "point");
  paco::app::addNoiseAdaptationOption(general, o.noise_adaptation);
  paco::app::addKeepInwardNormalsOption(general, o.keep_inward_normals);
  po::options_description gocopp("gocopp options");
  gocopp.add_options()
      ("lambda-simplicity", po::value(&o.lambda_simplicity)->default_value(o.lambda_simplicity, "1"), "weight of the number of planes, [0, 3)")
      ("lambda-completeness", po::value(&o.lambda_completeness)->default_value(o.lambda_completeness, "1"), "weight of the unassigned points, [0, 3)")
      ("max-rounds", po::value(&o.max_rounds)->default_value(o.max_rounds), "rounds of merge/split/insert/exclude/transfer at most");
  po::options_description growing("region-growing options");
  growing.add_options()
      ("curvature", po::value(&o.curvature)->default_value(o.curvature, "0.05"), "max curvature of a seed point, [0, 1/3]");
  po::options_description ransac("ransac options");
  ransac.add_options()
      ("max-iterations", po::value(&o.max_iterations)->default_value(o.max_iterations), "RANSAC iterations per plane");
  po::options_description efficient("efficient-ransac options");
  efficient.add_options()
      ("probability", po::value(&o.probability)->default_value(o.probability, "0.01"), "probability to miss the largest plane, (0, 1)")
      ("cluster-epsilon", po::value(&o.cluster_epsilon)->default_value(o.cluster_epsilon, "0"), "max gap inside a plane, fraction of the diagonal (0: 3 x mean spacing)");
  po::options_description visible;
  visible.add(general).add(gocopp).add(growing).add(ransac).add(efficient);
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
  if (o.output.empty()) throw paco::app::UsageError("expected -o LABELLED.pcd");
  paco::app::checkOutputPath(o.output, "-o", {".pcd", ".ply", ".xyz", ".npy", ".vg", ".bvg"});
  if (!o.vg.empty()) paco::app::checkOutputPath(o.vg, "--vg", {".vg", ".bvg"});
  paco::app::checkOutputsAreNotInputs({{"INPUT", o.input}}, {{"-o", o.output}, {"--vg", o.vg}});
  // Check every parameter before reading a large file.
  validateOptions(o);
  const paco::PlanarSegmenter<pcl::PointNormal>::Ptr segmenter =
      paco::app::usageErrorIfInvalid([&] { return makeSegmenter(o); });
  paco::app::PendingOutput labelled_output(o.output);
  std::unique_ptr<paco::app::PendingOutput> vg_output;
  if (!o.vg.empty()) vg_output = std::make_unique<paco::app::PendingOutput>(o.vg);

  paco::app::StageTimer timer;
  timer.start("load");
  paco::io::CloudReadOptions read;
  read.non_finite = paco::io::NonFinitePolicy::Drop;
  paco::io::LabelledCloud cloud = paco::io::loadCloud(o.input, read);
  timer.stop();
  std::printf("read '%s': %zu points%s\n", o.input.c_str(), cloud.points.size(),
              cloud.has_normals && !o.ignore_normals ? ", with normals" : "");
  paco::app::reportCoordinateOffset(cloud.coordinate_offset);
  if (!cloud.has_normals || o.ignore_normals) {
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (auto& p : cloud.points) p.normal_x = p.normal_y = p.normal_z = nan;
  }
  // As paco_reconstruct: so that the planes written face out of the solid the normals enclose.
  paco::app::reportNormalSides(paco::app::turnInwardNormals(cloud.points, o.keep_inward_normals));

  // The segmenter's input: the cloud's points, or a thinned copy made straight from them (a
  // full copy first would cost another 480 MB for 10 million points).
  auto points = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  const bool thin = o.max_points > 0 && cloud.points.size() > o.max_points;
  if (thin) {
    timer.start("thin");
    const paco::ThinningReport report = paco::thinToPointBudget(cloud.points, o.max_points, *points);
    timer.stop();
    std::printf("thin: segmenting %zu of %zu points, one per %.3g-unit voxel (--max-points %zu); every point is "
                "labelled from them\n",
                report.output_points, report.input_points, report.voxel_size, o.max_points);
  } else {
    *points = cloud.points;
  }
  timer.start("segment");
  segmenter->setInputCloud(points);
  paco::PlanarSegmentation result;
  segmenter->segment(result);
  timer.stop();
  std::printf("%s: %zu planes, coverage %.1f %%%s, %.3f s\n", segmenter->name().c_str(), result.size(),
              100.0 * result.coverage(),
              paco::app::noisyScanNote(o.epsilon, segmenter->getUsedDistanceThreshold()).c_str(),
              timer.seconds("segment"));

  // Write the normals used (given or estimated) along with the labels: onto the segmented
  // points, which are the cloud's own unless it was thinned.
  const auto& prepared = segmenter->prepared();
  pcl::PointCloud<pcl::PointNormal>& segmented = thin ? *points : cloud.points;
  for (std::size_t i = 0; i < prepared.size(); ++i) {
    auto& p = segmented[static_cast<std::size_t>(prepared.source_indices[i])];
    p.getNormalVector3fMap() = (*prepared.points)[i].getNormalVector3fMap();
  }
  if (thin) {
    // Every point from the thinned copy: the label of a nearby kept point whose plane it lies on
    // (labelsFromThinned), and, where the file had none, its nearest kept point's estimated normal.
    // The inlier distance in the cloud's units, as the segmenter used it on the thinned copy.
    const double max_distance = segmenter->getUsedDistanceThreshold() / prepared.normalization.scale;
    timer.start("label");
    // Ctrl-C ends the labelling cleanly; until here it ends the process (nothing is written yet).
    paco::InterruptGuard interrupt_guard;
    std::vector<int> nearest;
    // A bar where labelling takes long enough to watch (about 5 s per million points).
    constexpr std::size_t kProgressFrom = 1000000;
    std::unique_ptr<paco::ProgressBar> bar;
    if (cloud.points.size() >= kProgressFrom)
      bar = std::make_unique<paco::ProgressBar>("label every point", cloud.points.size());
    std::size_t shown = 0;
    result.labels = paco::labelsFromThinned(cloud.points, *points, result, max_distance, &nearest, [&](std::size_t done) {
      if (bar) bar->advance(done - shown);
      shown = done;
      if (paco::interruptRequested()) throw paco::InterruptedError("interrupted");
    }, o.threads);
    if (bar) bar->finish();
    result.rebuildSegmentsFromLabels();
    timer.stop();
    const bool keep_file_normals = cloud.has_normals && !o.ignore_normals;
    for (std::size_t i = 0; i < cloud.points.size() && !keep_file_normals; ++i)
      if (nearest[i] >= 0)
        cloud.points[i].getNormalVector3fMap() = (*points)[static_cast<std::size_t>(nearest[i])].getNormalVector3fMap();
    std::printf("labelled %zu points from the %zu segmented: coverage %.1f %%, %.3f s\n", cloud.points.size(),
                points->size(), 100.0 * result.coverage(), timer.seconds("label"));
  }
  cloud.has_normals = true;
  cloud.labels = result.labels;

  timer.start("save");
  paco::app::warnIfPcdRoundsFarCoordinates(o.output, cloud.coordinate_offset);
  paco::io::saveCloud(labelled_output.writePath(), cloud);
  if (vg_output) {
    paco::io::VertexGroups groups;
    groups.points = cloud.points;
    groups.has_normals = true;
    groups.segmentation = result;
    groups.coordinate_offset = cloud.coordinate_offset;
    paco::io::saveVertexGroups(vg_output->writePath(), groups);
  }
  labelled_output.commit();
  if (vg_output) vg_output->commit();
  timer.stop();
  std::printf("wrote '%s'%s%s\n", o.output.c_str(), o.vg.empty() ? "" : " and ", o.vg.c_str());
  timer.print();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
