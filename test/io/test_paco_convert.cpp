// Runs the built paco_convert tool on a good and on a bad file.
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>

#include <gtest/gtest.h>

#include "shapes.h"
#include "test_support.h"

#include <filesystem>

namespace {

using paco::test::TempDir;

using paco::test::quoted;

bool toolBuilt() { return std::filesystem::exists(paco::test::toolPath("paco_convert")); }

TEST(PacoConvert, ConvertsAndNormalisesACloud) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_convert is not built";
  TempDir dir;
  paco::io::LabelledCloud cloud;
  for (int i = 0; i < 100; ++i) {
    pcl::PointNormal p;
    p.x = 10.0f + static_cast<float>(i % 10);
    p.y = -5.0f + static_cast<float>(i / 10);
    p.z = 3.0f;
    p.normal_x = p.normal_y = 0.0f;
    p.normal_z = 1.0f;
    cloud.points.push_back(p);
    cloud.labels.push_back(i % 3);
  }
  cloud.has_normals = true;
  paco::io::saveCloud(dir.file("in.pcd"), cloud);
  std::string out;
  const int rc = paco::test::runCommand(paco::test::toolPath("paco_convert") + " " + quoted(dir.file("in.pcd")) + " " +
                                            quoted(dir.file("out.ply")) + " --normalize",
                                        &out);
  ASSERT_EQ(rc, 0) << out;
  EXPECT_NE(out.find("100 points"), std::string::npos) << out;
  EXPECT_NE(out.find("centre 14.5 -0.5 3"), std::string::npos) << out;
  const auto back = paco::io::loadCloud(dir.file("out.ply"));
  ASSERT_EQ(back.points.size(), 100u);
  EXPECT_EQ(back.labels, cloud.labels);
  // Unit bounding-box diagonal, centred at the origin: the 9 x 9 square has diagonal 9 * sqrt 2.
  EXPECT_NEAR(back.points[0].x, -4.5 / (9.0 * std::sqrt(2.0)), 1e-6);
  EXPECT_NEAR(back.points[99].y, 4.5 / (9.0 * std::sqrt(2.0)), 1e-6);
}

TEST(PacoConvert, ConvertsAMesh) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_convert is not built";
  TempDir dir;
  paco::io::saveMesh(dir.file("box.obj"), paco::test::makeBox({0, 0, 0}, {1, 2, 3}));
  std::string out;
  ASSERT_EQ(paco::test::runCommand(paco::test::toolPath("paco_convert") + " " + quoted(dir.file("box.obj")) + " " +
                                       quoted(dir.file("box.off")),
                                   &out),
            0)
      << out;
  EXPECT_NE(out.find("6 faces"), std::string::npos) << out;
  EXPECT_EQ(paco::io::loadMesh(dir.file("box.off")).faces.size(), 6u);
}

TEST(PacoConvert, BadInputFailsWithMessageAndLeavesNoOutput) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_convert is not built";
  TempDir dir;
  paco::test::writeBytes(dir.file("bad.pcd"), "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 9\nPOINTS 9\nDATA binary\nabc");
  std::string out;
  const int rc = paco::test::runCommand(
      paco::test::toolPath("paco_convert") + " " + quoted(dir.file("bad.pcd")) + " " + quoted(dir.file("out.ply")), &out);
  EXPECT_EQ(rc, 1) << out;
  EXPECT_NE(out.find("truncated: header says 9 points, data holds 0"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.ply")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("out.partial.ply")));
  // NaN points: rejected, or dropped on request.
  paco::test::writeBytes(dir.file("nan.xyz"), "1 2 3\nnan 0 0\n4 5 6\n");
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_convert") + " " + quoted(dir.file("nan.xyz")) + " " +
                                       quoted(dir.file("nan.pcd")),
                                   &out),
            1);
  EXPECT_NE(out.find("--drop-non-finite"), std::string::npos) << out;
  EXPECT_FALSE(std::filesystem::exists(dir.file("nan.pcd")));
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_convert") + " " + quoted(dir.file("nan.xyz")) + " " +
                                       quoted(dir.file("nan.pcd")) + " --drop-non-finite",
                                   &out),
            0)
      << out;
  EXPECT_EQ(paco::io::loadCloud(dir.file("nan.pcd")).points.size(), 2u);
  // Usage errors exit with 2.
  EXPECT_EQ(paco::test::runCommand(paco::test::toolPath("paco_convert") + " only_one_argument", &out), 2) << out;
}

}  // namespace

// UTM coordinates go to PLY in double precision, and to PCD (float32, for PCL) with a warning.
TEST(PacoConvert, FarCoordinatesKeepTheirPrecisionOrGetAWarning) {
  if (!toolBuilt()) GTEST_SKIP() << "paco_convert is not built";
  paco::test::TempDir dir;
  paco::test::writeBytes(dir.file("utm.xyz"), "500000.12 5412345.81 100.5\n500003.12 5412348.48 106.5\n"
                                              "500012.12 5412353.81 103.5\n");
  std::string log;
  const std::string convert = paco::test::toolPath("paco_convert") + " " + quoted(dir.file("utm.xyz")) + " ";
  ASSERT_EQ(paco::test::runCommand(convert + quoted(dir.file("utm.ply")), &log), 0) << log;
  EXPECT_EQ(log.find("warning"), std::string::npos) << log;
  const paco::io::LabelledCloud ply = paco::io::loadCloud(dir.file("utm.ply"));
  EXPECT_NEAR(ply.points[1].y + ply.coordinate_offset.y(), 5412348.48, 1e-5);
  ASSERT_EQ(paco::test::runCommand(convert + quoted(dir.file("utm.pcd")), &log), 0) << log;
  EXPECT_NE(log.find("warning: '" + dir.file("utm.pcd") + "' stores float32 positions"), std::string::npos) << log;
}
