#pragma once
// Usage:
//   paco::evaluation::BenchmarkOptions opt; opt.dataset = "/data/paco_mfcad"; opt.output_dir = "out/eval";
//   opt.methods = {"direct", "oracle", "poisson-qem"};
//   paco::evaluation::BenchmarkRun run = paco::evaluation::runBenchmark(opt);   // CSV + Markdown tables
#include <paco/evaluation/methods.h>
#include <paco/evaluation/metrics.h>

#include <cstddef>
#include <string>
#include <vector>

namespace paco::evaluation {

/// A dataset evaluation: every method (and assembler) on the same samples.
struct BenchmarkOptions {
  std::string dataset;          ///< folder written by paco_dataset
  std::string split = "val";    ///< "train", "val" or "test"
  std::vector<std::string> methods{"direct", "oracle", "poisson-qem"};  ///< see availableMethods()
  std::vector<std::string> assemblers{"polyfit", "cell-complex"};      ///< for the methods that assemble
  std::vector<int> levels{0, 1, 2};  ///< missing levels: 0 simple (25 %), 1 moderate (50 %), 2 hard (75 %)
  std::vector<int> views{0};         ///< view indices (the paper evaluates view 0)
  /// At most this many parts (the first ones by name, each at every level and view); 0: all.
  std::size_t limit = 0;
  unsigned jobs = 1;            ///< samples evaluated in parallel (>= 1)
  std::string output_dir;       ///< gets eval.csv (one row per case, appended) and results.md
  bool progress = true;         ///< draw a progress bar on stderr
  MethodOptions method;         ///< assembler time limit, segmenter, ...
  MetricOptions metrics;        ///< samples and seeds
  FailureBox failure_box = FailureBox::ReferenceBoundingBox;  ///< what a failure is scored as
  /// Give the methods the input points without their normals (zeroed), as from a scanner that
  /// records none: the segmenter then estimates them.
  bool drop_input_normals = false;
};

/// What runBenchmark did.
struct BenchmarkRun {
  std::size_t cases_total = 0;      ///< cases (sample x method x assembler) selected
  std::size_t cases_resumed = 0;    ///< already in the CSV from an earlier run: skipped
  std::size_t cases_evaluated = 0;  ///< evaluated by this run
  std::size_t cases_failed = 0;     ///< of those, how many failed (any reason)
  std::size_t samples_unreadable = 0;  ///< samples whose data or GT mesh could not be read
  bool interrupted = false;         ///< stopped by Ctrl-C; run again to resume
  std::string csv_path, report_path;
};

/// Runs the evaluation, resuming from `output_dir`/eval.csv when it exists (the cases already in it
/// are skipped; a line cut by an interruption is dropped). A failure of one case never stops the
/// run: it becomes a row with its reason. Writes `output_dir`/results.md from the whole CSV at the
/// end (also after an interruption). Throws InvalidInputError for bad options (unknown method,
/// assembler, split or level) and IoError for an unreadable dataset or unwritable output.
/// Needs paco::data; throws InvalidInputError when this build has none.
BenchmarkRun runBenchmark(const BenchmarkOptions& options);

}  // namespace paco::evaluation
