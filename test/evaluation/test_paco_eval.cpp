// paco_eval single mode on good and bad input.
#include <paco/evaluation/report.h>
#include <paco/io/mesh_io.h>

#include <shapes.h>
#include <test_support.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace {

bool toolBuilt() { return std::filesystem::exists(paco::test::toolPath("paco_eval")); }
using paco::test::quoted;

}  // namespace

TEST(PacoEvalTool, SingleModePrintsTheMetrics) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_eval is not built";
  paco::test::TempDir dir;
  paco::io::saveMesh(dir.file("gt.obj"), paco::test::makeBox({0, 0, 0}, {1, 1, 1}));
  paco::io::saveMesh(dir.file("pred.off"), paco::test::makeBox({0.1, 0, 0}, {1.1, 1, 1}));
  std::string out;
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --pred " + quoted(dir.file("pred.off")) +
                                       " --gt " + quoted(dir.file("gt.obj")) + " --same-seed",
                                   &out),
            0)
      << out;
  for (const char* field : {"CD=", "HD=", "NC=", "#f=6", "#v=8", "closed=yes", "volume_ratio=1"})
    EXPECT_NE(out.find(field), std::string::npos) << field << " missing in: " << out;
  // HD of the shifted cube is 0.1 / sqrt(3) x 100 = 5.77 (see test_metrics.cpp).
  const auto hd = out.find("HD=");
  EXPECT_NEAR(std::stod(out.substr(hd + 3)), 5.77, 0.6) << out;
}

TEST(PacoEvalTool, InputSplitsGtToPredIntoSeenAndHidden) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_eval is not built";
  paco::test::TempDir dir;
  paco::io::saveMesh(dir.file("gt.obj"), paco::test::makeBox({0, 0, 0}, {1, 1, 1}));
  paco::io::saveMesh(dir.file("pred.obj"), paco::test::makeBox({0, 0, 0.5}, {1, 1, 1}));
  // The scan saw the top face only (a 0.05 grid): about 80 % of the GT surface is hidden (see
  // Metrics.GtToPredSplitsIntoTheSeenAndTheHiddenSurface).
  std::string scan;
  for (int i = 0; i <= 20; ++i)
    for (int j = 0; j <= 20; ++j) scan += std::to_string(0.05 * i) + " " + std::to_string(0.05 * j) + " 1\n";
  paco::test::writeBytes(dir.file("scan.xyz"), scan);
  const std::string command = paco::test::toolPath("paco_eval") + " --pred " + quoted(dir.file("pred.obj")) + " --gt " +
                              quoted(dir.file("gt.obj")) + " --input ";
  std::string out;
  ASSERT_EQ(paco::test::runCommand(command + quoted(dir.file("scan.xyz")), &out), 0) << out;
  const auto hidden = out.find("over the hidden ");
  ASSERT_NE(hidden, std::string::npos) << out;
  EXPECT_NEAR(std::stod(out.substr(hidden + 16)), 12.3, 0.5) << out;
  const auto share = out.find(" (", hidden);
  ASSERT_NE(share, std::string::npos) << out;
  EXPECT_NEAR(std::stod(out.substr(share + 2)), 80.0, 2.0) << out;
  // An unreadable scan is an error naming it.
  paco::test::writeBytes(dir.file("bad.xyz"), "1 2\n");
  EXPECT_NE(paco::test::runCommand(command + quoted(dir.file("bad.xyz")), &out), 0);
  EXPECT_NE(out.find("bad.xyz"), std::string::npos) << out;
}

TEST(PacoEvalTool, ScoreFailurePrintsTheBoxAndTheFloor) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_eval is not built";
  paco::test::TempDir dir;
  // A box-shaped GT is its own failure box: both lines are at the sampling floor.
  paco::io::saveMesh(dir.file("gt.obj"), paco::test::makeBox({0, 0, 0}, {2, 1, 1}));
  std::string out;
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --gt " + quoted(dir.file("gt.obj")) +
                                       " --score-failure",
                                   &out),
            0)
      << out;
  const auto failure = out.find("failure: CD="), floor = out.find("floor: CD=");
  ASSERT_NE(failure, std::string::npos) << out;
  ASSERT_NE(floor, std::string::npos) << out;
  EXPECT_LT(std::stod(out.substr(failure + 12)), 2.0) << out;
  EXPECT_LT(std::stod(out.substr(floor + 10)), 2.0) << out;
}

TEST(PacoEvalTool, SingleModeRejectsBadInput) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_eval is not built";
  paco::test::TempDir dir;
  paco::io::saveMesh(dir.file("gt.obj"), paco::test::makeBox({0, 0, 0}, {1, 1, 1}));
  std::string out;
  EXPECT_NE(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --pred " + quoted(dir.file("missing.obj")) +
                                       " --gt " + quoted(dir.file("gt.obj")),
                                   &out),
            0);
  EXPECT_NE(out.find("missing.obj"), std::string::npos) << out;
  // A mesh with vertices but no faces.
  paco::test::writeBytes(dir.file("points.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\n");
  EXPECT_NE(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --pred " + quoted(dir.file("points.obj")) +
                                       " --gt " + quoted(dir.file("gt.obj")),
                                   &out),
            0);
  EXPECT_NE(out.find("error"), std::string::npos) << out;
  // Garbage.
  paco::test::writeBytes(dir.file("junk.ply"), "this is not a ply file");
  EXPECT_NE(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --pred " + quoted(dir.file("junk.ply")) +
                                       " --gt " + quoted(dir.file("gt.obj")),
                                   &out),
            0);
  // Neither mode chosen: a usage error.
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_eval"), &out), 2) << out;
  // A point budget too small to segment anything.
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --dataset " + quoted(dir.file("none")) +
                                       " -o " + quoted(dir.file("out")) + " --max-points 100",
                                   &out),
            2)
      << out;
  EXPECT_NE(out.find("--max-points must be 0 (keep all) or at least 256"), std::string::npos) << out;
  // Levels, views and the segmenter's smallest plane, in the tool's own words.
  for (const auto& [options, message] : std::vector<std::pair<std::string, std::string>>{
           {" --levels 0,3", "--levels takes missing levels 0 (25 %), 1 (50 %) and 2 (75 %), got 3"},
           {" --views -1", "--views takes view indices >= 0, got -1"},
           {" --min-points 2", "--min-points must be 0 (1 % of the points) or at least 3, got 2"},
           {" --min-parallel-points 2",
            "--min-parallel-points must be -1 (none), 0 (0.15 % of the points) or at least 3, got 2"},
           {" --scanner-at-viewpoint --observed-fusion off", "--scanner-at-viewpoint works through observed fusion"}}) {
    EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --dataset " + quoted(dir.file("none")) +
                                         " -o " + quoted(dir.file("out")) + options,
                                     &out),
              2)
        << options << "\n" << out;
    EXPECT_NE(out.find(message), std::string::npos) << out;
    EXPECT_EQ(out.find("runBenchmark"), std::string::npos) << out;
  }
  // PolyFit weights that are negative, or all 0.
  for (const std::string weights : {" --coverage=-0.1", " --fitting 0 --coverage 0 --complexity 0"}) {
    EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_eval") + " --dataset " + quoted(dir.file("none")) +
                                         " -o " + quoted(dir.file("out")) + weights,
                                     &out),
              2)
        << weights << ": " << out;
    EXPECT_NE(out.find("must be >= 0 and not all 0"), std::string::npos) << out;
  }
}

TEST(PacoEvalTool, CompareReportsThePairedDifferencesOfTwoRuns) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_eval is not built";
  paco::test::TempDir dir;
  auto write = [&](const std::string& path, const std::vector<std::pair<std::string, double>>& chamfers) {
    std::ofstream out(path);
    out << paco::evaluation::csvHeader() << "\n";
    for (const auto& [part, cd] : chamfers) {
      paco::evaluation::EvaluationRecord r;
      r.method = "direct";
      r.assembler = "polyfit";
      r.part = part;
      r.chamfer = cd;
      r.hausdorff = 10.0 * cd;
      r.normal_consistency = 0.9;
      paco::evaluation::appendRecord(out, r);
    }
  };
  std::filesystem::create_directories(dir.file("before"));
  write(dir.file("before") + "/eval.csv", {{"a", 2.0}, {"b", 4.0}});
  write(dir.file("after.csv"), {{"a", 3.0}, {"b", 4.0}});
  const std::string tool = paco::test::toolPath("paco_eval");
  std::string out;
  // A run folder and a CSV file are both accepted.
  ASSERT_EQ(paco::test::runCommand(tool + " --compare " + quoted(dir.file("before")) + " " + quoted(dir.file("after.csv")), &out),
            0)
      << out;
  EXPECT_NE(out.find("| direct | polyfit | 0 | 2 | 0 -> 0 | 3.000 -> 3.500 (+0.500 ± 0.500) | 30.00 -> 35.00 (+5.00 ± 5.00) |"),
            std::string::npos)
      << out;
  // Bad input: one run, a missing run, a file that is not an eval.csv, runs with no case in common.
  EXPECT_EQ(paco::test::runCommand(tool + " --compare " + quoted(dir.file("after.csv")), &out), 2) << out;
  EXPECT_NE(out.find("takes two runs"), std::string::npos) << out;
  EXPECT_EQ(paco::test::runCommand(tool + " --compare " + quoted(dir.file("after.csv")) + " " + quoted(dir.file("none")), &out),
            1)
      << out;
  EXPECT_NE(out.find("no evaluation results"), std::string::npos) << out;
  {
    std::ofstream other(dir.file("other.csv"));
    other << "x,y\n1,2\n";
  }
  EXPECT_EQ(paco::test::runCommand(tool + " --compare " + quoted(dir.file("other.csv")) + " " + quoted(dir.file("after.csv")), &out),
            1)
      << out;
  EXPECT_NE(out.find("is not an eval.csv"), std::string::npos) << out;
  write(dir.file("elsewhere.csv"), {{"c", 1.0}});
  EXPECT_EQ(paco::test::runCommand(tool + " --compare " + quoted(dir.file("elsewhere.csv")) + " " + quoted(dir.file("after.csv")), &out),
            1)
      << out;
  EXPECT_NE(out.find("no case in common"), std::string::npos) << out;
}
