// Failure classification, the CSV (with resume after an interruption) and the Markdown tables.
#include <paco/common/error.h>
#include <paco/evaluation/report.h>

#include <shapes.h>
#include <test_support.h>

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

namespace ev = paco::evaluation;

TEST(ClassifyMesh, NamesEachDefect) {
  const paco::SurfaceMesh box = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  EXPECT_EQ(ev::classifyMesh(box), ev::FailureReason::None);
  EXPECT_EQ(ev::classifyMesh(paco::SurfaceMesh{}), ev::FailureReason::EmptyMesh);

  paco::SurfaceMesh open = box;
  open.faces.pop_back();
  EXPECT_EQ(ev::classifyMesh(open), ev::FailureReason::NotClosed);

  paco::SurfaceMesh flipped = box;
  std::reverse(flipped.faces[0].begin(), flipped.faces[0].end());
  EXPECT_EQ(ev::classifyMesh(flipped), ev::FailureReason::NotOriented);

  paco::SurfaceMesh fin = box;  // a third face on the edge (0,1): non-manifold
  fin.vertices.emplace_back(0.5, -1.0, 0.0);
  fin.faces.push_back({0, 1, static_cast<std::uint32_t>(fin.vertices.size() - 1)});
  EXPECT_EQ(ev::classifyMesh(fin), ev::FailureReason::NotManifold);

  paco::SurfaceMesh flat;  // faces without area
  flat.vertices = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}};
  flat.faces = {{0, 1, 2}};
  EXPECT_EQ(ev::classifyMesh(flat), ev::FailureReason::EmptyMesh);
}

TEST(FailureReason, NamesRoundTrip) {
  for (auto r : {ev::FailureReason::None, ev::FailureReason::NoMesh, ev::FailureReason::EmptyMesh,
                 ev::FailureReason::NotClosed, ev::FailureReason::NotManifold, ev::FailureReason::NotOriented,
                 ev::FailureReason::TimeLimit, ev::FailureReason::Threw, ev::FailureReason::Sanity})
    EXPECT_EQ(ev::failureReasonFromString(ev::toString(r)), r);
  EXPECT_THROW(ev::failureReasonFromString("bogus"), paco::InvalidInputError);
}

namespace {

ev::EvaluationRecord record(const std::string& method, const std::string& part, int level, ev::FailureReason reason,
                            double cd, double hd, double nc) {
  ev::EvaluationRecord r;
  r.method = method;
  r.assembler = "polyfit";
  r.part = part;
  r.level = level;
  r.reason = reason;
  r.chamfer = cd;
  r.chamfer_pred_to_gt = 0.4 * cd;
  r.chamfer_gt_to_pred = 0.6 * cd;
  r.hausdorff = hd;
  r.normal_consistency = nc;
  if (reason == ev::FailureReason::None) {
    r.num_faces = 10;
    r.num_vertices = 16;
    r.volume_ratio = 0.8;
  }
  r.seconds = {{"assemble", 0.5}, {"total", 1.0}};
  return r;
}

}  // namespace

TEST(Csv, RoundTripsAndDropsALineCutByAnInterruption) {
  paco::test::TempDir dir;
  const std::string path = dir.file("eval.csv");
  ev::EvaluationRecord a = record("direct", "part,with \"comma\"", 2, ev::FailureReason::NotClosed, 6.0, 23.7, 0.753);
  a.nc_prim = 0.9;
  a.unmatched_predicted = 2;
  a.message = "3 boundary edges";
  a.chamfer_pred_to_gt = 2.5;
  a.chamfer_gt_to_pred = 3.5;
  a.hidden_fraction = 0.75;
  a.chamfer_gt_to_pred_seen = 0.5;
  a.chamfer_gt_to_pred_hidden = 4.5;
  a.nc_pred_to_gt = 0.8;
  a.nc_gt_to_pred = 0.706;
  a.nc_gt_to_pred_seen = 0.95;
  a.nc_gt_to_pred_hidden = 0.625;
  const ev::EvaluationRecord b = record("oracle", "p2", 0, ev::FailureReason::None, 1.61, 3.45, 0.957);
  {
    std::ofstream out(path);
    out << ev::csvHeader() << '\n';
    ev::appendRecord(out, a);
    ev::appendRecord(out, b);
    out << "oracle,polyfit,p3,1,0,ok,none,1.2";  // cut mid-line, no newline
  }
  std::size_t skipped = 0;
  const auto records = ev::readRecords(path, &skipped);
  ASSERT_EQ(records.size(), 2u);
  EXPECT_EQ(skipped, 1u);
  EXPECT_EQ(records[0].part, a.part);
  EXPECT_EQ(records[0].reason, ev::FailureReason::NotClosed);
  EXPECT_DOUBLE_EQ(records[0].chamfer, 6.0);
  EXPECT_DOUBLE_EQ(records[0].chamfer_pred_to_gt, 2.5);
  EXPECT_DOUBLE_EQ(records[0].chamfer_gt_to_pred, 3.5);
  EXPECT_DOUBLE_EQ(records[0].hidden_fraction, 0.75);
  EXPECT_DOUBLE_EQ(records[0].chamfer_gt_to_pred_seen, 0.5);
  EXPECT_DOUBLE_EQ(records[0].chamfer_gt_to_pred_hidden, 4.5);
  EXPECT_DOUBLE_EQ(records[0].nc_pred_to_gt, 0.8);
  EXPECT_DOUBLE_EQ(records[0].nc_gt_to_pred, 0.706);
  EXPECT_DOUBLE_EQ(records[0].nc_gt_to_pred_seen, 0.95);
  EXPECT_DOUBLE_EQ(records[0].nc_gt_to_pred_hidden, 0.625);
  EXPECT_DOUBLE_EQ(records[0].nc_prim, 0.9);
  EXPECT_EQ(records[0].unmatched_predicted, 2);
  EXPECT_EQ(records[0].message, a.message);
  EXPECT_TRUE(std::isnan(records[0].volume_ratio));
  EXPECT_EQ(records[1].key(), b.key());
  EXPECT_DOUBLE_EQ(records[1].volume_ratio, 0.8);
  EXPECT_DOUBLE_EQ(records[1].seconds.at("assemble"), 0.5);
  EXPECT_EQ(records[1].nc_prim, -1.0);
  EXPECT_TRUE(std::isnan(records[1].hidden_fraction));  // not measured: an empty field

  EXPECT_TRUE(ev::readRecords(dir.file("missing.csv")).empty());
  paco::test::writeBytes(dir.file("other.csv"), "a,b,c\n1,2,3\n");
  EXPECT_THROW(ev::readRecords(dir.file("other.csv")), paco::IoError);
}

TEST(Summary, FailureRateClosedOnlyFiguresAndReasons) {
  const std::vector<ev::EvaluationRecord> rs = {
      record("direct", "a", 0, ev::FailureReason::None, 2.0, 4.0, 0.9),
      record("direct", "b", 0, ev::FailureReason::None, 4.0, 8.0, 0.8),
      record("direct", "c", 0, ev::FailureReason::NotClosed, 6.0, 24.0, 0.75),
      record("direct", "d", 0, ev::FailureReason::TimeLimit, 8.0, 20.0, 0.7)};
  const ev::Summary s = ev::summarize(rs);
  EXPECT_EQ(s.count, 4u);
  EXPECT_EQ(s.failures, 2u);
  EXPECT_DOUBLE_EQ(s.failureRate(), 50.0);
  EXPECT_DOUBLE_EQ(s.chamfer, 5.0);
  EXPECT_DOUBLE_EQ(s.chamfer_pred_to_gt, 2.0);
  EXPECT_DOUBLE_EQ(s.chamfer_gt_to_pred, 3.0);
  EXPECT_DOUBLE_EQ(s.hausdorff, 14.0);
  EXPECT_DOUBLE_EQ(s.normal_consistency, (0.9 + 0.8 + 0.75 + 0.7) / 4.0);
  EXPECT_DOUBLE_EQ(s.closed_chamfer, 3.0);
  EXPECT_DOUBLE_EQ(s.closed_hausdorff, 6.0);
  EXPECT_DOUBLE_EQ(s.faces, 10.0);
  EXPECT_DOUBLE_EQ(s.volume_ratio_median, 0.8);
  EXPECT_EQ(s.failures_by_reason.at(ev::FailureReason::NotClosed), 1u);
  EXPECT_EQ(s.failures_by_reason.at(ev::FailureReason::TimeLimit), 1u);
  EXPECT_DOUBLE_EQ(s.mean_seconds.at("assemble"), 0.5);
  EXPECT_EQ(s.hidden_fraction, -1.0);  // no record measured the split
}

TEST(Summary, SeenAndHiddenMeansSkipTheCasesWithoutThem) {
  std::vector<ev::EvaluationRecord> rs = {record("paco", "a", 2, ev::FailureReason::None, 2.0, 4.0, 0.9),
                                          record("paco", "b", 2, ev::FailureReason::None, 4.0, 8.0, 0.8),
                                          record("paco", "c", 2, ev::FailureReason::None, 6.0, 9.0, 0.8)};
  rs[0].hidden_fraction = 0.6;
  rs[0].chamfer_gt_to_pred_seen = 0.5;
  rs[0].chamfer_gt_to_pred_hidden = 1.5;
  rs[1].hidden_fraction = 1.0;  // all hidden: no seen value
  rs[1].chamfer_gt_to_pred_hidden = 2.5;
  rs[0].nc_gt_to_pred_seen = 0.95;
  rs[0].nc_gt_to_pred_hidden = 0.75;
  rs[1].nc_gt_to_pred_hidden = 0.5;
  for (auto& r : rs) {
    r.nc_pred_to_gt = r.normal_consistency + 0.02;
    r.nc_gt_to_pred = r.normal_consistency - 0.02;
  }
  const ev::Summary s = ev::summarize(rs);  // rs[2] measured nothing
  EXPECT_DOUBLE_EQ(s.hidden_fraction, 0.8);
  EXPECT_DOUBLE_EQ(s.chamfer_gt_to_pred_seen, 0.5);
  EXPECT_DOUBLE_EQ(s.chamfer_gt_to_pred_hidden, 2.0);
  EXPECT_DOUBLE_EQ(s.nc_gt_to_pred_seen, 0.95);
  EXPECT_DOUBLE_EQ(s.nc_gt_to_pred_hidden, 0.625);
  const std::string md = ev::markdownReport(rs);
  EXPECT_NE(md.find("| 1.60 / 2.40 | 0.50 / 2.00 (80) | 7.00 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| 0.853 / 0.813 (0.950 / 0.625) |"), std::string::npos) << md;
}

TEST(Markdown, OneTablePerLevelAndOverall) {
  std::vector<ev::EvaluationRecord> rs = {record("direct", "a", 0, ev::FailureReason::None, 2.0, 4.0, 0.9),
                                          record("direct", "a", 2, ev::FailureReason::NoMesh, 6.0, 24.0, 0.75),
                                          record("sanity", "a", 0, ev::FailureReason::Sanity, 6.0, 24.0, 0.75),
                                          record("oracle", "a", 2, ev::FailureReason::None, 1.6, 3.4, 0.95)};
  const std::string md = ev::markdownReport(rs, "Title", "Some notes.");
  EXPECT_NE(md.find("# Title"), std::string::npos);
  EXPECT_NE(md.find("Some notes."), std::string::npos);
  EXPECT_NE(md.find("## Simple (25 % missing)"), std::string::npos);
  EXPECT_EQ(md.find("## Moderate"), std::string::npos);
  EXPECT_NE(md.find("## Hard (75 % missing)"), std::string::npos);
  EXPECT_NE(md.find("## Overall"), std::string::npos);
  EXPECT_NE(md.find("| direct | polyfit | 1 | 100.0 | 6.00 | 2.40 / 3.60 | – | 24.00 | 0.750 |"), std::string::npos) << md;
  EXPECT_NE(md.find("no-mesh 1"), std::string::npos);
  EXPECT_NE(md.find("t assemble (s)"), std::string::npos);
  // The sanity row comes after the methods.
  const std::string simple = md.substr(md.find("## Simple"), md.find("## Hard") - md.find("## Simple"));
  EXPECT_LT(simple.find("| direct"), simple.find("| sanity"));
}

TEST(Markdown, LatencyTableHasMedianAndNinetiethPercentile) {
  std::vector<ev::EvaluationRecord> rs;
  // Assembly times 1..10 s: median 5.5, 90th percentile (linear between ranks) 9.1.
  for (int i = 1; i <= 10; ++i) {
    ev::EvaluationRecord r = record("direct", "p" + std::to_string(i), i % 3, ev::FailureReason::None, 2.0, 4.0, 0.9);
    r.seconds = {{"segment", 0.1}, {"assemble", static_cast<double>(i)}, {"total", i + 0.1}};
    rs.push_back(r);
  }
  const ev::Summary s = ev::summarize(rs);
  EXPECT_DOUBLE_EQ(s.median_seconds.at("assemble"), 5.5);
  EXPECT_DOUBLE_EQ(s.p90_seconds.at("assemble"), 9.1);
  rs.push_back(record("sanity", "p1", 0, ev::FailureReason::Sanity, 6.0, 24.0, 0.75));
  const std::string md = ev::markdownReport(rs);
  const std::size_t latency = md.find("## Latency");
  ASSERT_NE(latency, std::string::npos) << md;
  const std::string section = md.substr(latency);
  EXPECT_NE(section.find("| Method | Assembler | N | segment | assemble | total |"), std::string::npos) << section;
  EXPECT_NE(section.find("| direct | polyfit | 10 | 0.100 / 0.100 | 5.500 / 9.100 | 5.600 / 9.200 |"), std::string::npos)
      << section;
  EXPECT_EQ(section.find("| sanity"), std::string::npos);  // nothing ran: no latency
}

namespace {

ev::EvaluationRecord pairedCase(const std::string& part, int level, double cd, double hd, double nc, double nc_prim,
                                bool failed = false) {
  ev::EvaluationRecord r;
  r.method = "paco";
  r.assembler = "polyfit";
  r.part = part;
  r.level = level;
  r.chamfer = cd;
  r.hausdorff = hd;
  r.normal_consistency = nc;
  r.nc_prim = nc_prim;
  if (failed) r.reason = ev::FailureReason::NoMesh;
  return r;
}

}  // namespace

TEST(PairedComparison, DifferencesAndStandardErrorsAreTheHandComputedOnes) {
  // Level 0: CD 2 -> 3 and 4 -> 4 (differences +1 and 0); level 1: CD 5 -> 3 (-2), failed after.
  // Part "x" is in the first run only, part "y" in the second only; part "z" has no NC_prim after.
  const std::vector<ev::EvaluationRecord> before = {
      pairedCase("a", 0, 2.0, 10.0, 0.8, 0.5), pairedCase("b", 0, 4.0, 12.0, 0.9, 0.7),
      pairedCase("c", 1, 5.0, 20.0, 0.7, 0.4), pairedCase("x", 0, 1.0, 1.0, 1.0, 1.0)};
  const std::vector<ev::EvaluationRecord> after = {
      pairedCase("a", 0, 3.0, 11.0, 0.8, 0.6), pairedCase("b", 0, 4.0, 10.0, 0.95, 0.7),
      pairedCase("c", 1, 3.0, 26.0, 0.6, -1.0, true), pairedCase("y", 1, 9.0, 9.0, 0.0, 0.0)};
  const auto comparisons = ev::comparePaired(before, after);
  ASSERT_EQ(comparisons.size(), 3u);  // level 0, level 1, all

  const ev::PairedComparison& simple = comparisons[0];
  EXPECT_EQ(simple.level, 0);
  EXPECT_EQ(simple.only_before, 1u);
  EXPECT_EQ(simple.only_after, 0u);
  EXPECT_EQ(simple.chamfer.count, 2u);
  EXPECT_DOUBLE_EQ(simple.chamfer.before, 3.0);
  EXPECT_DOUBLE_EQ(simple.chamfer.after, 3.5);
  EXPECT_DOUBLE_EQ(simple.chamfer.difference, 0.5);
  // Differences +1 and 0: sample standard deviation sqrt(0.5), standard error sqrt(0.5) / sqrt(2) = 0.5.
  EXPECT_DOUBLE_EQ(simple.chamfer.standard_error, 0.5);
  EXPECT_EQ(simple.chamfer.changed, 1u);
  EXPECT_DOUBLE_EQ(simple.hausdorff.difference, -0.5);  // +1 and -2
  EXPECT_DOUBLE_EQ(simple.hausdorff.standard_error, 1.5);
  EXPECT_NEAR(simple.normal_consistency.difference, 0.025, 1e-12);
  EXPECT_NEAR(simple.nc_prim.difference, 0.05, 1e-12);

  const ev::PairedComparison& moderate = comparisons[1];
  EXPECT_EQ(moderate.level, 1);
  EXPECT_EQ(moderate.only_after, 1u);
  EXPECT_EQ(moderate.failed_before, 0u);
  EXPECT_EQ(moderate.failed_after, 1u);
  EXPECT_DOUBLE_EQ(moderate.chamfer.difference, -2.0);  // the failed case takes part with its score
  EXPECT_DOUBLE_EQ(moderate.chamfer.standard_error, 0.0);  // one case
  EXPECT_EQ(moderate.nc_prim.count, 0u);                  // not applicable after

  const ev::PairedComparison& all = comparisons[2];
  EXPECT_EQ(all.level, -1);
  EXPECT_EQ(all.chamfer.count, 3u);
  EXPECT_EQ(all.only_before, 1u);
  EXPECT_EQ(all.only_after, 1u);
  EXPECT_DOUBLE_EQ(all.chamfer.difference, -1.0 / 3.0);  // (+1 + 0 - 2) / 3
  // Deviations 4/3, 1/3, -5/3: squares sum 42/9; variance 42/18; standard error sqrt(42/18/3).
  EXPECT_NEAR(all.chamfer.standard_error, std::sqrt(42.0 / 18.0 / 3.0), 1e-12);
  EXPECT_EQ(all.nc_prim.count, 2u);

  const std::string md = ev::markdownComparison(comparisons, "before", "after");
  EXPECT_NE(md.find("# before -> after"), std::string::npos) << md;
  EXPECT_NE(md.find("| paco | polyfit | 0 | 2 (1 only before, 0 only after) | 0 -> 0 | 3.000 -> 3.500 (+0.500 ± 0.500) |"),
            std::string::npos)
      << md;
  EXPECT_NE(md.find("| paco | polyfit | 1 | 1 (0 only before, 1 only after) | 0 -> 1 |"), std::string::npos) << md;
}

TEST(PairedComparison, RunsWithoutACommonCaseGiveNothing) {
  const std::vector<ev::EvaluationRecord> before = {pairedCase("a", 0, 2.0, 10.0, 0.8, 0.5)};
  std::vector<ev::EvaluationRecord> after = {pairedCase("a", 0, 2.0, 10.0, 0.8, 0.5)};
  after[0].assembler = "cell-complex";
  EXPECT_TRUE(ev::comparePaired(before, after).empty());
  EXPECT_TRUE(ev::comparePaired({}, before).empty());
  // One level only: no "all" row.
  EXPECT_EQ(ev::comparePaired(before, before).size(), 1u);
}

// A row whose CD, HD or NC is not a finite number is malformed: read, it made every mean it
// joined NaN ("2.754 -> nan" in paco_eval --compare). It is skipped and counted, as a cut line is.
TEST(EvaluationCsv, RowsWithANonFiniteMetricAreSkippedAndCounted) {
  paco::test::TempDir dir;
  std::ofstream out(dir.file("eval.csv"));
  out << ev::csvHeader() << '\n';
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const double cd : {2.0, nan, std::numeric_limits<double>::infinity(), 3.0}) {
    ev::EvaluationRecord r = pairedCase("part" + std::to_string(static_cast<int>(out.tellp())), 0, cd, 10.0, 0.8, 0.5);
    ev::appendRecord(out, r);
  }
  ev::EvaluationRecord no_nc = pairedCase("no-nc", 0, 2.0, 10.0, nan, 0.5);
  ev::appendRecord(out, no_nc);
  out.close();
  std::size_t skipped = 0;
  const auto records = ev::readRecords(dir.file("eval.csv"), &skipped);
  ASSERT_EQ(records.size(), 2u);
  EXPECT_DOUBLE_EQ(records[0].chamfer, 2.0);
  EXPECT_DOUBLE_EQ(records[1].chamfer, 3.0);
  EXPECT_EQ(skipped, 3u);
}
