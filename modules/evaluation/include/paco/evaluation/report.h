#pragma once
// Usage:
//   paco::evaluation::EvaluationRecord r; r.method = "direct"; ...;     // one CSV row per case
//   paco::evaluation::appendRecord(csv_stream, r);                      // header: csvHeader()
//   std::string md = paco::evaluation::markdownReport(paco::evaluation::readRecords("eval.csv"));
//   std::string diff = paco::evaluation::markdownComparison(
//       paco::evaluation::comparePaired(readRecords("a/eval.csv"), readRecords("b/eval.csv")), "a", "b");
#include <paco/common/surface_mesh.h>
#include <paco/evaluation/metrics.h>

#include <cstddef>
#include <limits>
#include <map>
#include <ostream>
#include <string>
#include <vector>

namespace paco::evaluation {

/// Why a case counts as failed (the FR of the paper, with every reason named).
enum class FailureReason {
  None,         ///< not failed: a closed, manifold, consistently oriented mesh
  NoMesh,       ///< the method produced no mesh
  EmptyMesh,    ///< the mesh has no faces (or no area)
  NotClosed,    ///< the mesh has boundary edges
  NotManifold,  ///< the mesh has non-manifold edges or vertices
  NotOriented,  ///< closed and manifold, but its faces are not consistently oriented
  TimeLimit,    ///< the solver ran out of its time budget
  Threw,        ///< the pipeline threw an exception
  Sanity,       ///< the "sanity" row: every case scored as failed on purpose (Table S1)
};

/// "none", "no-mesh", "empty", "not-closed", "not-manifold", "not-oriented", "time-limit",
/// "threw", "sanity".
std::string toString(FailureReason reason);
/// The inverse of toString; throws InvalidInputError for an unknown name.
FailureReason failureReasonFromString(const std::string& name);

/// Classifies a produced mesh: EmptyMesh, NotManifold, NotClosed, NotOriented or None.
FailureReason classifyMesh(const SurfaceMesh& mesh);

/// One evaluated case: a method + assembler on one sample. Metrics of failed cases are the
/// failure-box scores (evaluateFailure), as in the paper.
struct EvaluationRecord {
  std::string method;          ///< "direct", "oracle", "poisson-qem", "box-prior", "paco", "sanity"
  std::string assembler;       ///< "polyfit", "cell-complex", or "-" where none applies
  std::string part;            ///< part name
  int level = 0;               ///< 0 simple (25 %), 1 moderate (50 %), 2 hard (75 %)
  int view = 0;                ///< view index
  FailureReason reason = FailureReason::None;  ///< None: succeeded
  double chamfer = 0.0;        ///< CD x 100 (the box's score when failed)
  double chamfer_pred_to_gt = 0.0;  ///< CD's half from the prediction to the GT, x 100
  double chamfer_gt_to_pred = 0.0;  ///< CD's half from the GT to the prediction, x 100
  double hausdorff = 0.0;      ///< HD x 100
  double normal_consistency = 0.0;  ///< NC
  double nc_pred_to_gt = 0.0, nc_gt_to_pred = 0.0;  ///< NC's two directions (MeshMetrics)
  double nc_prim = -1.0;       ///< NC_prim of the primitives given to the assembler; < 0: not applicable
  int unmatched_predicted = -1;///< predicted planes without a GT partner; < 0: not applicable
  std::size_t num_faces = 0;   ///< #f (0 when failed)
  std::size_t num_vertices = 0;///< #v (0 when failed)
  double volume_ratio = std::numeric_limits<double>::quiet_NaN();  ///< predicted / GT volume; NaN when not closed
  /// GT->pred split by the partial input (MeshMetrics): the hidden share of the GT surface, and
  /// GT->pred x 100 over its seen and its hidden part. NaN when not measured or empty.
  double hidden_fraction = std::numeric_limits<double>::quiet_NaN();
  double chamfer_gt_to_pred_seen = std::numeric_limits<double>::quiet_NaN();
  double chamfer_gt_to_pred_hidden = std::numeric_limits<double>::quiet_NaN();
  /// NC's GT->pred direction over the seen and the hidden GT surface. NaN when not measured or empty.
  double nc_gt_to_pred_seen = std::numeric_limits<double>::quiet_NaN();
  double nc_gt_to_pred_hidden = std::numeric_limits<double>::quiet_NaN();
  /// Wall time per stage in seconds, e.g. {"segment", 0.12}, {"assemble", 0.8}; "total" is added.
  std::map<std::string, double> seconds;
  std::string message;         ///< why it failed, or empty

  bool failed() const { return reason != FailureReason::None; }
  /// Takes CD (and its halves, and GT->pred's seen and hidden parts), HD and NC (and its halves,
  /// and its GT->pred seen and hidden parts) from `metrics`.
  void setScores(const MeshMetrics& metrics);
  /// The resume key: method|assembler|part|level|view.
  std::string key() const;
};

/// The stage names that have a column in the CSV, in order.
const std::vector<std::string>& stageNames();
/// The CSV header line (no newline).
std::string csvHeader();
/// Writes one record as a CSV line (with a newline), quoting text fields as needed.
void appendRecord(std::ostream& out, const EvaluationRecord& record);
/// Reads a CSV written by appendRecord. Lines that are incomplete (an interrupted write) or
/// malformed are skipped and counted in `skipped_lines` when given. Throws IoError when the
/// file exists but its header is not ours. A missing file gives no records.
std::vector<EvaluationRecord> readRecords(const std::string& path, std::size_t* skipped_lines = nullptr);

/// Aggregate of a group of records (one table row).
struct Summary {
  std::size_t count = 0;
  std::size_t failures = 0;
  std::map<FailureReason, std::size_t> failures_by_reason;
  double chamfer = 0.0, hausdorff = 0.0, normal_consistency = 0.0;  ///< means over all cases
  double chamfer_pred_to_gt = 0.0, chamfer_gt_to_pred = 0.0;         ///< means over all cases
  /// Means over the cases that measured them (< 0: none): the hidden share of the GT surface and
  /// GT->pred over the seen and the hidden GT surface.
  double hidden_fraction = -1.0, chamfer_gt_to_pred_seen = -1.0, chamfer_gt_to_pred_hidden = -1.0;
  double nc_pred_to_gt = -1.0, nc_gt_to_pred = -1.0;  ///< means over all cases
  double nc_gt_to_pred_seen = -1.0, nc_gt_to_pred_hidden = -1.0;  ///< as chamfer_gt_to_pred_seen
  double nc_prim = -1.0;             ///< mean over the cases where it applies; < 0: none
  double unmatched_predicted = -1.0; ///< mean; < 0: not applicable
  double closed_chamfer = -1.0, closed_hausdorff = -1.0;  ///< means over the succeeded cases; < 0: none
  double faces = 0.0, vertices = 0.0;  ///< means over the succeeded cases
  double volume_ratio_median = std::numeric_limits<double>::quiet_NaN();  ///< median over the succeeded cases
  std::map<std::string, double> mean_seconds;  ///< per stage, over all cases that ran it
  std::map<std::string, double> median_seconds, p90_seconds;  ///< per stage: median and 90th percentile
  double failureRate() const { return count ? 100.0 * static_cast<double>(failures) / static_cast<double>(count) : 0.0; }
};
Summary summarize(const std::vector<EvaluationRecord>& records);

/// Markdown report: one table per level present (simple / moderate / hard) and one overall, one
/// row per method and assembler (like the paper's Tables 1, 2 and 4), with FR, CD, HD, NC,
/// NC_prim, closed-only CD/HD, volume ratio, #f, #v, failures by reason and time per stage.
/// Then a latency table: median and 90th percentile of each stage's wall time per method and
/// assembler, over all levels. `title` heads the document; `notes` (may be empty) follows it
/// verbatim.
std::string markdownReport(const std::vector<EvaluationRecord>& records, const std::string& title = "Evaluation",
                           const std::string& notes = "");

/// One metric compared case by case between two runs of the same cases.
struct PairedDifference {
  std::size_t count = 0;        ///< cases in both runs where the metric applies
  double before = 0.0, after = 0.0;  ///< means over those cases
  double difference = 0.0;      ///< mean of (after - before)
  double standard_error = 0.0;  ///< of that mean: sample standard deviation / sqrt(count); 0 for one case
  std::size_t changed = 0;      ///< cases whose value differs
};

/// Two runs of one method and assembler compared on the cases both have (matched by
/// EvaluationRecord::key()), for one level or all of them. A failed case takes part with its
/// failure-box scores, as it does in the report's means; NC_prim only where both runs have it.
struct PairedComparison {
  std::string method, assembler;
  int level = -1;                        ///< -1: all levels
  std::size_t only_before = 0, only_after = 0;  ///< cases that one run lacks (left out)
  std::size_t failed_before = 0, failed_after = 0;  ///< among the compared cases
  PairedDifference chamfer, hausdorff, normal_consistency, nc_prim;
};

/// One comparison per method + assembler present in both runs and per level, then over all levels
/// (only when there is more than one level), in that order.
std::vector<PairedComparison> comparePaired(const std::vector<EvaluationRecord>& before,
                                            const std::vector<EvaluationRecord>& after);

/// The comparisons as a Markdown table: per row the method, assembler, level, cases, failures
/// before -> after, and for CD, HD, NC and NC_prim the means before -> after with the paired
/// difference ± its standard error. `before_name` and `after_name` head the document.
std::string markdownComparison(const std::vector<PairedComparison>& comparisons, const std::string& before_name,
                               const std::string& after_name);

}  // namespace paco::evaluation
