// Dataset mode on a tiny dataset written here: rows, failure scores, resume, tables.
#include <paco/common/error.h>
#include <paco/common/progress.h>
#include <paco/data/builder.h>
#include <paco/evaluation/benchmark.h>
#include <paco/evaluation/metrics.h>

#include <shapes.h>
#include <test_support.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <functional>
#include <set>
#include <string>
#include <tuple>

namespace ev = paco::evaluation;

namespace {

// Three parts named so that they fall in one split; returns that split's name. `mode`: how the
// inputs were cut (nearest or visibility), `single_scanner`: with visibility, by one scanner.
std::string writeDataset(const std::string& folder, const std::string& mode = "nearest", bool single_scanner = false) {
  paco::data::BuildOptions options;
  options.info.mode = mode;
  options.info.single_scanner = single_scanner;
  options.info.levels = {0, 2};
  options.info.views = 1;
  options.info.source = "test shapes";
  paco::data::DatasetWriter writer(folder, options.info);
  const std::vector<paco::SurfaceMesh> meshes = {paco::test::makeLBracket(), paco::test::makeChamferedCube(),
                                                 paco::test::makeBossOnSlab()};
  // Pick names in the validation split (FNV-1a bucket 80..89).
  std::vector<std::string> names;
  for (int i = 0; names.size() < meshes.size(); ++i) {
    const std::string name = "shape-" + std::to_string(i);
    if (paco::data::splitOf(name) == paco::data::Split::Val) names.push_back(name);
  }
  for (std::size_t i = 0; i < meshes.size(); ++i) writer.write(paco::data::buildPart(names[i], meshes[i], options));
  return "val";
}

// A test method alone on the dataset's first `limit` parts at 25 % missing, quietly, with few samples.
ev::BenchmarkOptions oneMethodOptions(const std::string& dataset, const std::string& split, const std::string& method,
                                      std::size_t limit) {
  ev::BenchmarkOptions options;
  options.dataset = dataset;
  options.split = split;
  options.methods = {method};
  options.levels = {0};
  options.limit = limit;
  options.progress = false;
  options.metrics.num_samples = 500;
  return options;
}

}  // namespace

TEST(Benchmark, WritesOneRowPerCaseScoresFailuresAsTheBoxAndResumes) {
  paco::test::TempDir dir;
  const std::string split = writeDataset(dir.file("ds"));
  ev::BenchmarkOptions options;
  options.dataset = dir.file("ds");
  options.split = split;
  options.methods = {"sanity"};
  const auto available = ev::availableMethods();
  const bool assemble = std::find(available.begin(), available.end(), "oracle") != available.end();
  if (assemble) options.methods.push_back("oracle");
  options.assemblers = {"cell-complex"};
  options.levels = {0, 2};
  options.limit = 2;
  options.jobs = 2;
  options.output_dir = dir.file("out");
  options.progress = false;
  options.metrics.num_samples = 2000;
  paco::setInterruptRequested(false);

  const ev::BenchmarkRun first = ev::runBenchmark(options);
  const std::size_t cases = 2 /*parts*/ * 2 /*levels*/ * options.methods.size();
  EXPECT_EQ(first.cases_total, cases);
  EXPECT_EQ(first.cases_evaluated, cases);
  EXPECT_EQ(first.cases_resumed, 0u);
  EXPECT_FALSE(first.interrupted);

  const auto records = ev::readRecords(first.csv_path);
  ASSERT_EQ(records.size(), cases);
  std::set<std::string> parts;
  for (const auto& r : records) {
    parts.insert(r.part);
    if (r.method == "sanity") {
      EXPECT_EQ(r.reason, ev::FailureReason::Sanity);
      EXPECT_EQ(r.assembler, "-");
      EXPECT_GT(r.chamfer, 0.0);
      EXPECT_GT(r.hausdorff, r.chamfer);
    } else {  // oracle
      // The oracle gets the exact GT planes: NC_prim is 1 and, when it closes, it is near the GT.
      EXPECT_NEAR(r.nc_prim, 1.0, 1e-9);
      if (!r.failed()) {
        EXPECT_LT(r.chamfer, 5.0) << r.part;
      }
    }
  }
  EXPECT_EQ(parts.size(), 2u);
  // Every row splits GT->pred by the partial input: more of the GT is hidden at 75 % missing
  // than at 25 %, and the two parts make up GT->pred.
  for (const auto& r : records) {
    EXPECT_GT(r.hidden_fraction, r.level == 0 ? 0.05 : 0.45) << r.key();
    EXPECT_LT(r.hidden_fraction, r.level == 0 ? 0.55 : 0.95) << r.key();
    EXPECT_NEAR((1.0 - r.hidden_fraction) * r.chamfer_gt_to_pred_seen + r.hidden_fraction * r.chamfer_gt_to_pred_hidden,
                r.chamfer_gt_to_pred, 1e-6)
        << r.key();
  }
  // Sanity rows of one sample equal evaluateFailure on its GT mesh: identical across levels of a part.
  for (const auto& a : records)
    for (const auto& b : records)
      if (a.method == "sanity" && b.method == "sanity" && a.part == b.part) {
        EXPECT_EQ(a.chamfer, b.chamfer);
      }

  const std::string md = paco::test::readBytes(first.report_path);
  EXPECT_NE(md.find("## Simple (25 % missing)"), std::string::npos);
  EXPECT_NE(md.find("## Hard (75 % missing)"), std::string::npos);
  EXPECT_NE(md.find("| sanity | - | 2 | 100.0 |"), std::string::npos) << md;

  // A second run finds everything done.
  const ev::BenchmarkRun second = ev::runBenchmark(options);
  EXPECT_EQ(second.cases_evaluated, 0u);
  EXPECT_EQ(second.cases_resumed, cases);
  EXPECT_EQ(ev::readRecords(second.csv_path).size(), cases);

  // A new method is added to the same CSV.
  options.methods = {"sanity", "poisson-qem"};
  if (std::find(available.begin(), available.end(), "poisson-qem") != available.end()) {
    options.limit = 1;
    const ev::BenchmarkRun third = ev::runBenchmark(options);
    EXPECT_EQ(third.cases_evaluated, 2u);
    EXPECT_EQ(ev::readRecords(third.csv_path).size(), cases + 2);
  }
}

TEST(Benchmark, BadOptionsAreErrors) {
  paco::test::TempDir dir;
  ev::BenchmarkOptions options;
  options.dataset = dir.file("nothing");
  options.output_dir = dir.file("out");
  options.methods = {"no-such-method"};
  EXPECT_THROW(ev::runBenchmark(options), paco::InvalidInputError);
  options.methods = {"sanity"};
  options.levels = {3};
  EXPECT_THROW(ev::runBenchmark(options), paco::InvalidInputError);
  options.levels = {0};
  options.method.segment_min_points = 2;
  EXPECT_THROW(ev::runBenchmark(options), paco::InvalidInputError);
  options.method.segment_min_points = 0;
  // Method options no case could run with fail before any case runs, not as a failure in each.
  const ev::MethodOptions good = options.method;
  const std::vector<std::pair<std::function<void(ev::MethodOptions&)>, std::string>> bad = {
      {[](ev::MethodOptions& m) { m.segmenter = "no-such-segmenter"; }, "choose one of: gocopp"},
      {[](ev::MethodOptions& m) { m.completion_frame = "paper"; }, "not one of: own, complete"},
      {[](ev::MethodOptions& m) { m.confidence_threshold = 1.5; }, "in [0, 1], got 1.5"},
      {[](ev::MethodOptions& m) { m.confidence_threshold = std::nan(""); }, "in [0, 1], got nan"},
      {[](ev::MethodOptions& m) { m.qem_target_faces = 3; }, "at least 4 faces, got 3"}};
  const auto available = ev::availableMethods();
  const bool segments = std::find(available.begin(), available.end(), "direct") != available.end();
  for (const auto& [spoil, message] : bad) {
    if (!segments && message.rfind("choose one of", 0) == 0) continue;  // no segmenter in this build
    options.method = good;
    spoil(options.method);
    try {
      ev::runBenchmark(options);
      ADD_FAILURE() << "no error; expected one saying " << message;
    } catch (const paco::InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
  options.method = good;
  EXPECT_THROW(ev::runBenchmark(options), paco::IoError);  // no dataset there
}

// started.log holds each case as it starts. A case Ctrl-C stopped (here a method that throws
// InterruptedError, as an assembly whose child process was killed for Ctrl-C does), or one in
// flight when a second Ctrl-C ended the run, is evaluated again by the next run; a case that
// started and never reached the CSV otherwise killed its process, and is recorded as failed
// instead of run again.
TEST(Benchmark, ACaseCtrlCStoppedRunsAgainAndOneThatCrashedIsRecordedAsFailed) {
  paco::test::TempDir dir;
  const std::string split = writeDataset(dir.file("ds"));
  static int calls = 0;
  calls = 0;
  ev::registerMethod(
      "test-stopped-once", [](const ev::MethodInput&, const ev::MethodOptions&) -> ev::MethodOutput {
        if (calls++ == 0) {
          paco::setInterruptRequested(true);
          throw paco::InterruptedError("assembly interrupted");
        }
        ev::MethodOutput out;
        out.reason = ev::FailureReason::NoMesh;
        out.message = "evaluated";
        return out;
      },
      false);
  ev::BenchmarkOptions options = oneMethodOptions(dir.file("ds"), split, "test-stopped-once", 2);
  options.jobs = 1;
  options.output_dir = dir.file("out");
  paco::setInterruptRequested(false);
  const ev::BenchmarkRun stopped = ev::runBenchmark(options);
  paco::setInterruptRequested(false);
  EXPECT_TRUE(stopped.interrupted);
  EXPECT_EQ(stopped.cases_evaluated, 0u);
  EXPECT_TRUE(ev::readRecords(stopped.csv_path).empty());

  const ev::BenchmarkRun resumed = ev::runBenchmark(options);
  EXPECT_FALSE(resumed.interrupted);
  const auto records = ev::readRecords(resumed.csv_path);
  ASSERT_EQ(records.size(), 2u);
  for (const auto& r : records) EXPECT_EQ(r.message, "evaluated") << r.key();

  // A journal whose first run started the first case and died (a crash), and whose second run
  // started the other case and was ended by a second Ctrl-C (the handler's "-*" line); the CSV has
  // neither. Only the first is recorded as failed; the other runs again.
  options.output_dir = dir.file("crashed");
  std::filesystem::create_directories(options.output_dir);
  paco::test::writeBytes(dir.file("crashed/started.log"),
                         "+\n" + records[0].key() + "\n+\n" + records[1].key() + "\n-*\n");
  const auto after_crash = ev::readRecords(ev::runBenchmark(options).csv_path);
  ASSERT_EQ(after_crash.size(), 2u);
  for (const auto& r : after_crash) {
    if (r.key() == records[0].key()) {
      EXPECT_EQ(r.reason, ev::FailureReason::Threw);
      EXPECT_NE(r.message.find("killed an earlier evaluation process"), std::string::npos) << r.message;
    } else {
      EXPECT_EQ(r.message, "evaluated") << r.key();
    }
  }
  // This run wrote its "+" and the one case it ran.
  const std::string journal = paco::test::readBytes(dir.file("crashed/started.log"));
  const std::string this_run = "-*\n+\n" + records[1].key() + "\n";
  ASSERT_GE(journal.size(), this_run.size());
  EXPECT_EQ(journal.substr(journal.size() - this_run.size()), this_run) << journal;
}

TEST(Benchmark, NoNormalsOptionHandsTheMethodsBarePoints) {
  paco::test::TempDir dir;
  const std::string split = writeDataset(dir.file("ds"));
  // A method that reports how many input points carry a normal.
  ev::registerMethod(
      "test-count-normals", [](const ev::MethodInput& in, const ev::MethodOptions&) {
        std::size_t with_normal = 0;
        for (const auto& p : in.input) with_normal += p.getNormalVector3fMap().squaredNorm() > 0.5f;
        ev::MethodOutput out;
        out.reason = ev::FailureReason::NoMesh;
        out.message = std::to_string(with_normal) + " of " + std::to_string(in.input.size()) + " with normals";
        return out;
      },
      false);
  ev::BenchmarkOptions options = oneMethodOptions(dir.file("ds"), split, "test-count-normals", 1);
  for (bool drop : {false, true}) {
    options.drop_input_normals = drop;
    options.output_dir = dir.file(drop ? "bare" : "with");
    const ev::BenchmarkRun run = ev::runBenchmark(options);
    const auto records = ev::readRecords(run.csv_path);
    ASSERT_EQ(records.size(), 1u);
    EXPECT_EQ(records[0].message.rfind("0 of ", 0) == 0, drop) << records[0].message;
  }
}

TEST(Benchmark, TheScannerStoodAtTheViewpointOfASingleScannerDatasetOnly) {
  paco::test::TempDir dir;
  // A method that reports where its input says the scanner stood.
  ev::registerMethod(
      "test-scanner-position", [](const ev::MethodInput& in, const ev::MethodOptions&) {
        ev::MethodOutput out;
        out.reason = ev::FailureReason::NoMesh;
        if (!in.scanner_position) {
          out.message = "none";
        } else {
          const Eigen::Vector3d& p = *in.scanner_position;
          out.message = std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z());
        }
        return out;
      },
      false);
  ev::BenchmarkOptions options;
  options.methods = {"test-scanner-position"};
  options.levels = {0};
  options.views = {0};
  options.limit = 1;
  options.progress = false;
  options.metrics.num_samples = 500;
  // View 0 of a dataset of one view is the cube corner (1, 1, 1) / sqrt(3), one diagonal out.
  const std::string corner = std::to_string(1.0 / std::sqrt(3.0));
  for (const auto& [name, mode, single] : {std::tuple<std::string, std::string, bool>{"nearest", "nearest", false},
                                           {"stations", "visibility", false},
                                           {"one-scanner", "visibility", true}}) {
    options.dataset = dir.file(name);
    options.split = writeDataset(options.dataset, mode, single);
    options.output_dir = dir.file(name + "-out");
    const auto records = ev::readRecords(ev::runBenchmark(options).csv_path);
    ASSERT_EQ(records.size(), 1u) << name;
    EXPECT_EQ(records[0].message, single ? corner + " " + corner + " " + corner : "none") << name;
  }
  // Nearest mode removed what a scanner at the viewpoint would have seen, and other stations add
  // what it could not see: asking for the scanner there is an error.
  options.method.use_scanner_position = true;
  for (const std::string name : {"nearest", "stations"}) {
    options.dataset = dir.file(name);
    options.output_dir = dir.file(name + "-asked");
    try {
      ev::runBenchmark(options);
      ADD_FAILURE() << name << ": no error";
    } catch (const paco::InvalidInputError& e) {
      EXPECT_NE(std::string(e.what()).find("--mode visibility --single-scanner"), std::string::npos) << e.what();
    }
  }
}
