#include <paco/data/dataset.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>

#include "shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <map>
#include <sstream>
#include <vector>

namespace {

#ifdef PACO_HAVE_DATASET_TOOL

const char kSmall[] = " --views 2 --levels 0,2 --input-points 256 --gt-points 512 --dense-points 2048";

TEST(PacoDatasetTool, ProceduralRunIsResumable) {
  paco::test::TempDir dir;
  const std::string out = dir.file("ds");
  const std::string command = paco::test::toolPath("paco_dataset") + " --procedural 3 " + out + kSmall + " --jobs 2";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(command, &log), 0) << log;
  EXPECT_NE(log.find("nearest"), std::string::npos) << log;
  EXPECT_NE(log.find("built 3 parts"), std::string::npos) << log;
  const std::string index = paco::test::readBytes(out + "/index.tsv");
  // Rerun: nothing left to build, index unchanged.
  ASSERT_EQ(paco::test::runCommand(command, &log), 0) << log;
  EXPECT_NE(log.find("0 to build"), std::string::npos) << log;
  EXPECT_EQ(paco::test::readBytes(out + "/index.tsv"), index);
  // More parts later: only the new ones are built.
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " --procedural 4 " + out + kSmall, &log), 0);
  EXPECT_NE(log.find("built 1 parts"), std::string::npos) << log;
  const paco::data::Dataset dataset(out);
  EXPECT_EQ(dataset.parts().size(), 4u);
  // Other options into the same folder are refused.
  EXPECT_NE(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " --procedural 4 " + out + " --noise 3", &log), 0);

  // --verify reads every sample back.
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " --verify " + out, &log), 0) << log;
  EXPECT_NE(log.find("read 16 samples"), std::string::npos) << log;

  // --export writes a PCD with normals and the GT mesh.
  const std::string pcd = dir.file("sample.pcd"), off = dir.file("sample_gt.off");
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " --export " + out + " " + pcd +
                                       " --export-mesh " + off + " --level 2 --view 1", &log), 0) << log;
  const paco::io::LabelledCloud cloud = paco::io::loadCloud(pcd);
  EXPECT_EQ(cloud.points.size(), 256u);
  EXPECT_TRUE(cloud.has_normals);
  EXPECT_TRUE(paco::analyseTopology(paco::io::loadMesh(off)).isClosedManifold());
}

std::vector<std::string> sortedLines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::sort(lines.begin(), lines.end());
  return lines;
}

// Every file of a procedural dataset, by its path under the folder.
std::map<std::string, std::string> folderBytes(const std::string& folder) {
  std::map<std::string, std::string> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder))
    if (entry.is_regular_file())
      files[std::filesystem::relative(entry.path(), folder).string()] = paco::test::readBytes(entry.path().string());
  return files;
}

// The same options give the same bytes in another process and with other --jobs (the index's rows
// come in the order the parts finished). CGAL's Nef solids list their faces in an order that
// follows heap addresses, and before the meshes were sorted, about one part in ten came out in
// another order (and so with other samples) in every run.
TEST(PacoDatasetTool, TheSameOptionsGiveTheSameBytesInEveryRun) {
  paco::test::TempDir dir;
  const std::string command = paco::test::toolPath("paco_dataset") + " --procedural 40" + kSmall;
  std::string log;
  ASSERT_EQ(paco::test::runCommand(command + " " + dir.file("a") + " --jobs 1", &log), 0) << log;
  ASSERT_EQ(paco::test::runCommand(command + " " + dir.file("b") + " --jobs 1", &log), 0) << log;
  ASSERT_EQ(paco::test::runCommand(command + " " + dir.file("c") + " --jobs 2", &log), 0) << log;
  const auto a = folderBytes(dir.file("a"));
  EXPECT_GT(a.size(), 80u);  // the index, and a mesh and samples per part
  for (const char* other : {"b", "c"}) {
    const auto files = folderBytes(dir.file(other));
    ASSERT_EQ(files.size(), a.size()) << other;
    for (const auto& [name, bytes] : a) {
      if (name == "index.tsv")  // the same rows, in the order the parts finished
        EXPECT_EQ(sortedLines(files.at(name)), sortedLines(bytes)) << other;
      else
        EXPECT_TRUE(files.at(name) == bytes) << other << ": " << name;
    }
  }
}

// A real Ctrl-C: SIGINT reaches paco_dataset while it builds (once the index holds a part, with
// hundreds to go), the run ends with exit code 130 and a consistent index, and the same command
// builds the rest: the same files as a run never stopped.
TEST(PacoDatasetTool, ASignalStopsTheBuildAndTheSameCommandFinishesIt) {
  paco::test::TempDir dir;
  const std::string tool = paco::test::toolPath("paco_dataset");
  const auto arguments = [&](const std::string& folder) {
    std::vector<std::string> words = {tool, "--procedural", "600", folder};
    std::istringstream small(std::string(kSmall) + " --jobs 2");
    for (std::string word; small >> word;) words.push_back(word);
    return words;
  };
  const auto command = [&](const std::string& folder) {
    std::string line;
    for (const auto& word : arguments(folder)) line += word + " ";
    return line;
  };
  const auto indexRows = [&] {
    const std::string index = paco::test::readBytes(dir.file("a/index.tsv"));
    return std::count(index.begin(), index.end(), '\n') - 1;  // less the header
  };
  int code = 0;
  {
    paco::test::BackgroundTool build(arguments(dir.file("a")), dir.file("log.txt"));
    ASSERT_TRUE(build.waitUntil([&] { return indexRows() >= 1; }, 120.0)) << paco::test::readBytes(dir.file("log.txt"));
    code = build.signalAndWait(SIGINT);
  }
  const std::string log = paco::test::readBytes(dir.file("log.txt"));
  EXPECT_EQ(code, 130) << log;
  EXPECT_NE(log.find("interrupted: the index is consistent; rerun the same command to resume"), std::string::npos) << log;
  const auto stopped_at = indexRows();
  EXPECT_GE(stopped_at, 1);
  EXPECT_LT(stopped_at, 600);
  EXPECT_EQ(paco::data::Dataset(dir.file("a")).parts().size(), static_cast<std::size_t>(stopped_at));

  std::string resumed;
  ASSERT_EQ(paco::test::runCommand(command(dir.file("a")), &resumed), 0) << resumed;
  EXPECT_NE(resumed.find(std::to_string(stopped_at) + " already done"), std::string::npos) << resumed;
  ASSERT_EQ(paco::test::runCommand(command(dir.file("b")), &resumed), 0) << resumed;
  const auto a = folderBytes(dir.file("a")), b = folderBytes(dir.file("b"));
  ASSERT_EQ(a.size(), b.size());
  for (const auto& [name, bytes] : a) {
    if (name == "index.tsv")
      EXPECT_EQ(sortedLines(bytes), sortedLines(b.at(name)));
    else
      EXPECT_TRUE(bytes == b.at(name)) << name;
  }
}

// --only-split, --stride and --limit choose among MESH_DIR's meshes. With --procedural alone they
// were ignored (every part was built); a split that does not exist was only found after the scan.
TEST(PacoDatasetTool, MeshChoiceOptionsNeedMeshesAndAKnownSplit) {
  paco::test::TempDir dir;
  const std::string tool = paco::test::toolPath("paco_dataset");
  std::string log;
  for (const char* option : {" --only-split val", " --stride 2", " --limit 3"}) {
    EXPECT_EQ(paco::test::runCommand(tool + " --procedural 4 " + dir.file("p") + option, &log), 2) << option;
    EXPECT_NE(log.find("choose among MESH_DIR's meshes"), std::string::npos) << log;
  }
  std::filesystem::create_directories(dir.file("meshes"));
  paco::io::saveMesh(dir.file("meshes/good.obj"), paco::test::makeLBracket());
  EXPECT_EQ(paco::test::runCommand(tool + " " + dir.file("meshes") + " " + dir.file("m") + " --only-split value", &log), 2);
  EXPECT_NE(log.find("--only-split: unknown split 'value': use train, val or test"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.file("p")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("m")));
}

TEST(PacoDatasetTool, BadMeshesAreListedNotFatal) {
  paco::test::TempDir dir;
  std::filesystem::create_directories(dir.file("meshes"));
  paco::io::saveMesh(dir.file("meshes/good.obj"), paco::test::makeLBracket());
  paco::SurfaceMesh open = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  open.faces.pop_back();
  paco::io::saveMesh(dir.file("meshes/open.off"), open);
  paco::test::writeBytes(dir.file("meshes/garbage.stl"), "not a mesh");
  std::string log;
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " " + dir.file("meshes") + " " +
                                       dir.file("ds") + kSmall + " --mode visibility", &log), 0) << log;
  EXPECT_NE(log.find("visibility"), std::string::npos);
  const std::string failures = paco::test::readBytes(dir.file("ds/failures.tsv"));
  EXPECT_NE(failures.find("open\tmesh is not closed"), std::string::npos) << failures;
  EXPECT_NE(failures.find("garbage\tcannot read"), std::string::npos) << failures;
  const paco::data::Dataset dataset(dir.file("ds"));
  ASSERT_EQ(dataset.parts().size(), 1u);
  EXPECT_EQ(dataset.parts()[0].num_planes, 8);
  EXPECT_EQ(dataset.info().mode, "visibility");
  // Usage errors exit with 2.
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " " + dir.file("ds"), &log), 2);
  const std::string build_new = paco::test::toolPath("paco_dataset") + " " + dir.file("meshes") + " " + dir.file("ds2") + kSmall;
  EXPECT_EQ(paco::test::runCommand(build_new + " --segment --segment-min-points -1", &log), 2);
  EXPECT_NE(log.find("--segment-min-points must be >= 0"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(build_new + " --segment-min-points 40", &log), 2);
  EXPECT_NE(log.find("needs --segment"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(build_new + " --segment-min-parallel-points 0", &log), 2);
  EXPECT_NE(log.find("--segment-min-parallel-points needs --segment"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(build_new + " --single-scanner", &log), 2);
  EXPECT_NE(log.find("--single-scanner needs --mode visibility"), std::string::npos) << log;
  EXPECT_FALSE(std::filesystem::exists(dir.file("ds2")));
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " --help", &log), 0);
  // One scanner, recorded in the dataset's description.
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_dataset") + " " + dir.file("meshes") + " " +
                                       dir.file("ds3") + kSmall + " --mode visibility --single-scanner", &log), 0)
      << log;
  EXPECT_NE(log.find("one scanner"), std::string::npos) << log;
  EXPECT_TRUE(paco::data::Dataset(dir.file("ds3")).info().single_scanner);
}

#else
TEST(PacoDatasetTool, NotBuilt) { GTEST_SKIP() << "paco_dataset is not part of this build"; }
#endif

}  // namespace
