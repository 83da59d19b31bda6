// paco_dataset: builds a training/evaluation dataset from plane-only meshes (or procedural parts):
// ground-truth planes and points, and partial views at three missing ratios (see doc/dataset.md).
//   paco_dataset ../shared/data/mfcad /data/mfcad_ds --augment-scale 0.5,2 --augment-rotate
//   paco_dataset --procedural 1000 /data/proc_ds --jobs 2
//   paco_dataset --export /data/proc_ds sample.pcd --export-mesh sample_gt.off --level 1 --view 0
//   paco_dataset --verify /data/proc_ds          (reads every sample back, reports samples/s)
#include "app_support.h"

#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/common/scan_shares.h>
#include <paco/data/builder.h>
#include <paco/data/dataset.h>
#include <paco/data/procedural.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>

#include <boost/program_options.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace po = boost::program_options;
namespace fs = std::filesystem;

namespace {

const char kTool[] = "paco_dataset";

struct Options {
  std::vector<std::string> positional;
  std::size_t procedural = 0;
  std::string levels = "0,1,2";
  bool single_scanner = false;
  int views = 8;
  double noise = 0.0;
  std::string mode = "nearest";
  std::string augment_scale;
  bool augment_rotate = false;
  std::uint64_t seed = 1;
  std::size_t limit = 0;
  std::string only_split;
  std::size_t stride = 1;
  unsigned jobs = 2;
  int input_points = 2048;
  int gt_points = 8192;
  int dense_points = 16384;
  bool segment = false;
  int segment_min_points = 0;
  int segment_min_parallel_points = -1;
  bool verify_mode = false;
  // --export
  bool export_mode = false;
  std::string export_mesh, part;
  int level = 1, view = 0;
};

struct Job {
  std::string name;
  std::string path;           // mesh file, or empty for a procedural part
  std::uint64_t seed = 0;     // procedural generator seed
  std::string early_failure;  // e.g. a duplicate name
};

void printHelp(const po::options_description& visible) {
  std::cout
      << "Usage: " << kTool << " MESH_DIR OUT_DIR [options]\n"
      << "       " << kTool << " --procedural N OUT_DIR [options]      (MESH_DIR may be given too: both are used)\n"
      << "       " << kTool << " --export DATASET_DIR OUT.pcd [--export-mesh GT.off] [--part NAME] [--level L] [--view V]\n"
      << "       " << kTool << " --verify DATASET_DIR [--limit N]\n\n"
      << "Builds a dataset of plane-only parts: per part the ground-truth planes, 8,192 ground-truth points\n"
      << "and, per missing level and view, a partial input of 2,048 points, all in the normalised frame of\n"
      << "the complete (augmented) part. Meshes: .obj .off .ply .stl in MESH_DIR (not recursive). A part\n"
      << "that is not closed or not plane-only is listed in OUT_DIR/failures.tsv with the reason and\n"
      << "skipped. A rerun with the same options resumes (finished and failed parts are skipped);\n"
      << "Ctrl-C stops cleanly. The format is described in doc/dataset.md.\n"
      << "--export writes one sample's partial input (binary PCD with normals) and its GT mesh.\n"
      << "--verify reads every sample (or the first N of each split) back and reports the read rate.\n\n"
      << visible << std::endl;
}

std::vector<int> parseLevels(const std::string& text) {
  std::vector<int> levels;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item != "0" && item != "1" && item != "2")
      throw paco::app::UsageError("--levels takes a comma list of 0 (25 % missing), 1 (50 %), 2 (75 %)");
    levels.push_back(std::stoi(item));
  }
  std::sort(levels.begin(), levels.end());
  levels.erase(std::unique(levels.begin(), levels.end()), levels.end());
  if (levels.empty()) throw paco::app::UsageError("--levels is empty");
  return levels;
}

std::vector<Job> collectJobs(const Options& o, const std::string& mesh_dir, std::uint64_t seed) {
  std::vector<Job> jobs;
  if (!mesh_dir.empty()) {
    if (!fs::is_directory(mesh_dir)) throw paco::IoError("mesh folder '" + mesh_dir + "' does not exist");
    std::vector<fs::path> files;
    for (const auto& entry : fs::directory_iterator(mesh_dir)) {
      const std::string ext = paco::io::extensionOf(entry.path().string());
      if (entry.is_regular_file() && (ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl"))
        files.push_back(entry.path());
    }
    std::sort(files.begin(), files.end());
    if (files.empty()) throw paco::IoError("no .obj/.off/.ply/.stl mesh in '" + mesh_dir + "'");
    // Subsets that are reproducible from the names alone: one split, then every K-th, then N.
    if (!o.only_split.empty()) {
      const paco::data::Split wanted = paco::data::splitFromString(o.only_split);
      std::vector<fs::path> kept;
      for (const auto& f : files)
        if (paco::data::splitOf(f.stem().string()) == wanted) kept.push_back(f);
      files = std::move(kept);
    }
    if (o.stride > 1) {
      std::vector<fs::path> kept;
      for (std::size_t i = 0; i < files.size(); i += o.stride) kept.push_back(files[i]);
      files = std::move(kept);
    }
    if (files.empty()) throw paco::IoError("no mesh of '" + mesh_dir + "' is left after --only-split/--stride");
    if (o.limit > 0 && files.size() > o.limit) files.resize(o.limit);
    std::map<std::string, std::string> seen;
    for (const auto& file : files) {
      Job job;
      job.name = file.stem().string();
      job.path = file.string();
      const auto [it, inserted] = seen.emplace(job.name, job.path);
      if (!inserted) job.early_failure = "duplicate part name: '" + it->second + "' has the same name";
      if (job.name.find_first_of("\t\n\r") != std::string::npos) job.early_failure = "the file name has tabs or newlines";
      jobs.push_back(job);
    }
  }
  for (std::size_t i = 0; i < o.procedural; ++i) {
    Job job;
    job.name = paco::data::proceduralPartName(i);
    job.seed = paco::data::fnv1a64(job.name) ^ seed;
    jobs.push_back(job);
  }
  return jobs;
}

int exportSample(const Options& o) {
  if (o.positional.size() != 2) throw paco::app::UsageError("--export expects DATASET_DIR and OUT.pcd");
  if (o.level < 0 || o.level > 2) throw paco::app::UsageError("--level must be 0, 1 or 2");
  paco::app::checkOutputPath(o.positional[1], "OUT.pcd", {".pcd", ".ply", ".xyz", ".npy", ".vg", ".bvg"});
  if (!o.export_mesh.empty())
    paco::app::checkOutputPath(o.export_mesh, "--export-mesh", {".obj", ".off", ".ply", ".stl"});
  paco::app::checkOutputsAreNotInputs({}, {{"OUT.pcd", o.positional[1]}, {"--export-mesh", o.export_mesh}});
  const paco::data::Dataset dataset(o.positional[0]);
  const std::string part = o.part.empty() && !dataset.parts().empty() ? dataset.parts().front().part : o.part;
  for (paco::data::Split split : {paco::data::Split::Train, paco::data::Split::Val, paco::data::Split::Test}) {
    for (std::size_t i : dataset.select(split, static_cast<paco::data::MissingLevel>(o.level), o.view)) {
      const paco::data::Sample sample = dataset.load(split, i);
      if (sample.part != part) continue;
      paco::io::LabelledCloud cloud;
      cloud.points = sample.input;
      cloud.has_normals = true;
      paco::app::PendingOutput output(o.positional[1]);
      paco::io::saveCloud(output.writePath(), cloud);
      std::unique_ptr<paco::app::PendingOutput> mesh_output;
      if (!o.export_mesh.empty()) {
        mesh_output = std::make_unique<paco::app::PendingOutput>(o.export_mesh);
        paco::io::saveMesh(mesh_output->writePath(), dataset.loadGtMesh(sample));
        mesh_output->commit();
      }
      output.commit();
      std::printf("wrote '%s': part %s, level %s, view %d, %zu points, %.1f %% missing, %zu GT planes\n",
                  o.positional[1].c_str(), part.c_str(), paco::data::toString(sample.level).c_str(), sample.view,
                  sample.input.size(), 100.0 * sample.missing_ratio, sample.gt_planes.size());
      if (!o.export_mesh.empty()) std::printf("wrote '%s': GT mesh (normalised frame)\n", o.export_mesh.c_str());
      return 0;
    }
  }
  throw paco::InvalidInputError("no sample of part '" + part + "' at level " + std::to_string(o.level) + ", view " +
                                std::to_string(o.view) + " in '" + o.positional[0] + "'");
}

int verifyDataset(const Options& o) {
  if (o.positional.size() != 1) throw paco::app::UsageError("--verify expects DATASET_DIR");
  const paco::data::Dataset dataset(o.positional[0]);
  std::printf("%s", dataset.description().c_str());
  std::size_t total = 0;
  for (paco::data::Split split : {paco::data::Split::Train, paco::data::Split::Val, paco::data::Split::Test})
    total += o.limit ? std::min(o.limit, dataset.size(split)) : dataset.size(split);
  paco::InterruptGuard guard;
  paco::ProgressBar bar("read", total);
  std::size_t read = 0, points = 0;
  const auto start = std::chrono::steady_clock::now();
  for (paco::data::Split split : {paco::data::Split::Train, paco::data::Split::Val, paco::data::Split::Test}) {
    const std::size_t n = o.limit ? std::min(o.limit, dataset.size(split)) : dataset.size(split);
    for (std::size_t i = 0; i < n && !paco::interruptRequested(); ++i) {
      const paco::data::Sample s = dataset.load(split, i);
      for (int label : s.gt_labels)
        if (label < 0 || label >= static_cast<int>(s.gt_planes.size()))
          throw paco::IoError("part '" + s.part + "': a GT point has label " + std::to_string(label) + " out of range");
      points += s.input.size();
      ++read;
      bar.advance();
    }
  }
  bar.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("read %zu samples (%zu input points) in %.2f s: %.0f samples/s; all consistent\n", read, points, seconds,
              read / std::max(seconds, 1e-9));
  return paco::interruptRequested() ? 130 : 0;
}

int run(int argc, char** argv) {
  Options o;
  po::options_description visible("Options");
  visible.add_options()
      ("help,h", "print this help")
      ("procedural", po::value(&o.procedural), "also generate N procedural plane-only parts (proc-000000 ...)")
      ("levels", po::value(&o.levels)->default_value(o.levels), "missing levels: 0 = 25 %, 1 = 50 %, 2 = 75 % missing")
      ("views", po::value(&o.views)->default_value(o.views), "viewpoints per part and level (8: cube corners; more: Fibonacci sphere)")
      ("noise", po::value(&o.noise)->default_value(o.noise), "Gaussian noise on the inputs, sigma in % of the diagonal (paper: 1.5, 3, 4.5)")
      ("mode", po::value(&o.mode)->default_value(o.mode), "nearest (AdaPoinTr: drop points nearest to the viewpoint) or visibility (ray cast)")
      ("single-scanner", po::bool_switch(&o.single_scanner),
       "with --mode visibility: an input is what one scanner at the viewpoint sees (no other station adds to it), "
       "as paco_reconstruct --seen-from-point assumes")
      ("augment-scale", po::value(&o.augment_scale), "random anisotropic scale per axis, log-uniform in MIN,MAX (e.g. 0.5,2)")
      ("augment-rotate", po::bool_switch(&o.augment_rotate), "random rotation of every part")
      ("seed", po::value(&o.seed)->default_value(o.seed), "base seed of every random choice")
      ("only-split", po::value(&o.only_split), "use only the meshes of this split (train, val or test; by hash of the name)")
      ("stride", po::value(&o.stride)->default_value(o.stride), "use every K-th mesh (sorted by name, after --only-split)")
      ("limit", po::value(&o.limit), "use only the first N meshes of MESH_DIR (sorted by name, after --only-split and --stride)")
      ("jobs,j", po::value(&o.jobs)->default_value(o.jobs), "worker threads")
      ("input-points", po::value(&o.input_points)->default_value(o.input_points), "points per partial input")
      ("gt-points", po::value(&o.gt_points)->default_value(o.gt_points), "ground-truth points per part")
      ("dense-points", po::value(&o.dense_points)->default_value(o.dense_points), "dense surface sample views are cut from")
      ("segment", po::bool_switch(&o.segment), "label inputs with PlanarSegmenter (default: GT faces of the visible points)")
      ("segment-min-points", po::value(&o.segment_min_points)->default_value(o.segment_min_points),
       ("with --segment: the smallest plane in points; 0: " + paco::percentText(paco::kScanMinPlaneFraction) +
        " of each input's points, " + paco::percentText(paco::kExactScanMinPlaneFraction) +
        " on an input without noise, as paco_reconstruct does").c_str())
      ("segment-min-parallel-points", po::value(&o.segment_min_parallel_points)->default_value(o.segment_min_parallel_points),
       ("with --segment: the smallest plane parallel to a larger one, in points; 0: " +
        paco::percentText(paco::kScanMinParallelPlaneFraction) + " of each input's points, as paco_reconstruct does; "
        "negative: none").c_str())
      ("verify", po::bool_switch(&o.verify_mode), "read a dataset back: DATASET_DIR (with --limit: N samples per split)")
      ("export", po::bool_switch(&o.export_mode), "export one sample: DATASET_DIR OUT.pcd")
      ("export-mesh", po::value(&o.export_mesh), "with --export: also write the GT mesh (normalised frame) here")
      ("part", po::value(&o.part), "with --export: part name (default: the first)")
      ("level", po::value(&o.level)->default_value(o.level), "with --export: missing level 0, 1, 2")
      ("view", po::value(&o.view)->default_value(o.view), "with --export: view index");
  po::options_description all;
  all.add(visible).add_options()("positional", po::value(&o.positional));
  po::positional_options_description positional;
  positional.add("positional", -1);
  const po::variables_map vm = paco::app::parseCommandLine(argc, argv, all, positional);
  if (vm.count("help")) {
    printHelp(visible);
    return 0;
  }
  if (o.export_mode) return exportSample(o);
  if (o.verify_mode) return verifyDataset(o);

  std::string mesh_dir, out_dir;
  if (o.positional.size() == 2) {
    mesh_dir = o.positional[0];
    out_dir = o.positional[1];
  } else if (o.positional.size() == 1 && o.procedural > 0) {
    out_dir = o.positional[0];
  } else {
    throw paco::app::UsageError("expected MESH_DIR OUT_DIR, or --procedural N OUT_DIR");
  }
  if (o.views < 1 || o.views > 255) throw paco::app::UsageError("--views must be in 1..255");
  if (o.stride < 1) throw paco::app::UsageError("--stride must be at least 1");
  if (!o.only_split.empty())
    paco::app::usageErrorIfInvalid([&] { return paco::data::splitFromString(o.only_split); }, "--only-split: ");
  // They choose among MESH_DIR's meshes; ignored, they would build every procedural part.
  if (mesh_dir.empty() && (!o.only_split.empty() || o.stride > 1 || o.limit > 0))
    throw paco::app::UsageError("--only-split, --stride and --limit choose among MESH_DIR's meshes; with --procedural "
                                "alone, --procedural N sets how many parts are built");
  paco::app::validateThreads("--jobs", o.jobs);
  if (!(o.noise >= 0.0)) throw paco::app::UsageError("--noise must be >= 0");
  if (o.input_points < 1 || o.gt_points < 1 || o.dense_points < o.input_points)
    throw paco::app::UsageError("point counts must be >= 1, and --dense-points >= --input-points");
  if (o.mode != "nearest" && o.mode != "visibility") throw paco::app::UsageError("--mode must be nearest or visibility");
  if (o.single_scanner && o.mode != "visibility") throw paco::app::UsageError("--single-scanner needs --mode visibility");
  if (o.segment && !paco::data::segmentationAvailable())
    throw paco::app::UsageError("--segment needs the segmentation module, which this build does not have");
  if (o.segment_min_points < 0)
    throw paco::app::UsageError("--segment-min-points must be >= 0 (0: " + paco::percentText(paco::kScanMinPlaneFraction) +
                                " of each input's points)");
  if (o.segment_min_points > 0 && !o.segment)
    throw paco::app::UsageError("--segment-min-points needs --segment");
  if (o.segment_min_parallel_points >= 0 && !o.segment)
    throw paco::app::UsageError("--segment-min-parallel-points needs --segment");

  paco::data::BuildOptions build;
  paco::data::DatasetInfo& info = build.info;
  info.mode = o.mode;
  info.single_scanner = o.single_scanner;
  info.levels = parseLevels(o.levels);
  info.views = o.views;
  info.noise_percent = o.noise;
  info.augment_rotate = o.augment_rotate;
  info.seed = o.seed;
  info.input_points = o.input_points;
  info.gt_points = o.gt_points;
  info.dense_points = o.dense_points;
  info.input_labels_from_segmenter = o.segment;
  info.segment_min_points = o.segment_min_points;
  info.segment_min_parallel_points = o.segment_min_parallel_points;
  build.segment = o.segment;
  if (!o.augment_scale.empty()) {
    double lo = 0, hi = 0;
    char comma = 0;
    std::istringstream in(o.augment_scale);
    if (!(in >> lo >> comma >> hi) || comma != ',' || !(lo > 0) || !(hi >= lo))
      throw paco::app::UsageError("--augment-scale takes MIN,MAX with 0 < MIN <= MAX, e.g. 0.5,2");
    info.augment_scale_min = lo;
    info.augment_scale_max = hi;
  }
  info.source = mesh_dir.empty() ? "procedural" : mesh_dir + (o.procedural ? " + procedural" : "");

  std::vector<Job> jobs = collectJobs(o, mesh_dir, o.seed);
  paco::data::DatasetWriter writer(out_dir, info);
  std::printf("%s: building '%s'\n%s", kTool, out_dir.c_str(), info.describe().c_str());
  std::vector<Job> todo;
  for (const Job& job : jobs)
    if (!writer.isDone(job.name)) todo.push_back(job);
  std::printf("parts: %zu given, %zu already done (finished %zu, failed %zu), %zu to build, %u jobs\n", jobs.size(),
              jobs.size() - todo.size(), writer.numFinished(), writer.numFailed(), todo.size(), o.jobs);
  std::fflush(stdout);

  paco::InterruptGuard guard;
  paco::ProgressBar bar("parts", todo.size());
  std::atomic<std::size_t> next{0}, built{0}, failed{0};
  std::atomic<bool> fatal{false};
  std::string fatal_message;
  std::mutex fatal_mutex;
  const auto start = std::chrono::steady_clock::now();
  auto worker = [&] {
    while (!fatal && !paco::interruptRequested()) {
      const std::size_t i = next++;
      if (i >= todo.size()) break;
      const Job& job = todo[i];
      try {
        std::string reason = job.early_failure;
        paco::data::PartSamples part;
        if (reason.empty()) {
          try {
            const paco::SurfaceMesh mesh = job.path.empty() ? paco::data::generatePart(job.seed) : paco::io::loadMesh(job.path);
            part = paco::data::buildPart(job.name, mesh, build);
          } catch (const paco::IoError& e) {
            reason = std::string("cannot read: ") + e.what();
          } catch (const std::exception& e) {  // paco::Error, CGAL failures, bad_alloc
            reason = e.what();
          }
        }
        if (reason.empty()) {
          writer.write(part);
          ++built;
        } else {
          writer.fail(job.name, reason);
          ++failed;
        }
      } catch (const std::exception& e) {  // cannot write the dataset: stop everything
        std::lock_guard<std::mutex> lock(fatal_mutex);
        if (!fatal) fatal_message = e.what();
        fatal = true;
        break;
      }
      bar.setStatus("failed " + std::to_string(failed.load()));
      bar.advance();
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < std::min<std::size_t>(o.jobs, std::max<std::size_t>(todo.size(), 1)); ++t) threads.emplace_back(worker);
  for (auto& thread : threads) thread.join();
  bar.finish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (fatal) throw paco::IoError(fatal_message);

  const std::size_t per_part = info.levels.size() * static_cast<std::size_t>(info.views);
  std::printf("built %zu parts (%zu partial inputs) in %.1f s: %.2f parts/s, %.1f inputs/s; failed %zu%s\n",
              built.load(), built.load() * per_part, seconds, built / std::max(seconds, 1e-9),
              static_cast<double>(built * per_part) / std::max(seconds, 1e-9), failed.load(),
              failed ? " (reasons in failures.tsv)" : "");
  std::printf("dataset '%s': %zu parts finished, %zu failed\n", out_dir.c_str(), writer.numFinished(), writer.numFailed());
  if (paco::interruptRequested()) {
    std::printf("interrupted: the index is consistent; rerun the same command to resume\n");
    return 130;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return paco::app::runTool(kTool, [&] { return run(argc, argv); });
}
