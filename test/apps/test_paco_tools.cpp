// The checks the paco_* tools share (apps/app_support.h): no output may replace an input; counts
// given as negative numbers and more threads than make sense are usage errors; labels may be any
// numbers; an output extension error names the user's path; and option errors speak of the
// tool's options and units, not of the library's classes. Every refusal comes before any slow
// work and leaves the files as they were.
#include "shapes.h"
#include "test_support.h"

#ifdef PACO_TEST_WITH_COMPLETION
#include <torch/torch.h>  // before PCL-using headers (see doc/training.md)

#include <paco/completion/checkpoint.h>

#include "tiny_model_config.h"
#endif

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/surface_mesh.h>
#include <paco/io/cloud_io.h>

#include <gtest/gtest.h>

#include "app_support.h"

#include <cmath>
#include <filesystem>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using paco::test::TempDir;

using paco::test::quoted;
std::string tool(const std::string& name) { return quoted(paco::test::toolPath(name)); }

// Whether this build has the tool (the tools of missing modules are not built).
bool built(const std::string& name) {
  return ("," + std::string(PACO_BUILT_TOOLS) + ",").find("," + name + ",") != std::string::npos;
}

#define REQUIRE_TOOLS(...)                                   \
  for (const char* required : {__VA_ARGS__}) {               \
    if (!built(required)) GTEST_SKIP() << required << " is not built"; \
  }

// 2400 points on the box [0,2] x [0,1] x [0,1] with normals, labelled by face as 10, 13, ..., 25
// (label ids that are not 0..5).
paco::io::LabelledCloud sparselyLabelledBox() {
  const paco::SurfaceSample surface = paco::sampleSurface(paco::test::makeBox({0, 0, 0}, {2, 1, 1}), 2400, 5);
  paco::io::LabelledCloud cloud;
  cloud.has_normals = true;
  for (std::size_t i = 0; i < surface.points.size(); ++i) {
    pcl::PointNormal p;
    p.x = float(surface.points[i].x()), p.y = float(surface.points[i].y()), p.z = float(surface.points[i].z());
    p.normal_x = float(surface.normals[i].x()), p.normal_y = float(surface.normals[i].y()),
    p.normal_z = float(surface.normals[i].z());
    cloud.points.push_back(p);
    cloud.labels.push_back(10 + 3 * static_cast<int>(surface.faces[i]));
  }
  return cloud;
}

// Runs `command`, which must be refused as a usage error before reading anything, with `message`
// in its log, and leave `kept` (an input) as it was. Returns the log.
std::string expectRefused(const std::string& command, const std::string& message, const std::string& kept = "") {
  const std::string before = kept.empty() ? "" : paco::test::readBytes(kept);
  std::string log;
  EXPECT_EQ(paco::test::runCommand(command, &log), 2) << command << "\n" << log;
  EXPECT_NE(log.find(message), std::string::npos) << command << "\n" << log;
  EXPECT_EQ(log.find("read '"), std::string::npos) << command << "\n" << log;
  if (!kept.empty()) {
    EXPECT_EQ(paco::test::readBytes(kept), before) << kept << " changed by " << command;
  }
  return log;
}

TEST(PacoTools, AnOutputThatIsAnInputIsRefused) {
  REQUIRE_TOOLS("paco_convert", "paco_segment", "paco_assemble", "paco_complete", "paco_reconstruct");
  TempDir dir;
  const paco::io::LabelledCloud box = sparselyLabelledBox();
  for (const char* name : {"box.xyz", "box.ply", "box.vg", "m.partial.xyz", "m_primitives.pcd"})
    paco::io::saveCloud(dir.file(name), box);
  const std::string xyz = dir.file("box.xyz"), ply = dir.file("box.ply"), vg = dir.file("box.vg");

  expectRefused(tool("paco_convert") + " " + quoted(xyz) + " " + quoted(xyz),
                "OUTPUT '" + xyz + "' is the same file as INPUT '" + xyz +
                    "': writing it would replace that input; give OUTPUT another file name",
                xyz);
  // The same file by another name: through "..", a symbolic link, a hard link.
  fs::create_directory(dir.file("sub"));
  expectRefused(tool("paco_convert") + " " + quoted(xyz) + " " + quoted(dir.file("sub/../box.xyz")),
                "is the same file as INPUT", xyz);
  fs::create_symlink(xyz, dir.file("link.xyz"));
  expectRefused(tool("paco_convert") + " " + quoted(dir.file("link.xyz")) + " " + quoted(xyz),
                "is the same file as INPUT", xyz);
  fs::create_hard_link(xyz, dir.file("hard.xyz"));
  expectRefused(tool("paco_convert") + " " + quoted(dir.file("hard.xyz")) + " " + quoted(xyz),
                "is the same file as INPUT", xyz);
  // The temporary file an output is written to first is an output too.
  expectRefused(tool("paco_convert") + " " + quoted(dir.file("m.partial.xyz")) + " " + quoted(dir.file("m.xyz")),
                "OUTPUT '" + dir.file("m.xyz") + "' is written to '" + dir.file("m.partial.xyz") + "' first",
                dir.file("m.partial.xyz"));

  expectRefused(tool("paco_segment") + " " + quoted(xyz) + " -o " + quoted(xyz), "-o '" + xyz + "' is the same file",
                xyz);
  expectRefused(tool("paco_segment") + " " + quoted(xyz) + " -o " + quoted(dir.file("out.vg")) + " --vg " +
                    quoted(dir.file("out.vg")),
                "give each output its own file name");
  expectRefused(tool("paco_assemble") + " " + quoted(ply) + " -o " + quoted(ply), "is the same file as PRIMITIVES",
                ply);
  expectRefused(tool("paco_complete") + " " + quoted(vg) + " -o " + quoted(vg) + " --use-labels",
                "-o '" + vg + "' is the same file as INPUT", vg);
  expectRefused(tool("paco_reconstruct") + " " + quoted(ply) + " -o " + quoted(ply), "is the same file as INPUT", ply);
  // The default --pcd (MESH stem + _primitives.pcd) is an output too.
  expectRefused(tool("paco_reconstruct") + " " + quoted(dir.file("m_primitives.pcd")) + " -o " +
                    quoted(dir.file("m.obj")),
                "--pcd '" + dir.file("m_primitives.pcd") + "' is the same file as INPUT", dir.file("m_primitives.pcd"));
  EXPECT_FALSE(fs::exists(dir.file("m.obj")));
  EXPECT_FALSE(fs::exists(dir.file("out.vg")));
}

TEST(PacoTools, TrainExportDoesNotReplaceItsCheckpoint) {
  REQUIRE_TOOLS("paco_train");
  TempDir dir;
  paco::test::writeBytes(dir.file("best.pt"), "a training checkpoint");
  expectRefused(tool("paco_train") + " --export " + quoted(dir.file("best.pt")) + " -o " + quoted(dir.file("best.pt")),
                "-o '" + dir.file("best.pt") + "' is the same file as --export", dir.file("best.pt"));
}

TEST(PacoTools, NegativeCountsAndTooManyThreadsAreUsageErrors) {
  REQUIRE_TOOLS("paco_segment", "paco_assemble", "paco_complete", "paco_reconstruct");
  TempDir dir;
  paco::io::saveCloud(dir.file("box.ply"), sparselyLabelledBox());
  const std::string in = quoted(dir.file("box.ply"));
  const std::string reconstruct = tool("paco_reconstruct") + " " + in + " -o " + quoted(dir.file("m.obj"));
  const std::string complete = tool("paco_complete") + " " + in + " -o " + quoted(dir.file("p.vg"));
  const std::string segment = tool("paco_segment") + " " + in + " -o " + quoted(dir.file("s.pcd"));
  const std::string assemble = tool("paco_assemble") + " " + in + " -o " + quoted(dir.file("a.obj"));
  // Unsigned options would read "-1" as the largest number.
  expectRefused(reconstruct + " --max-points -1", "--max-points must be a whole number >= 0, got '-1'");
  expectRefused(reconstruct + " --max-candidate-faces -1", "--max-candidate-faces must be a whole number >= 0");
  expectRefused(reconstruct + " --threads -1", "--threads must be 0 (all cores) or 1 to ");
  expectRefused(reconstruct + " --threads 100000", "(4 per hardware thread), got 100000");
  expectRefused(complete + " --max-points -1", "--max-points must be a whole number >= 0");
  expectRefused(complete + " --threads 100000", "(4 per hardware thread), got 100000");
  expectRefused(segment + " --threads -1", "--threads must be a whole number >= 0");
  expectRefused(segment + " --threads 100000", "(4 per hardware thread), got 100000");
  expectRefused(assemble + " --max-candidate-faces -1", "--max-candidate-faces must be a whole number >= 0");
  expectRefused(assemble + " --min-support=-1", "--min-support must be a whole number >= 0");
  if (built("paco_dataset")) {
    expectRefused(tool("paco_dataset") + " --procedural -1 " + quoted(dir.file("ds")), "--procedural must be a whole");
    expectRefused(tool("paco_dataset") + " --procedural 1 " + quoted(dir.file("ds")) + " --jobs 100000",
                  "--jobs must be 1 to ");
    EXPECT_FALSE(fs::exists(dir.file("ds")));
  }
  if (built("paco_train")) {
    const std::string train = tool("paco_train") + " " + quoted(dir.file("ds")) + " -o " + quoted(dir.file("run"));
    expectRefused(train + " --threads 100000", "--threads must be 1 to ");
    expectRefused(train + " --limit-train -1", "--limit-train must be a whole number >= 0");
    EXPECT_FALSE(fs::exists(dir.file("run")));
  }
  if (built("paco_eval")) {
    const std::string eval = tool("paco_eval") + " --dataset " + quoted(dir.file("ds")) + " -o " + quoted(dir.file("ev"));
    expectRefused(eval + " --threads -1", "--threads must be 0 (one per hardware thread) or 1 to ");
    expectRefused(eval + " --jobs 100000", "--jobs must be 1 to ");
    expectRefused(eval + " --samples -1", "--samples must be a whole number >= 0");
    EXPECT_FALSE(fs::exists(dir.file("ev")));
  }
}

TEST(PacoTools, AnUnsupportedOutputExtensionNamesTheUsersPath) {
  REQUIRE_TOOLS("paco_convert");
  TempDir dir;
  paco::io::saveCloud(dir.file("box.xyz"), sparselyLabelledBox());
  for (const char* name : {"out.foo", "out"}) {
    std::string log;
    EXPECT_EQ(paco::test::runCommand(tool("paco_convert") + " " + quoted(dir.file("box.xyz")) + " " +
                                         quoted(dir.file(name)),
                                     &log),
              2)
        << log;
    EXPECT_NE(log.find("OUTPUT must name a .pcd, .ply, .xyz, .npy, .vg, .bvg, .obj, .off or .stl file, got '" +
                       dir.file(name) + "'"),
              std::string::npos)
        << log;
    EXPECT_EQ(log.find(".partial"), std::string::npos) << log;
    EXPECT_EQ(log.find("read '"), std::string::npos) << log;
  }
  if (built("paco_dataset")) {
    // Checked before the dataset is opened (this one does not exist).
    const std::string run = tool("paco_dataset") + " --export " + quoted(dir.file("no_dataset")) + " ";
    expectRefused(run + quoted(dir.file("x.obj")), "OUT.pcd must name a .pcd, .ply, .xyz, .npy, .vg or .bvg file, got '" +
                                                      dir.file("x.obj") + "'");
    expectRefused(run + quoted(dir.file("x.pcd")) + " --export-mesh " + quoted(dir.file("x.pcd")),
                  "--export-mesh must name a .obj, .off, .ply or .stl file");
    expectRefused(run + quoted(dir.file("x.ply")) + " --export-mesh " + quoted(dir.file("x.ply")),
                  "give each output its own file name");
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

// A run that fails leaves no checkpoint folder behind: options are checked before the folder is
// made, and a folder the run made is removed again when the run wrote nothing into it.
TEST(PacoTools, AFailedTrainingRunLeavesNoFolder) {
  REQUIRE_TOOLS("paco_dataset", "paco_train");
  TempDir dir;
  std::string log;
  ASSERT_EQ(paco::test::runCommand(tool("paco_dataset") + " --procedural 3 " + quoted(dir.file("ds")) +
                                       " --levels 0 --views 1 --jobs 1 --input-points 256 --gt-points 512 "
                                       "--dense-points 1024",
                                   &log),
            0)
      << log;
  const std::string train = tool("paco_train") + " " + quoted(dir.file("ds")) + " -o " + quoted(dir.file("run")) +
                            " --epochs 1 --threads 1 --quiet --gt-points 512";
  expectRefused(train + " --input-points 0", "--input-points and --gt-points must be at least 1, got 0 and 512");
  log = expectRefused(train + " --input-points 256 --batch 0", "--batch must be at least 1, got 0");
  EXPECT_EQ(log.find("Trainer:"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir.file("run")));

  // A part file that cannot be read fails the run after the trainer made the folder.
  paco::test::writeBytes(dir.file("ds/parts/proc-000000.bin"), "");
  EXPECT_EQ(paco::test::runCommand(train + " --input-points 256 --batch 1", &log), 1) << log;
  EXPECT_NE(log.find("proc-000000.bin"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir.file("run"))) << log;
  // A folder the user made stays.
  fs::create_directory(dir.file("run"));
  EXPECT_EQ(paco::test::runCommand(train + " --input-points 256 --batch 1", &log), 1) << log;
  EXPECT_TRUE(fs::is_directory(dir.file("run")));
}

// What is wrong, in the tools' own words: an option for another format, a folder where a file
// goes, a file where a folder goes.
TEST(PacoTools, MessagesSayWhatIsWrongWithAPath) {
  REQUIRE_TOOLS("paco_convert", "paco_assemble", "paco_reconstruct");
  TempDir dir;
  paco::io::saveCloud(dir.file("box.ply"), sparselyLabelledBox());
  fs::create_directory(dir.file("folder"));
  const std::string in = quoted(dir.file("box.ply"));
  expectRefused(tool("paco_convert") + " " + in + " " + quoted(dir.file("c.pcd")) + " --ascii",
                "--ascii writes an ascii PLY cloud; for '" + dir.file("c.pcd") + "' drop it and give --pcd-encoding ascii");
  expectRefused(tool("paco_reconstruct") + " " + in + " -o " + quoted(dir.file("box.ply") + "/m.obj"),
                "'" + dir.file("box.ply") + "' is a file, not a folder");
  expectRefused(tool("paco_reconstruct") + " " + in + " -o " + quoted(dir.file("m.obj")) + " --known-extent " +
                    quoted(dir.file("folder")),
                "--known-extent '" + dir.file("folder") + "' is a folder");
  std::string log;
  EXPECT_EQ(paco::test::runCommand(tool("paco_assemble") + " " + quoted(dir.file("folder")) + " -o " +
                                       quoted(dir.file("a.obj")), &log),
            1)
      << log;
  EXPECT_NE(log.find("is a folder, not a point cloud file"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir.file("c.pcd")) || fs::exists(dir.file("m.obj")) || fs::exists(dir.file("a.obj")));
}

TEST(PacoTools, OptionErrorsSpeakOfTheToolsOptions) {
  REQUIRE_TOOLS("paco_segment", "paco_assemble", "paco_complete", "paco_reconstruct");
  TempDir dir;
  paco::io::saveCloud(dir.file("box.ply"), sparselyLabelledBox());
  const std::string in = quoted(dir.file("box.ply"));
  const std::string assemble = tool("paco_assemble") + " " + in + " -o " + quoted(dir.file("a.obj"));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {assemble + " --merge-angle 400", "--merge-angle must be in [0, 90) degrees, got 400"},
      {assemble + " --smoothness 0", "--smoothness must be a finite number > 0, got 0"},
      {assemble + " --time-limit 0", "--time-limit must be more than 0 seconds, got 0"},
      {assemble + " --min-support 2", "--min-support must be at least 3 (points of a plane), got 2"},
      {tool("paco_segment") + " " + in + " -o " + quoted(dir.file("s.pcd")) + " --epsilon 2",
       "--epsilon must be in (0, 1) (a fraction of the bounding-box diagonal), got 2"},
      {tool("paco_segment") + " " + in + " -o " + quoted(dir.file("s.pcd")) + " --lambda-simplicity 5",
       "--lambda-simplicity must be in [0, 3), got 5"},
      {tool("paco_complete") + " " + in + " -o " + quoted(dir.file("p.vg")) + " -e 0",
       "--epsilon must be in (0, 1) (a fraction of the bounding-box diagonal), got 0"},
      {tool("paco_complete") + " " + in + " -o " + quoted(dir.file("p.vg")) + " --points 0",
       "--points must be 1 to 65536 (the shipped model was trained on 2048), got 0"},
      {tool("paco_complete") + " " + in + " -o " + quoted(dir.file("p.vg")) + " --points 2000000000",
       "--points must be 1 to 65536 (the shipped model was trained on 2048), got 2000000000"},
      {tool("paco_reconstruct") + " " + in + " -o " + quoted(dir.file("m.obj")) + " --time-limit -1",
       "--time-limit must be more than 0 seconds, got -1"}};
  for (const auto& [command, message] : cases) {
    const std::string log = expectRefused(command, message);
    for (const char* internal : {"PolygonalAssembler", "PlanarSegmenter", "GoCoPP", "PlaneProxyEncoder", "pi/2"})
      EXPECT_EQ(log.find(internal), std::string::npos) << command << "\n" << log;
  }

  // A .vg file without a group: the tool says so instead of naming the assembler's API.
  paco::io::LabelledCloud unlabelled = sparselyLabelledBox();
  unlabelled.labels.clear();
  paco::io::saveCloud(dir.file("none.vg"), unlabelled);
  std::string log;
  EXPECT_EQ(paco::test::runCommand(tool("paco_assemble") + " " + quoted(dir.file("none.vg")) + " -o " +
                                       quoted(dir.file("a.obj")),
                                   &log),
            1)
      << log;
  EXPECT_NE(log.find("'" + dir.file("none.vg") + "' holds no primitives"), std::string::npos) << log;
  EXPECT_EQ(log.find("setInputPrimitives"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir.file("a.obj")));
}

// How far a mesh reaches beyond the scan's box, as a share of its diagonal, and the note that
// asks the user to bound the completion past kFarReach.
TEST(PacoTools, AMeshReachingFarBeyondTheScanIsNoted) {
  const Eigen::AlignedBox3d scan_box(Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(2, 1, 2));  // diagonal 3
  EXPECT_DOUBLE_EQ(paco::app::reachBeyondBox(paco::test::makeBox({0, 0, 0}, {2, 1, 2}), scan_box), 0.0);
  // The box grown by 1.2 along +y: its farthest vertices lie 1.2 from the scan's box, 40 % of 3.
  const paco::SurfaceMesh grown = paco::test::makeBox({0, 0, 0}, {2, 2.2, 2});
  EXPECT_NEAR(paco::app::reachBeyondBox(grown, scan_box), 0.4, 1e-12);
  // A corner 0.3 past two sides at once is 0.3 * sqrt(2) away.
  EXPECT_NEAR(paco::app::reachBeyondBox(paco::test::makeBox({-0.3, -0.3, 0}, {2, 1, 2}), scan_box),
              0.3 * std::sqrt(2.0) / 3.0, 1e-12);
  EXPECT_DOUBLE_EQ(paco::app::reachBeyondBox(grown, Eigen::AlignedBox3d()), 0.0);
  // Along turned axes (the box fill's, 45 degrees about z): the scan's box there is [0,2] x [0,1] x
  // [0,2]; the same box turned into place reaches nothing past it, though its corners stand out of
  // the turned box's axis-aligned bounds. Grown by 1.2 along the second axis, it reaches 1.2.
  const Eigen::Matrix3d axes = Eigen::AngleAxisd(paco::kPi / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  auto turned = [&](paco::SurfaceMesh mesh) {
    for (Eigen::Vector3d& v : mesh.vertices) v = axes * v;
    return mesh;
  };
  EXPECT_NEAR(paco::app::reachBeyondBox(turned(paco::test::makeBox({0, 0, 0}, {2, 1, 2})), scan_box, axes), 0.0, 1e-12);
  EXPECT_GT(paco::app::reachBeyondBox(turned(paco::test::makeBox({0, 0, 0}, {2, 1, 2})), scan_box), 0.1);
  EXPECT_NEAR(paco::app::reachBeyondBox(turned(grown), scan_box, axes), 0.4, 1e-12);

  const std::string note = paco::app::farReachNote(0.4, 3.0);
  EXPECT_NE(note.find("reaches 1.2 (40 % of the scan's diagonal)"), std::string::npos) << note;
  EXPECT_NE(note.find("--seen-from"), std::string::npos) << note;
  EXPECT_NE(note.find("--known-extent"), std::string::npos) << note;
  EXPECT_EQ(paco::app::farReachNote(paco::app::kFarReach, 3.0), "");
  EXPECT_EQ(paco::app::farReachNote(0.0, 3.0), "");
}

#ifdef PACO_TEST_WITH_COMPLETION
// --points below the model's centres is a usage error found when the model is read, before the
// scan is read and segmented.
TEST(PacoTools, CompleteChecksPointsAgainstTheModel) {
  REQUIRE_TOOLS("paco_complete");
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  paco::io::saveCloud(dir.file("box.ply"), sparselyLabelledBox());
  const std::string command = tool("paco_complete") + " " + quoted(dir.file("box.ply")) + " -o " +
                              quoted(dir.file("p.vg")) + " --model " + quoted(dir.file("tiny.pt")) + " --points 16";
  const std::string log = expectRefused(command, "--points must be at least 32 (the model's centres), got 16");
  EXPECT_EQ(log.find("PlaneProxyEncoder"), std::string::npos) << log;
  EXPECT_EQ(log.find("segment ("), std::string::npos) << log;
}

// paco_complete --use-labels and paco_assemble read a labelled cloud alike (one shared function):
// any label numbers, and a label with too few points named by its own number.
TEST(PacoTools, LabelsMayBeAnyNumbers) {
  REQUIRE_TOOLS("paco_complete", "paco_assemble");
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  paco::io::LabelledCloud box = sparselyLabelledBox();
  paco::io::saveCloud(dir.file("sparse.pcd"), box);
  const std::string complete = tool("paco_complete") + " --model " + quoted(dir.file("tiny.pt")) +
                               " --use-labels --threshold 1 --threads 1 ";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(complete + quoted(dir.file("sparse.pcd")) + " -o " + quoted(dir.file("p.vg")), &log),
            0)
      << log;
  EXPECT_NE(log.find("segment (input labels): 6 planes"), std::string::npos) << log;
  ASSERT_EQ(paco::test::runCommand(tool("paco_assemble") + " " + quoted(dir.file("sparse.pcd")) + " -o " +
                                       quoted(dir.file("a.obj")) + " --backend cell-complex",
                                   &log),
            0)
      << log;
  EXPECT_NE(log.find("6 planes used"), std::string::npos) << log;

  box.labels[0] = box.labels[1] = 99;
  paco::io::saveCloud(dir.file("two.pcd"), box);
  const std::string message = "label 99 of '" + dir.file("two.pcd") + "' has 2 points; a plane needs at least 3";
  EXPECT_EQ(paco::test::runCommand(complete + quoted(dir.file("two.pcd")) + " -o " + quoted(dir.file("q.vg")), &log), 1)
      << log;
  EXPECT_NE(log.find(message), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool("paco_assemble") + " " + quoted(dir.file("two.pcd")) + " -o " +
                                       quoted(dir.file("b.obj")),
                                   &log),
            1)
      << log;
  EXPECT_NE(log.find(message), std::string::npos) << log;
}
#endif

// Ctrl-C is honoured at a stage boundary by throwing paco::InterruptedError: the tool says so,
// ends with 130 as a shell reports SIGINT, and its pending outputs are gone.
TEST(PacoTools, AnInterruptEndsWith130AndLeavesNoOutput) {
  TempDir dir;
  const std::string mesh = dir.file("m.obj");
  std::string written;
  testing::internal::CaptureStderr();
  const int code = paco::app::runTool("paco_x", [&]() -> int {
    paco::app::PendingOutput out(mesh);
    written = out.writePath();
    paco::test::writeBytes(written, "v 0 0 0\n");
    throw paco::InterruptedError("interrupted");
  });
  const std::string log = testing::internal::GetCapturedStderr();
  EXPECT_EQ(code, 130);
  EXPECT_EQ(log, "paco_x: interrupted; nothing written\n");
  EXPECT_FALSE(fs::exists(written));
  EXPECT_FALSE(fs::exists(mesh));
}

}  // namespace
