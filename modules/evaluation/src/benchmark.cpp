#include <paco/evaluation/benchmark.h>

#include <paco/common/error.h>
#include <paco/common/point_types.h>
#include <paco/common/progress.h>

#ifdef PACO_EVALUATION_WITH_DATA
#include <paco/data/dataset.h>
#endif

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

namespace paco::evaluation {

namespace {

void checkOptions(const BenchmarkOptions& options) {
  if (options.dataset.empty()) throw InvalidInputError("runBenchmark: no dataset folder given");
  if (options.output_dir.empty()) throw InvalidInputError("runBenchmark: no output folder given");
  if (options.methods.empty()) throw InvalidInputError("runBenchmark: no method given");
  validateMethodOptions(options.method);
  if (options.jobs < 1) throw InvalidInputError("runBenchmark: jobs must be at least 1");
  if (options.levels.empty() || options.views.empty()) throw InvalidInputError("runBenchmark: no level or no view given");
  for (int level : options.levels)
    if (level < 0 || level > 2) throw InvalidInputError("runBenchmark: level " + std::to_string(level) + " is not 0, 1 or 2");
  for (int view : options.views)
    if (view < 0) throw InvalidInputError("runBenchmark: view " + std::to_string(view) + " is negative");
  if (options.method.max_input_points != 0 && options.method.max_input_points < kMinInputPointBudget)
    throw InvalidInputError("runBenchmark: the input point budget must be 0 (keep all) or at least " +
                            std::to_string(kMinInputPointBudget));
  if (options.method.segment_min_points != 0 && options.method.segment_min_points < 3)
    throw InvalidInputError("runBenchmark: the fewest points of a plane must be 0 (a share of the input) or at least 3; got " +
                            std::to_string(options.method.segment_min_points));
  const int parallel = options.method.segment_min_parallel_points;
  if (parallel != -1 && parallel != 0 && parallel < 3)
    throw InvalidInputError("runBenchmark: the fewest points of a parallel plane must be -1 (none), 0 (a share of the "
                            "input) or at least 3; got " + std::to_string(parallel));
  const std::vector<std::string> available = availableMethods();
  for (const auto& m : options.methods) {
    if (std::find(available.begin(), available.end(), m) == available.end()) {
      MethodInput none;
      runMethod(m, none, options.method);  // throws the message that says what the build lacks
    }
  }
  bool any_assembling = false;
  for (const auto& m : options.methods) any_assembling = any_assembling || methodUsesAssembler(m);
  if (any_assembling && options.assemblers.empty()) throw InvalidInputError("runBenchmark: no assembler given");
  for (const auto& a : options.assemblers)
    if (a != "polyfit" && a != "cell-complex")
      throw InvalidInputError("runBenchmark: unknown assembler '" + a + "'; use polyfit or cell-complex");
}

}  // namespace

#ifdef PACO_EVALUATION_WITH_DATA

namespace {

// started.log: a line that starts with this marks a case Ctrl-C stopped (a key starts with a
// method's name); a run starts with kRunStart; kHardStop ends a run that a second Ctrl-C ended.
constexpr char kStoppedMark = '-';
constexpr const char* kRunStart = "+";
constexpr const char* kHardStop = "-*";
constexpr const char* kHardStopLine = "-*\n";

struct Combination {
  std::string method, assembler;
};

EvaluationRecord evaluateCase(const data::Sample& sample, const SurfaceMesh& gt_mesh, const MeshMetrics& failure_score,
                              const Combination& combination, const BenchmarkOptions& options,
                              const data::DatasetInfo& info) {
  MethodInput in;
  in.input = sample.input;
  // With one scanner, an input is what the scanner at the viewpoint saw.
  if (info.mode == "visibility" && info.single_scanner) in.scanner_position = sample.viewpoint * info.viewpoint_distance;
  if (options.drop_input_normals)
    for (auto& p : in.input) p.normal_x = p.normal_y = p.normal_z = 0.0f;
  in.input_labels = sample.input_labels;
  in.input_labels_from_segmenter = sample.input_labels_from_segmenter;
  in.gt_points = sample.gt_points;
  in.gt_labels = sample.gt_labels;
  in.gt_planes = sample.gt_planes;
  MethodOptions method_options = options.method;
  if (combination.assembler != "-") method_options.assembler = combination.assembler;
  MethodOutput out = runMethod(combination.method, in, method_options);

  EvaluationRecord r;
  r.method = combination.method;
  r.assembler = combination.assembler;
  r.part = sample.part;
  r.level = static_cast<int>(sample.level);
  r.view = sample.view;
  r.seconds = out.seconds;
  r.message = out.message;
  if (out.has_planes) {
    const PrimitiveAgreement a = comparePrimitives(out.planes, sample.gt_planes);
    r.nc_prim = a.nc_prim;
    r.unmatched_predicted = static_cast<int>(a.unmatched_predicted);
  }
  r.reason = out.reason;
  if (r.reason == FailureReason::None) r.reason = out.has_mesh ? classifyMesh(out.mesh) : FailureReason::NoMesh;
  const auto start = std::chrono::steady_clock::now();
  if (r.reason == FailureReason::None) {
    try {
      const MeshMetrics m = evaluateMesh(out.mesh, gt_mesh, positionsOf(sample.input), options.metrics);
      r.setScores(m);
      r.num_faces = m.num_faces;
      r.num_vertices = m.num_vertices;
      r.volume_ratio = m.volume_ratio;
    } catch (const Error& e) {
      r.reason = FailureReason::EmptyMesh;
      r.message = e.what();
    }
  }
  if (r.failed()) {
    r.setScores(failure_score);
    r.num_faces = r.num_vertices = 0;
    if (r.message.empty() && out.has_mesh) r.message = analyseTopology(out.mesh).describe();
  }
  r.seconds["evaluate"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace

BenchmarkRun runBenchmark(const BenchmarkOptions& options) {
  checkOptions(options);
  const data::Split split = data::splitFromString(options.split);
  const data::Dataset dataset(options.dataset);
  if (options.method.use_scanner_position && !(dataset.info().mode == "visibility" && dataset.info().single_scanner))
    throw InvalidInputError(
        "dataset '" + options.dataset + "' " +
        (dataset.info().mode == "visibility"
             ? std::string("adds what other stations saw to the scan from the viewpoint")
             : "was cut by distance from the viewpoint (" + dataset.info().mode +
                   " mode), which removes the points nearest to it: a scanner there would have seen them") +
        ". The scanner's position needs inputs from one scanner: build the dataset with paco_dataset --mode "
        "visibility --single-scanner");

  // Every sample of the split at the requested levels and views, in the dataset's order (by part).
  std::vector<std::size_t> indices;
  for (int level : options.levels)
    for (int view : options.views)
      for (std::size_t i : dataset.select(split, static_cast<data::MissingLevel>(level), view)) indices.push_back(i);
  std::sort(indices.begin(), indices.end());
  indices.erase(std::unique(indices.begin(), indices.end()), indices.end());
  if (indices.empty())
    throw InvalidInputError("dataset '" + options.dataset + "' has no " + options.split +
                            " sample at the requested levels and views");
  if (options.limit > 0) {
    // Sample indices are ordered by part, so the first `limit` parts own the first indices.
    std::set<std::string> kept;
    std::vector<std::size_t> limited;
    for (std::size_t i : indices) {
      const std::string part = dataset.load(split, i).part;
      if (!kept.count(part)) {
        if (kept.size() == options.limit) break;
        kept.insert(part);
      }
      limited.push_back(i);
    }
    indices = std::move(limited);
  }

  std::vector<Combination> combinations;
  for (const auto& m : options.methods) {
    if (methodUsesAssembler(m))
      for (const auto& a : options.assemblers) combinations.push_back({m, a});
    else
      combinations.push_back({m, "-"});
  }

  std::filesystem::create_directories(options.output_dir);
  BenchmarkRun run;
  run.csv_path = (std::filesystem::path(options.output_dir) / "eval.csv").string();
  run.report_path = (std::filesystem::path(options.output_dir) / "results.md").string();

  // Resume: keep the complete rows of an earlier run, rewrite the file without a cut last line.
  std::size_t skipped_lines = 0;
  const std::vector<EvaluationRecord> previous = readRecords(run.csv_path, &skipped_lines);
  std::set<std::string> done;
  for (const auto& r : previous) done.insert(r.key());
  {
    const std::string temp = run.csv_path + ".partial";
    std::ofstream out(temp, std::ios::trunc);
    out << csvHeader() << '\n';
    for (const auto& r : previous) appendRecord(out, r);
    out.close();
    if (!out) throw IoError("cannot write '" + temp + "': check the output folder's permissions and free space");
    std::filesystem::rename(temp, run.csv_path);
  }
  if (skipped_lines > 0)
    std::cerr << "paco_eval: dropped " << skipped_lines << " incomplete line(s) of " << run.csv_path << "\n";

  // Journal of started cases. A case started by an earlier run but missing from the CSV killed
  // that process (e.g. an assertion inside a solver): it is recorded as failed, not run again,
  // so that a resumed run cannot crash on it forever. A case that Ctrl-C stopped has a second
  // line, kStoppedMark and its key, and is evaluated again. Each run starts with kRunStart; a
  // second Ctrl-C, which ends the process at once, leaves kHardStop: that run's unfinished cases
  // were stopped too, not crashed.
  const std::string journal_path = (std::filesystem::path(options.output_dir) / "started.log").string();
  std::set<std::string> crashed;
  {
    std::ifstream journal(journal_path);
    std::string key;
    std::vector<std::string> unfinished_in_run;
    while (std::getline(journal, key)) {
      if (key.empty()) continue;
      if (key == kRunStart) {
        unfinished_in_run.clear();
      } else if (key == kHardStop) {
        for (const auto& k : unfinished_in_run) crashed.erase(k);
        unfinished_in_run.clear();
      } else if (key[0] == kStoppedMark) {
        crashed.erase(key.substr(1));
      } else if (!done.count(key)) {
        crashed.insert(key);
        unfinished_in_run.push_back(key);
      }
    }
  }
  std::ofstream journal(journal_path, std::ios::app);
  if (!journal) throw IoError("cannot append to '" + journal_path + "'");
  journal << kRunStart << '\n';
  journal.flush();
  // Its own descriptor for the signal handler, appending as the stream does; closed on the way out.
  struct HardStopNote {
    int fd;
    explicit HardStopNote(const std::string& path) : fd(::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC)) {
      setHardInterruptNote(fd, kHardStopLine);
    }
    ~HardStopNote() {
      setHardInterruptNote(-1, nullptr);
      if (fd >= 0) ::close(fd);
    }
  } hard_stop_note(journal_path);

  run.cases_total = indices.size() * combinations.size();
  std::ofstream csv(run.csv_path, std::ios::app);
  if (!csv) throw IoError("cannot append to '" + run.csv_path + "'");

  std::mutex mutex;
  std::atomic<std::size_t> next{0};
  std::unique_ptr<ProgressBar> bar;
  if (options.progress) bar = std::make_unique<ProgressBar>("evaluate", indices.size());
  std::size_t failed_so_far = 0, evaluated_so_far = 0;

  auto worker = [&]() {
    while (!interruptRequested()) {
      const std::size_t k = next++;
      if (k >= indices.size()) break;
      data::Sample sample;
      SurfaceMesh gt_mesh;
      MeshMetrics failure_score;
      std::vector<Combination> todo;
      try {
        sample = dataset.load(split, indices[k]);
        for (const auto& c : combinations) {
          EvaluationRecord probe;
          probe.method = c.method;
          probe.assembler = c.assembler;
          probe.part = sample.part;
          probe.level = static_cast<int>(sample.level);
          probe.view = sample.view;
          if (!done.count(probe.key())) todo.push_back(c);
        }
        if (!todo.empty()) {
          gt_mesh = dataset.loadGtMesh(sample);
          // The partial input splits GT->pred into the seen and the hidden GT surface.
          failure_score = evaluateFailure(gt_mesh, positionsOf(sample.input), options.metrics, options.failure_box);
        }
      } catch (const std::exception& e) {
        std::lock_guard<std::mutex> lock(mutex);
        ++run.samples_unreadable;
        std::cerr << "\npaco_eval: sample " << indices[k] << " of " << options.split << " is unreadable, skipped: " << e.what()
                  << "\n";
        if (bar) bar->advance();
        continue;
      }
      {
        std::lock_guard<std::mutex> lock(mutex);
        run.cases_resumed += combinations.size() - todo.size();
      }
      for (const auto& c : todo) {
        if (interruptRequested()) break;
        EvaluationRecord r;
        r.method = c.method;
        r.assembler = c.assembler;
        r.part = sample.part;
        r.level = static_cast<int>(sample.level);
        r.view = sample.view;
        const std::string key = r.key();
        try {
          if (crashed.count(key)) {
            r.reason = FailureReason::Threw;
            r.message = "this case killed an earlier evaluation process (e.g. an assertion in a solver); recorded as failed";
            r.setScores(failure_score);
          } else {
            {
              std::lock_guard<std::mutex> lock(mutex);
              journal << key << '\n';
              journal.flush();
            }
            r = evaluateCase(sample, gt_mesh, failure_score, c, options, dataset.info());
          }
        } catch (const InterruptedError&) {
          // Stopped, not crashed (the assembly's child process was killed for Ctrl-C): the
          // journal says so, or the next run would record the case as failed.
          std::lock_guard<std::mutex> lock(mutex);
          journal << kStoppedMark << key << '\n';
          journal.flush();
          break;
        } catch (const std::exception& e) {
          // Whatever went wrong, this case fails and the run goes on.
          r.reason = FailureReason::Threw;
          r.message = e.what();
          r.setScores(failure_score);
        }
        std::lock_guard<std::mutex> lock(mutex);
        appendRecord(csv, r);
        csv.flush();
        ++run.cases_evaluated;
        ++evaluated_so_far;
        if (r.failed()) ++run.cases_failed, ++failed_so_far;
      }
      if (bar) {
        std::lock_guard<std::mutex> lock(mutex);
        std::ostringstream status;
        status << failed_so_far << "/" << evaluated_so_far << " failed";
        bar->setStatus(status.str());
      }
      if (bar) bar->advance();
    }
  };
  std::vector<std::thread> threads;
  for (unsigned j = 1; j < options.jobs; ++j) threads.emplace_back(worker);
  worker();
  for (auto& t : threads) t.join();
  if (bar) bar->finish();
  csv.close();
  run.interrupted = interruptRequested();

  const std::vector<EvaluationRecord> all = readRecords(run.csv_path);
  std::ostringstream notes;
  notes << "Dataset `" << options.dataset << "`, split " << options.split << ", " << indices.size()
        << " samples selected" << (options.limit ? " (--limit " + std::to_string(options.limit) + " parts)" : "")
        << ". " << dataset.description() << "\n\nFailure box: "
        << (options.failure_box == FailureBox::ReferenceBoundingBox ? "the GT's normalised bounding box"
                                                                     : "a cube of diagonal 1")
        << "; " << options.metrics.num_samples << " samples per mesh; assembler time limit "
        << options.method.time_limit << " s; visible segments from "
        << (options.method.use_dataset_labels ? "the dataset's labels" : "PlanarSegmenter '" + options.method.segmenter + "'")
        << (run.interrupted ? ".\n\n**Interrupted**: run the same command again to resume." : ".");
  const std::string temp = run.report_path + ".partial";
  {
    std::ofstream md(temp, std::ios::trunc);
    md << markdownReport(all, "paco_eval results", notes.str());
    if (!md) throw IoError("cannot write '" + temp + "'");
  }
  std::filesystem::rename(temp, run.report_path);
  return run;
}

#else

BenchmarkRun runBenchmark(const BenchmarkOptions& options) {
  checkOptions(options);
  throw InvalidInputError("this build of paco has no paco::data module, so it cannot read datasets; "
                          "rebuild with the data module enabled");
}

#endif

}  // namespace paco::evaluation
