// Files written by paco::io open in PCL, and files written by PCL open in paco::io.
#include <paco/common/error.h>
#include <paco/io/cloud_io.h>

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>

#include "test_support.h"

#include <string>

namespace {

using paco::test::TempDir;

paco::io::LabelledCloud makeCloud() {
  paco::io::LabelledCloud c;
  c.has_normals = true;
  for (int i = 0; i < 500; ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(i) * 0.37f;
    p.y = -static_cast<float>(i);
    p.z = 1e-3f * static_cast<float>(i % 17);
    p.normal_x = 0.6f;
    p.normal_y = 0.0f;
    p.normal_z = -0.8f;
    p.curvature = 0.0f;
    c.points.push_back(p);
    c.labels.push_back(i % 4 - 1);
  }
  return c;
}

const paco::io::PcdEncoding kPcdEncodings[] = {paco::io::PcdEncoding::Ascii, paco::io::PcdEncoding::Binary,
                                                paco::io::PcdEncoding::BinaryCompressed};

void savePcd(const std::string& path, const paco::io::LabelledCloud& cloud, paco::io::PcdEncoding encoding) {
  paco::io::CloudWriteOptions options;
  options.pcd_encoding = encoding;
  paco::io::saveCloud(path, cloud, options);
}

class PclInterop : public ::testing::TestWithParam<paco::io::PcdEncoding> {};

TEST_P(PclInterop, PclReadsOurPcdAndWeReadPcls) {
  TempDir dir;
  const auto cloud = makeCloud();
  savePcd(dir.file("ours.pcd"), cloud, GetParam());
  pcl::PointCloud<pcl::PointNormal> normals;
  pcl::PointCloud<pcl::PointXYZL> labelled;
  ASSERT_EQ(pcl::io::loadPCDFile(dir.file("ours.pcd"), normals), 0);
  ASSERT_EQ(pcl::io::loadPCDFile(dir.file("ours.pcd"), labelled), 0);
  ASSERT_EQ(normals.size(), cloud.points.size());
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    EXPECT_EQ(normals[i].getVector3fMap(), cloud.points[i].getVector3fMap());
    EXPECT_EQ(normals[i].getNormalVector3fMap(), cloud.points[i].getNormalVector3fMap());
    EXPECT_EQ(labelled[i].label, static_cast<std::uint32_t>(cloud.labels[i]));  // -1 is 4294967295
  }

  pcl::PCDWriter writer;
  const bool binary = GetParam() != paco::io::PcdEncoding::Ascii;
  if (GetParam() == paco::io::PcdEncoding::BinaryCompressed) {
    writer.writeBinaryCompressed(dir.file("pcl_n.pcd"), normals);
    writer.writeBinaryCompressed(dir.file("pcl_l.pcd"), labelled);
  } else {
    writer.write(dir.file("pcl_n.pcd"), normals, binary);
    writer.write(dir.file("pcl_l.pcd"), labelled, binary);
  }
  const auto back_n = paco::io::loadCloud(dir.file("pcl_n.pcd"));
  const auto back_l = paco::io::loadCloud(dir.file("pcl_l.pcd"));
  EXPECT_TRUE(back_n.has_normals);
  EXPECT_FALSE(back_n.hasLabels());
  EXPECT_EQ(back_l.labels, cloud.labels);
  ASSERT_EQ(back_n.points.size(), cloud.points.size());
  // PCL's ascii writer prints 8 significant digits, not always enough to give back the same float.
  const double tolerance = binary ? 0.0 : 1e-6;
  const auto near = [&](const Eigen::Vector3f& a, const Eigen::Vector3f& b) {
    return (a - b).norm() <= tolerance * std::max(1.0f, b.norm());
  };
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    EXPECT_TRUE(near(back_n.points[i].getVector3fMap(), cloud.points[i].getVector3fMap())) << i;
    EXPECT_TRUE(near(back_n.points[i].getNormalVector3fMap(), cloud.points[i].getNormalVector3fMap())) << i;
    EXPECT_TRUE(near(back_l.points[i].getVector3fMap(), cloud.points[i].getVector3fMap())) << i;
  }
}

INSTANTIATE_TEST_SUITE_P(AllEncodings, PclInterop, ::testing::ValuesIn(kPcdEncodings));

}  // namespace

TEST(PclInteropColours, PclReadsOurRgbField) {
  TempDir dir;
  auto cloud = makeCloud();
  for (std::size_t i = 0; i < cloud.points.size(); ++i)
    cloud.colours.push_back(static_cast<std::uint32_t>((i * 2654435761u) & 0xffffffu));
  for (const auto encoding : kPcdEncodings) {
    savePcd(dir.file("rgb.pcd"), cloud, encoding);
    pcl::PointCloud<pcl::PointXYZRGBL> coloured;
    ASSERT_EQ(pcl::io::loadPCDFile(dir.file("rgb.pcd"), coloured), 0);
    ASSERT_EQ(coloured.size(), cloud.points.size());
    for (std::size_t i = 0; i < coloured.size(); ++i) {
      EXPECT_EQ(coloured[i].rgba & 0xffffffu, cloud.colours[i]) << i;
      EXPECT_EQ(coloured[i].label, static_cast<std::uint32_t>(cloud.labels[i]));
    }
    // Our own reader still reads the file (and ignores the colours).
    EXPECT_EQ(paco::io::loadCloud(dir.file("rgb.pcd")).labels, cloud.labels);
  }
  cloud.colours.pop_back();
  EXPECT_THROW(paco::io::saveCloud(dir.file("bad.pcd"), cloud), paco::IoError);
}

// A cloud read with a coordinate offset (UTM coordinates) writes a PCD that PCL's float point
// types read in the file's coordinates, to float32's precision (0.5 at northing 5.4e6).
TEST(PclInteropFarCoordinates, PclReadsOurPcdInTheFilesCoordinates) {
  TempDir dir;
  paco::test::writeBytes(dir.file("utm.xyz"), "500000.12 5412345.81 100.5\n500003.12 5412348.48 106.5\n"
                                              "500012.12 5412353.81 103.5\n");
  const paco::io::LabelledCloud cloud = paco::io::loadCloud(dir.file("utm.xyz"));
  ASSERT_FALSE(cloud.coordinate_offset.isZero(0.0));
  for (const auto encoding : kPcdEncodings) {
    savePcd(dir.file("utm.pcd"), cloud, encoding);
    pcl::PointCloud<pcl::PointXYZ> read;
    ASSERT_EQ(pcl::io::loadPCDFile(dir.file("utm.pcd"), read), 0);
    ASSERT_EQ(read.size(), 3u);
    EXPECT_NEAR(read[1].x, 500003.12, 0.25);
    EXPECT_NEAR(read[1].y, 5412348.48, 0.25);
    EXPECT_NEAR(read[1].z, 106.5, 1e-5);
  }
}
