#include <paco/common/error.h>
#include <paco/io/cloud_io.h>
#include <paco/io/vertex_groups_io.h>

#include <gtest/gtest.h>

#include "../../modules/io/src/lzf.h"
#include "test_support.h"

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

namespace {

using paco::IoError;
using paco::io::LabelledCloud;
using paco::test::TempDir;
using paco::test::writeBytes;
using paco::test::readBytes;

LabelledCloud makeCloud(std::size_t n, bool normals, bool labels, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-100.0f, 100.0f);
  LabelledCloud c;
  c.has_normals = normals;
  for (std::size_t i = 0; i < n; ++i) {
    pcl::PointNormal p;
    p.x = u(rng); p.y = u(rng) * 1e-3f; p.z = u(rng) * 1e4f;  // varied magnitudes test precision
    if (normals) {
      Eigen::Vector3f nrm(u(rng), u(rng), u(rng));
      nrm.normalize();
      p.normal_x = nrm.x(); p.normal_y = nrm.y(); p.normal_z = nrm.z();
    } else {
      p.normal_x = p.normal_y = p.normal_z = 0.0f;
    }
    p.curvature = 0.0f;
    c.points.push_back(p);
    if (labels) c.labels.push_back(static_cast<int>(i % 5) - 1);  // includes -1
  }
  return c;
}

/// Bit-exact equality of positions, normals (when present) and labels.
void expectSameCloud(const LabelledCloud& a, const LabelledCloud& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(a.has_normals, b.has_normals);
  EXPECT_EQ(a.labels, b.labels);
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].x, b.points[i].x) << i;
    EXPECT_EQ(a.points[i].y, b.points[i].y) << i;
    EXPECT_EQ(a.points[i].z, b.points[i].z) << i;
    if (a.has_normals) {
      EXPECT_EQ(a.points[i].normal_x, b.points[i].normal_x) << i;
      EXPECT_EQ(a.points[i].normal_y, b.points[i].normal_y) << i;
      EXPECT_EQ(a.points[i].normal_z, b.points[i].normal_z) << i;
    }
  }
}

/// Expects loadCloud(path) to throw IoError whose message names the file and contains `problem`.
void expectLoadError(const std::string& path, const std::string& problem) {
  try {
    paco::io::loadCloud(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const IoError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << "expected '" << problem << "' in: " << msg;
  }
}

struct PcdCase {
  paco::io::PcdEncoding encoding;
  bool normals, labels;
};

class PcdRoundTrip : public ::testing::TestWithParam<PcdCase> {};

std::string pcdCaseName(const ::testing::TestParamInfo<PcdCase>& info) {
  static const char* const kNames[] = {"ascii", "binary", "binary_compressed"};
  return std::string(kNames[static_cast<int>(info.param.encoding)]) + (info.param.normals ? "_normals" : "") +
         (info.param.labels ? "_labels" : "");
}

TEST_P(PcdRoundTrip, WrittenThenReadGivesEqualData) {
  TempDir dir;
  const auto param = GetParam();
  const LabelledCloud cloud = makeCloud(500, param.normals, param.labels);
  paco::io::CloudWriteOptions options;
  options.pcd_encoding = param.encoding;
  const std::string path = dir.file("cloud.pcd");
  paco::io::saveCloud(path, cloud, options);
  expectSameCloud(cloud, paco::io::loadCloud(path));
}

INSTANTIATE_TEST_SUITE_P(
    AllEncodings, PcdRoundTrip,
    ::testing::Values(PcdCase{paco::io::PcdEncoding::Ascii, false, false}, PcdCase{paco::io::PcdEncoding::Ascii, true, true},
                      PcdCase{paco::io::PcdEncoding::Ascii, false, true}, PcdCase{paco::io::PcdEncoding::Binary, false, false},
                      PcdCase{paco::io::PcdEncoding::Binary, true, false}, PcdCase{paco::io::PcdEncoding::Binary, true, true},
                      PcdCase{paco::io::PcdEncoding::BinaryCompressed, false, false},
                      PcdCase{paco::io::PcdEncoding::BinaryCompressed, true, false},
                      PcdCase{paco::io::PcdEncoding::BinaryCompressed, true, true},
                      PcdCase{paco::io::PcdEncoding::BinaryCompressed, false, true}),
    pcdCaseName);

TEST(CloudIo, CompressedPcdIsSmallerForRepetitiveData) {
  TempDir dir;
  LabelledCloud cloud = makeCloud(2000, true, true);
  for (auto& p : cloud.points) p.z = 1.0f;  // one constant field compresses well
  paco::io::CloudWriteOptions binary, compressed;
  compressed.pcd_encoding = paco::io::PcdEncoding::BinaryCompressed;
  paco::io::saveCloud(dir.file("b.pcd"), cloud, binary);
  paco::io::saveCloud(dir.file("c.pcd"), cloud, compressed);
  EXPECT_LT(readBytes(dir.file("c.pcd")).size(), readBytes(dir.file("b.pcd")).size() * 9 / 10);
  expectSameCloud(cloud, paco::io::loadCloud(dir.file("c.pcd")));
}

TEST(CloudIo, PlyRoundTripBinaryAndAscii) {
  TempDir dir;
  for (bool ascii : {false, true})
    for (bool normals : {false, true})
      for (bool labels : {false, true}) {
        const LabelledCloud cloud = makeCloud(300, normals, labels);
        paco::io::CloudWriteOptions options;
        options.ascii_ply = ascii;
        paco::io::saveCloud(dir.file("c.ply"), cloud, options);
        SCOPED_TRACE(std::string(ascii ? "ascii" : "binary") + (normals ? " normals" : "") + (labels ? " labels" : ""));
        expectSameCloud(cloud, paco::io::loadCloud(dir.file("c.ply")));
      }
}

TEST(CloudIo, XyzRoundTripWithAndWithoutNormals) {
  TempDir dir;
  for (bool normals : {false, true}) {
    const LabelledCloud cloud = makeCloud(300, normals, false);
    paco::io::saveCloud(dir.file("c.xyz"), cloud);
    expectSameCloud(cloud, paco::io::loadCloud(dir.file("c.xyz")));
  }
}

TEST(CloudIo, NpyRoundTripWithNormalsAndLabels) {
  TempDir dir;
  for (bool normals : {false, true})
    for (bool labels : {false, true}) {
      const LabelledCloud cloud = makeCloud(200, normals, labels);
      paco::io::saveCloud(dir.file("c.npy"), cloud);
      SCOPED_TRACE(std::string(normals ? "normals" : "") + (labels ? " labels" : ""));
      expectSameCloud(cloud, paco::io::loadCloud(dir.file("c.npy")));
    }
}

TEST(CloudIo, LabelledCloudAsVertexGroupsRoundTrip) {
  TempDir dir;
  // Points on two planes (z = 1 with label 4, x = 2 with label 9) and unlabelled points.
  LabelledCloud cloud;
  cloud.has_normals = true;
  for (int i = 0; i < 30; ++i) {
    pcl::PointNormal p;
    const float a = static_cast<float>(i % 6) * 0.25f, b = static_cast<float>(i / 6) * 0.5f;
    const int kind = i % 3;
    if (kind == 0) { p.x = a; p.y = b; p.z = 1.0f; p.normal_x = 0; p.normal_y = 0; p.normal_z = 1; }
    if (kind == 1) { p.x = 2.0f; p.y = a; p.z = b; p.normal_x = 1; p.normal_y = 0; p.normal_z = 0; }
    if (kind == 2) { p.x = a; p.y = -b; p.z = 7.0f * a; p.normal_x = 0; p.normal_y = 1; p.normal_z = 0; }
    p.curvature = 0;
    cloud.points.push_back(p);
    cloud.labels.push_back(kind == 0 ? 4 : kind == 1 ? 9 : -1);
  }
  for (const char* name : {"c.vg", "c.bvg"}) {
    paco::io::saveCloud(dir.file(name), cloud);
    const LabelledCloud back = paco::io::loadCloud(dir.file(name));
    // Labels are renumbered densely in order of first appearance: 4 -> 0, 9 -> 1.
    LabelledCloud expected = cloud;
    for (int& l : expected.labels) l = l == 4 ? 0 : l == 9 ? 1 : -1;
    expectSameCloud(expected, back);
    const auto groups = paco::io::loadVertexGroups(dir.file(name));
    ASSERT_EQ(groups.segmentation.size(), 2u);
    EXPECT_NEAR(groups.segmentation.planes[0].normal.z(), 1.0, 1e-6);  // oriented like the normals
    EXPECT_NEAR(groups.segmentation.planes[0].offset, -1.0, 1e-6);
    EXPECT_NEAR(groups.segmentation.planes[1].normal.x(), 1.0, 1e-6);
    EXPECT_NEAR(groups.segmentation.planes[1].offset, -2.0, 1e-6);
  }
  // A group of collinear points has no plane.
  LabelledCloud line;
  for (int i = 0; i < 4; ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(i); p.y = p.z = 0.0f;
    line.points.push_back(p);
    line.labels.push_back(0);
  }
  EXPECT_THROW(paco::io::saveCloud(dir.file("line.vg"), line), IoError);
}

TEST(CloudIo, ExtensionIsCaseInsensitive) {
  TempDir dir;
  const LabelledCloud cloud = makeCloud(10, true, false);
  paco::io::saveCloud(dir.file("UPPER.PCD"), cloud);
  expectSameCloud(cloud, paco::io::loadCloud(dir.file("UPPER.PCD")));
  EXPECT_EQ(paco::io::extensionOf("/a.b/c.PlY"), ".ply");
  EXPECT_EQ(paco::io::extensionOf("/a.b/noext"), "");
}

TEST(CloudIo, ReadsHandWrittenPcdWithExtraFieldsAndUnsignedLabel) {
  TempDir dir;
  // As PCL writes PointXYZRGBL: rgb packed in a float, label U 4, and a padding field of count 3.
  const std::string path = dir.file("pcl.pcd");
  writeBytes(path,
             "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb _ label\nSIZE 4 4 4 4 1 4\nTYPE F F F F U U\n"
             "COUNT 1 1 1 1 3 1\nWIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
             "1 2 3 0 0 0 0 4\n4 5 6 0 0 0 0 4294967295\n7 8 9.5 0 0 0 0 0\n");
  const LabelledCloud c = paco::io::loadCloud(path);
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_FALSE(c.has_normals);
  EXPECT_EQ(c.labels, (std::vector<int>{4, -1, 0}));
  EXPECT_FLOAT_EQ(c.points[2].z, 9.5f);
}

TEST(CloudIo, ReadsBinaryPcdWithPaddingAndDoubleFields) {
  TempDir dir;
  std::string bytes =
      "VERSION .7\nFIELDS x y z _ normal_x normal_y normal_z\nSIZE 8 8 8 4 4 4 4\nTYPE F F F U F F F\n"
      "COUNT 1 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\nDATA binary\n";
  for (int i = 0; i < 2; ++i) {
    const double xyz[3] = {1.5 + i, -2.0, 1e6};
    const float pad = 0, n[3] = {0, 0, 1};
    bytes.append(reinterpret_cast<const char*>(xyz), sizeof(xyz));
    bytes.append(reinterpret_cast<const char*>(&pad), 4);
    bytes.append(reinterpret_cast<const char*>(n), sizeof(n));
  }
  writeBytes(dir.file("d.pcd"), bytes);
  const LabelledCloud c = paco::io::loadCloud(dir.file("d.pcd"));
  ASSERT_EQ(c.points.size(), 2u);
  EXPECT_TRUE(c.has_normals);
  // 1e6 is far for a cloud 1 unit wide: it goes to the offset (see CloudIoFarCoordinates).
  EXPECT_EQ(c.points[1].x + c.coordinate_offset.x(), 2.5);
  EXPECT_EQ(c.points[1].z + c.coordinate_offset.z(), 1e6);
  EXPECT_EQ(c.points[1].normal_z, 1.0f);
}

TEST(CloudIo, ReadsPlyWithOtherTypesAndLabelNames) {
  TempDir dir;
  // double coordinates, uchar normals-free, plane_id as int, plus a face element to skip.
  writeBytes(dir.file("a.ply"),
             "ply\nformat ascii 1.0\ncomment test\nelement vertex 3\nproperty double x\nproperty double y\n"
             "property double z\nproperty uchar red\nproperty int plane_id\nelement face 1\n"
             "property list uchar int vertex_indices\nend_header\n0 0 0 255 2\n1 0 0 0 -1\n0 1 0.25 7 2\n3 0 1 2\n");
  LabelledCloud c = paco::io::loadCloud(dir.file("a.ply"));
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.labels, (std::vector<int>{2, -1, 2}));
  EXPECT_EQ(c.points[2].z, 0.25f);

  // binary big-endian with float nx ny nz and a segment_index
  std::string be =
      "ply\nformat binary_big_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\nproperty short segment_index\nend_header\n";
  const auto pushBig = [&](const void* v, std::size_t n) {
    const char* c = static_cast<const char*>(v);
    for (std::size_t k = n; k-- > 0;) be += c[k];
  };
  for (float v : {1.0f, 2.0f, 3.0f, 0.0f, 1.0f, 0.0f}) pushBig(&v, 4);
  const std::int16_t seg = 12;
  pushBig(&seg, 2);
  writeBytes(dir.file("be.ply"), be);
  c = paco::io::loadCloud(dir.file("be.ply"));
  ASSERT_EQ(c.points.size(), 1u);
  EXPECT_TRUE(c.has_normals);
  EXPECT_EQ(c.points[0].y, 2.0f);
  EXPECT_EQ(c.points[0].normal_y, 1.0f);
  EXPECT_EQ(c.labels, (std::vector<int>{12}));
}

TEST(CloudIo, XyzAcceptsCommentsAndCommas) {
  TempDir dir;
  writeBytes(dir.file("a.xyz"), "# header\n1 2 3\n\n4,5,6\n  7 8 9  # trailing comment\r\n");
  const LabelledCloud c = paco::io::loadCloud(dir.file("a.xyz"));
  ASSERT_EQ(c.points.size(), 3u);
  EXPECT_EQ(c.points[1].y, 5.0f);
  EXPECT_EQ(c.points[2].z, 9.0f);
  EXPECT_FALSE(c.has_normals);
}

TEST(CloudIo, XyzAcceptsAnyMixOfCommasAndBlanks) {
  TempDir dir;
  writeBytes(dir.file("a.xyz"), "1, 2, 3\n4 ,5,\t6\n7\t8 , 9\r\n 10,11 12 \n");
  const LabelledCloud c = paco::io::loadCloud(dir.file("a.xyz"));
  ASSERT_EQ(c.points.size(), 4u);
  EXPECT_EQ(c.points[0].y, 2.0f);
  EXPECT_EQ(c.points[1].z, 6.0f);
  EXPECT_EQ(c.points[2].y, 8.0f);
  EXPECT_EQ(c.points[3].z, 12.0f);
  // An empty value would shift the columns; a word is still not a number.
  writeBytes(dir.file("b.xyz"), "1, 2, 3\n4,, 5, 6\n");
  expectLoadError(dir.file("b.xyz"), "line 2 has an empty value");
  writeBytes(dir.file("c.xyz"), "1, 2, 3,\n");
  expectLoadError(dir.file("c.xyz"), "line 1 has an empty value");
  writeBytes(dir.file("d.xyz"), "1, two, 3\n");
  expectLoadError(dir.file("d.xyz"), "'two' on line 1 is not a number");
}

TEST(CloudIo, TextFilesMayStartWithUtf8ByteOrderMark) {
  TempDir dir;
  const std::string bom = "\xEF\xBB\xBF";
  writeBytes(dir.file("a.xyz"), bom + "-0.5 2 3\n4 5 6\n");
  const LabelledCloud xyz = paco::io::loadCloud(dir.file("a.xyz"));
  ASSERT_EQ(xyz.points.size(), 2u);
  EXPECT_EQ(xyz.points[0].x, -0.5f);

  const LabelledCloud cloud = makeCloud(20, true, true);
  paco::io::CloudWriteOptions ascii;
  ascii.pcd_encoding = paco::io::PcdEncoding::Ascii;
  ascii.ascii_ply = true;
  for (const char* name : {"c.pcd", "c.ply"}) {
    SCOPED_TRACE(name);
    paco::io::saveCloud(dir.file(name), cloud, ascii);
    writeBytes(dir.file(name), bom + readBytes(dir.file(name)));
    expectSameCloud(cloud, paco::io::loadCloud(dir.file(name)));
  }
}

TEST(CloudIo, NonFiniteNormalsReadAsMissingNormalsInEveryFormat) {
  TempDir dir;
  LabelledCloud cloud = makeCloud(50, true, true);
  cloud.points[11].normal_x = std::numeric_limits<float>::quiet_NaN();
  cloud.points[12].normal_z = -std::numeric_limits<float>::infinity();
  struct Case {
    const char* name;
    paco::io::PcdEncoding encoding;
    bool ascii_ply;
  };
  const Case cases[] = {{"ascii.pcd", paco::io::PcdEncoding::Ascii, false},
                        {"binary.pcd", paco::io::PcdEncoding::Binary, false},
                        {"compressed.pcd", paco::io::PcdEncoding::BinaryCompressed, false},
                        {"ascii.ply", paco::io::PcdEncoding::Binary, true},
                        {"binary.ply", paco::io::PcdEncoding::Binary, false},
                        {"c.npy", paco::io::PcdEncoding::Binary, false},
                        {"c.xyz", paco::io::PcdEncoding::Binary, false}};
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    paco::io::CloudWriteOptions options;
    options.pcd_encoding = c.encoding;
    options.ascii_ply = c.ascii_ply;
    paco::io::saveCloud(dir.file(c.name), cloud, options);
    const LabelledCloud read = paco::io::loadCloud(dir.file(c.name));  // the default rejects NaN points
    ASSERT_EQ(read.points.size(), 50u);
    EXPECT_TRUE(read.has_normals);
    for (int i : {11, 12})
      EXPECT_EQ(read.points[i].getNormalVector3fMap(), Eigen::Vector3f::Zero()) << "point " << i;
    EXPECT_EQ(read.points[13].getNormalVector3fMap(), cloud.points[13].getNormalVector3fMap());
  }
}

TEST(CloudIo, CloudWhoseNormalsAreAllNanOrZeroHasNoNormals) {
  TempDir dir;
  paco::io::CloudReadOptions drop;
  drop.non_finite = paco::io::NonFinitePolicy::Drop;
  writeBytes(dir.file("nan.xyz"), "1 2 3 nan nan nan\n4 5 6 nan nan nan\n7 8 9 0 0 inf\n");
  for (const auto& options : {paco::io::CloudReadOptions{}, drop}) {
    const LabelledCloud c = paco::io::loadCloud(dir.file("nan.xyz"), options);
    ASSERT_EQ(c.points.size(), 3u);  // the coordinates are fine: no point is dropped
    EXPECT_FALSE(c.has_normals);
    for (const auto& p : c.points) EXPECT_EQ(p.getNormalVector3fMap(), Eigen::Vector3f::Zero());
  }
  writeBytes(dir.file("zero.xyz"), "1 2 3 0 0 0\n4 5 6 0 0 0\n7 8 9 0 0 0\n");
  EXPECT_FALSE(paco::io::loadCloud(dir.file("zero.xyz")).has_normals);
}

// ---- errors: missing, empty, truncated, malformed, NaN, for each format family ----

TEST(CloudIoErrors, MissingFileForEveryFormat) {
  TempDir dir;
  for (const char* ext : {".pcd", ".ply", ".xyz", ".npy", ".vg", ".bvg"})
    expectLoadError(dir.file(std::string("absent") + ext), "file not found");
}

TEST(CloudIoErrors, EmptyFileForEveryFormat) {
  TempDir dir;
  for (const char* ext : {".pcd", ".ply", ".xyz", ".npy", ".vg", ".bvg"}) {
    writeBytes(dir.file(std::string("empty") + ext), "");
    expectLoadError(dir.file(std::string("empty") + ext), "empty");
  }
}

TEST(CloudIoErrors, FolderAndUnknownExtension) {
  TempDir dir;
  std::filesystem::create_directory(dir.file("folder.pcd"));
  expectLoadError(dir.file("folder.pcd"), "folder");
  writeBytes(dir.file("a.las"), "x");
  expectLoadError(dir.file("a.las"), "unknown point cloud extension '.las'");
}

TEST(CloudIoErrors, TruncatedPcdInEveryEncoding) {
  TempDir dir;
  const LabelledCloud cloud = makeCloud(2048, true, true);
  for (auto enc : {paco::io::PcdEncoding::Ascii, paco::io::PcdEncoding::Binary, paco::io::PcdEncoding::BinaryCompressed}) {
    paco::io::CloudWriteOptions options;
    options.pcd_encoding = enc;
    paco::io::saveCloud(dir.file("full.pcd"), cloud, options);
    std::string bytes = readBytes(dir.file("full.pcd"));
    const std::size_t header = bytes.find("DATA");
    // Cut the data roughly in half (after the header).
    bytes.resize(header + (bytes.size() - header) / 2);
    writeBytes(dir.file("cut.pcd"), bytes);
    expectLoadError(dir.file("cut.pcd"), "truncated: header says 2048 points, data holds");
  }
}

TEST(CloudIoErrors, TruncatedBinaryPcdReportsHowManyPointsTheDataHolds) {
  TempDir dir;
  const LabelledCloud cloud = makeCloud(2048, false, false);
  paco::io::saveCloud(dir.file("full.pcd"), cloud);
  std::string bytes = readBytes(dir.file("full.pcd"));
  bytes.resize(bytes.size() - 1048 * 12);  // 12 bytes a point
  writeBytes(dir.file("scan.pcd"), bytes);
  expectLoadError(dir.file("scan.pcd"), "truncated: header says 2048 points, data holds 1000");
}

TEST(CloudIoErrors, MalformedPcd) {
  TempDir dir;
  const std::string head = "VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n";
  const struct {
    std::string bytes, problem;
  } cases[] = {
      {"\x89PNG\r\n\x1a\n garbage", "unknown keyword"},
      {head + "WIDTH 1\nHEIGHT 1\nPOINTS 1\n", "no DATA line"},
      {head + "WIDTH 2\nHEIGHT 1\nPOINTS 3\nDATA ascii\n1 2 3\n", "WIDTH x HEIGHT = 2 but POINTS 3"},
      {head + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 two 3\n", "'two' is not a number"},
      {head + "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA zipped\n", "DATA must be"},
      {"VERSION .7\nFIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "SIZE has 2 entries"},
      {"VERSION .7\nFIELDS a b c\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "no x, y, z"},
      {"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F Q\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3\n", "TYPE 'Q'"},
      {"VERSION .7\nFIELDS x y z label\nSIZE 4 4 4 4\nTYPE F F F F\nWIDTH 1\nPOINTS 1\nDATA ascii\n1 2 3 0.5\n",
       "label 0.5 of point 0 is not an integer"},
      {head + "WIDTH 4000000000\nHEIGHT 4000000000\nDATA binary\n", "too large"},
  };
  for (const auto& c : cases) {
    writeBytes(dir.file("bad.pcd"), c.bytes);
    expectLoadError(dir.file("bad.pcd"), c.problem);
  }
}

TEST(CloudIoErrors, CorruptCompressedPcd) {
  TempDir dir;
  paco::io::CloudWriteOptions options;
  options.pcd_encoding = paco::io::PcdEncoding::BinaryCompressed;
  paco::io::saveCloud(dir.file("c.pcd"), makeCloud(100, true, false), options);
  std::string bytes = readBytes(dir.file("c.pcd"));
  const std::size_t data = bytes.find("binary_compressed\n") + 18;
  // Claim a huge uncompressed size.
  std::string wrong_size = bytes;
  const std::uint32_t huge = 0xfffffff0u;
  std::memcpy(&wrong_size[data + 4], &huge, 4);
  writeBytes(dir.file("size.pcd"), wrong_size);
  expectLoadError(dir.file("size.pcd"), "malformed: compressed block holds");
  // Garble the compressed stream: a back-reference before the start.
  std::string garbled = bytes;
  garbled[data + 8] = static_cast<char>(0xff);
  garbled[data + 9] = static_cast<char>(0xff);
  writeBytes(dir.file("garbled.pcd"), garbled);
  expectLoadError(dir.file("garbled.pcd"), "compressed data is corrupt");
}

TEST(CloudIoErrors, TruncatedAndMalformedPly) {
  TempDir dir;
  const LabelledCloud cloud = makeCloud(2048, true, true);
  for (bool ascii : {false, true}) {
    paco::io::CloudWriteOptions options;
    options.ascii_ply = ascii;
    paco::io::saveCloud(dir.file("full.ply"), cloud, options);
    std::string bytes = readBytes(dir.file("full.ply"));
    bytes.resize(bytes.size() * 2 / 3);
    writeBytes(dir.file("cut.ply"), bytes);
    expectLoadError(dir.file("cut.ply"), "truncated: header says 2048 vertices");
  }
  const struct {
    std::string bytes, problem;
  } cases[] = {
      {"solid not a ply\n", "not a PLY file"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "no end_header"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n", "no x, y, z"},
      {"ply\nformat zip 1.0\nend_header\n", "unknown format 'zip'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty quad x\nend_header\n", "unknown type 'quad'"},
      {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 y 3\n",
       "'y' is not a number"},
      {"ply\nformat ascii 1.0\nelement vertex -4\nend_header\n", "element <name> <count>"},
  };
  for (const auto& c : cases) {
    writeBytes(dir.file("bad.ply"), c.bytes);
    expectLoadError(dir.file("bad.ply"), c.problem);
  }
}

// A header that declares fewer points than the data holds is refused, not obeyed: reading only
// what it declares dropped 98 % of a scan without a word. Trailing whitespace is no data.
TEST(CloudIoErrors, HeadersThatUndercountTheDataAreRefusedInEveryFormat) {
  TempDir dir;
  const LabelledCloud cloud = makeCloud(100, true, false);
  const auto replaceAll = [](std::string text, const std::string& from, const std::string& to) {
    for (std::size_t at = text.find(from); at != std::string::npos; at = text.find(from, at + to.size()))
      text.replace(at, from.size(), to);
    return text;
  };
  const struct {
    std::string name;
    paco::io::PcdEncoding pcd;
    bool ascii_ply;
    std::vector<std::pair<std::string, std::string>> edits;
  } cases[] = {
      {"ascii.pcd", paco::io::PcdEncoding::Ascii, false, {{"WIDTH 100", "WIDTH 60"}, {"POINTS 100", "POINTS 60"}}},
      {"binary.pcd", paco::io::PcdEncoding::Binary, false, {{"WIDTH 100", "WIDTH 60"}, {"POINTS 100", "POINTS 60"}}},
      {"ascii.ply", paco::io::PcdEncoding::Binary, true, {{"element vertex 100", "element vertex 60"}}},
      {"binary.ply", paco::io::PcdEncoding::Binary, false, {{"element vertex 100", "element vertex 60"}}},
      {"rows.npy", paco::io::PcdEncoding::Binary, false, {{"(100, ", "(60,  "}}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    paco::io::CloudWriteOptions options;
    options.pcd_encoding = c.pcd;
    options.ascii_ply = c.ascii_ply;
    paco::io::saveCloud(dir.file(c.name), cloud, options);
    const std::string whole = readBytes(dir.file(c.name));
    std::string edited = whole;
    for (const auto& [from, to] : c.edits) {
      ASSERT_NE(edited.find(from), std::string::npos) << from;
      edited = replaceAll(edited, from, to);
    }
    writeBytes(dir.file("lying_" + c.name), edited);
    expectLoadError(dir.file("lying_" + c.name), "the header undercounts the data");
    if (c.name.find("npy") != std::string::npos) continue;  // .npy files end with their data
    writeBytes(dir.file("spaced_" + c.name), whole + "\n  \n");
    EXPECT_EQ(paco::io::loadCloud(dir.file("spaced_" + c.name)).points.size(), 100u);
  }
}

TEST(CloudIoErrors, TruncatedAndMalformedXyz) {
  TempDir dir;
  writeBytes(dir.file("a.xyz"), "1 2 3\n4 5 6\n7 8");
  expectLoadError(dir.file("a.xyz"), "line 3 has 2 values, earlier lines have 3");
  writeBytes(dir.file("b.xyz"), "1 2 3 4\n");
  expectLoadError(dir.file("b.xyz"), "line 1 has 4 values");
  writeBytes(dir.file("c.xyz"), "1 2 3\n4 five 6\n");
  expectLoadError(dir.file("c.xyz"), "'five' on line 2 is not a number");
  writeBytes(dir.file("d.xyz"), "# only a comment\n");
  expectLoadError(dir.file("d.xyz"), "holds no points");
}

TEST(CloudIoErrors, NonFiniteCoordinatesRejectedOrDroppedInEveryFormat) {
  TempDir dir;
  LabelledCloud cloud = makeCloud(50, true, true);
  cloud.points[7].y = std::numeric_limits<float>::quiet_NaN();
  cloud.points[9].z = std::numeric_limits<float>::infinity();
  cloud.points[11].normal_x = std::numeric_limits<float>::quiet_NaN();  // a missing normal, kept
  for (const char* ext : {".pcd", ".ply", ".npy"}) {
    const std::string path = dir.file(std::string("nan") + ext);
    paco::io::saveCloud(path, cloud);
    expectLoadError(path, "2 of 50 points have non-finite (NaN/Inf) coordinates");
    expectLoadError(path, "the first is point 7");
    paco::io::CloudReadOptions drop;
    drop.non_finite = paco::io::NonFinitePolicy::Drop;
    const LabelledCloud kept = paco::io::loadCloud(path, drop);
    ASSERT_EQ(kept.points.size(), 48u) << ext;
    ASSERT_EQ(kept.labels.size(), 48u);
    EXPECT_EQ(kept.points[7].x, cloud.points[8].x);  // the points after a dropped one move up
    EXPECT_EQ(kept.labels[7], cloud.labels[8]);
    EXPECT_EQ(kept.points[9].x, cloud.points[11].x);
  }
  writeBytes(dir.file("nan.xyz"), "1 2 3\nnan 1 2\n4 5 inf\n");
  expectLoadError(dir.file("nan.xyz"), "2 of 3 points have non-finite");
  writeBytes(dir.file("allnan.xyz"), "nan 1 2\n");
  paco::io::CloudReadOptions drop;
  drop.non_finite = paco::io::NonFinitePolicy::Drop;
  EXPECT_THROW(paco::io::loadCloud(dir.file("allnan.xyz"), drop), IoError);  // nothing left
}

TEST(CloudIoErrors, UnwritablePathAndUnknownExtension) {
  TempDir dir;
  const LabelledCloud cloud = makeCloud(5, false, false);
  for (const char* name : {"no/such/folder/c.pcd", "no/such/folder/c.ply", "no/such/folder/c.xyz", "no/such/folder/c.npy"}) {
    try {
      paco::io::saveCloud(dir.file(name), cloud);
      ADD_FAILURE() << "no error writing " << name;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot open for writing"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(paco::io::saveCloud(dir.file("c.las"), cloud), IoError);
  LabelledCloud mismatched = cloud;
  mismatched.labels = {1, 2};
  EXPECT_THROW(paco::io::saveCloud(dir.file("c.pcd"), mismatched), IoError);
}

TEST(Lzf, RoundTripsRandomAndRepetitiveDataAndRejectsCorruption) {
  std::mt19937 rng(3);
  for (std::size_t size : {0u, 1u, 2u, 3u, 31u, 32u, 33u, 1000u, 100000u}) {
    for (int kind = 0; kind < 3; ++kind) {
      std::string data(size, '\0');
      for (std::size_t i = 0; i < size; ++i)
        data[i] = static_cast<char>(kind == 0 ? rng() : kind == 1 ? (i % 7) : (i / 300) % 3);
      const std::string packed = paco::io::detail::lzfCompress(data);
      std::string back;
      ASSERT_TRUE(paco::io::detail::lzfDecompress(packed, size, back)) << size << " " << kind;
      EXPECT_EQ(back, data);
      if (kind == 1 && size >= 1000) {
        EXPECT_LT(packed.size(), size / 10);
      }
    }
  }
  std::string back;
  EXPECT_FALSE(paco::io::detail::lzfDecompress(std::string("\x20\x05", 2), 10, back));  // reference before start
  EXPECT_FALSE(paco::io::detail::lzfDecompress(std::string("\x05" "ab", 3), 6, back));     // literal overrun
  EXPECT_FALSE(paco::io::detail::lzfDecompress(std::string("\x00" "a", 2), 5, back));      // too short
}

}  // namespace

namespace {

/// Every reader, given cut or corrupted versions of valid files, either succeeds or throws
/// paco::IoError: no crash, no other exception, no hang.
TEST(IoRobustness, CorruptedFilesOnlyEverThrowIoError) {
  TempDir dir;
  LabelledCloud cloud = makeCloud(64, true, true);
  std::vector<std::string> files;
  for (auto enc : {paco::io::PcdEncoding::Ascii, paco::io::PcdEncoding::Binary, paco::io::PcdEncoding::BinaryCompressed}) {
    paco::io::CloudWriteOptions o;
    o.pcd_encoding = enc;
    files.push_back(dir.file("c" + std::to_string(files.size()) + ".pcd"));
    paco::io::saveCloud(files.back(), cloud, o);
  }
  paco::io::CloudWriteOptions ascii_ply;
  ascii_ply.ascii_ply = true;
  files.push_back(dir.file("a.ply"));
  paco::io::saveCloud(files.back(), cloud, ascii_ply);
  for (const char* name : {"b.ply", "c.xyz", "c.npy"}) {
    files.push_back(dir.file(name));
    paco::io::saveCloud(files.back(), cloud);
  }
  for (std::size_t i = 0; i < cloud.labels.size(); ++i) cloud.labels[i] = static_cast<int>(i % 3);
  for (auto& p : cloud.points) p.z = 0.25f * p.x - 0.5f * p.y;  // planar groups for .vg
  for (const char* name : {"c.vg", "c.bvg"}) {
    files.push_back(dir.file(name));
    paco::io::saveCloud(files.back(), cloud);
  }
  std::mt19937 rng(11);
  std::size_t loads = 0, failures = 0;
  for (const std::string& file : files) {
    const std::string original = readBytes(file);
    const std::string ext = paco::io::extensionOf(file);
    for (int trial = 0; trial < 40; ++trial) {
      std::string bytes = original;
      if (trial % 3 == 0) {
        bytes.resize(rng() % bytes.size());
      } else {
        for (int k = 0; k < 1 + trial % 5; ++k) bytes[rng() % bytes.size()] = static_cast<char>(rng());
      }
      const std::string bad = dir.file("bad" + ext);
      writeBytes(bad, bytes);
      ++loads;
      try {
        paco::io::loadCloud(bad);
      } catch (const IoError&) {
        ++failures;
      } catch (const std::exception& e) {
        ADD_FAILURE() << file << " trial " << trial << ": " << e.what();
      }
    }
  }
  EXPECT_GT(failures, loads / 4);  // most corruptions are caught
}

}  // namespace

TEST(CloudIo, PrimitivesToCloudLabelsAndColoursEveryPoint) {
  std::vector<paco::PlanarPrimitive> primitives(2);
  for (int k = 0; k < 3; ++k) {
    pcl::PointNormal p;
    p.x = static_cast<float>(k); p.y = 0; p.z = 0;
    p.normal_x = 0; p.normal_y = 0; p.normal_z = 1;
    primitives[k % 2].points.push_back(p);
  }
  const paco::io::LabelledCloud cloud = paco::io::primitivesToCloud(primitives);
  ASSERT_EQ(cloud.points.size(), 3u);
  EXPECT_EQ(cloud.labels, (std::vector<int>{0, 0, 1}));
  EXPECT_EQ(cloud.colours[0], paco::io::primitiveColour(0));
  EXPECT_EQ(cloud.colours[2], paco::io::primitiveColour(1));
  EXPECT_NE(paco::io::primitiveColour(0), paco::io::primitiveColour(1));
  EXPECT_TRUE(cloud.has_normals);
}

namespace {

/// Points of a 12 x 8 x 6 m box in UTM coordinates (northing 5.4e6, where float32 steps by 0.5 m),
/// given to the centimetre as a surveyor's file would.
std::vector<Eigen::Vector3d> utmBoxPoints() {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j)
      for (int k = 0; k < 3; ++k)
        points.emplace_back(std::round((500000.12 + 3.0 * i) * 100) / 100, std::round((5412345.81 + 2.67 * j) * 100) / 100,
                            std::round((100.5 + 3.0 * k) * 100) / 100);
  return points;
}

std::string xyzText(const std::vector<Eigen::Vector3d>& points) {
  std::string text;
  char line[128];
  for (const auto& p : points) {
    std::snprintf(line, sizeof line, "%.2f %.2f %.2f\n", p.x(), p.y(), p.z());
    text += line;
  }
  return text;
}

/// The largest distance between the file coordinates a cloud holds (points + offset) and `truth`.
double largestError(const LabelledCloud& cloud, const std::vector<Eigen::Vector3d>& truth) {
  EXPECT_EQ(cloud.points.size(), truth.size());
  double error = 0.0;
  for (std::size_t i = 0; i < std::min(cloud.points.size(), truth.size()); ++i)
    error = std::max(error, (cloud.points[i].getVector3fMap().cast<double>() + cloud.coordinate_offset - truth[i]).norm());
  return error;
}

}  // namespace

TEST(CloudIoFarCoordinates, NationalGridCoordinatesKeepTheirPrecisionThroughEveryFormat) {
  TempDir dir;
  const std::vector<Eigen::Vector3d> truth = utmBoxPoints();
  writeBytes(dir.file("utm.xyz"), xyzText(truth));
  const LabelledCloud cloud = paco::io::loadCloud(dir.file("utm.xyz"));
  // The centre (500006.12, 5412349.8, 103.5) rounded to the hundred at or above the 15.6 m diagonal.
  EXPECT_EQ(cloud.coordinate_offset, Eigen::Vector3d(500000.0, 5412300.0, 100.0));
  EXPECT_LT(largestError(cloud, truth), 1e-5);
  // Stored as float32 without the offset, the northing would be off by up to 0.25 m.
  EXPECT_GT(std::abs(static_cast<double>(static_cast<float>(truth[1].y())) - truth[1].y()), 0.01);

  for (const std::string name : {"a.pcd", "b.pcd", "c.pcd", "a.ply", "b.ply", "a.xyz", "a.npy", "a.vg"}) {
    SCOPED_TRACE(name);
    paco::io::CloudWriteOptions options;
    options.pcd_encoding = name == "a.pcd"   ? paco::io::PcdEncoding::Ascii
                           : name == "b.pcd" ? paco::io::PcdEncoding::Binary
                                             : paco::io::PcdEncoding::BinaryCompressed;
    options.ascii_ply = name == "a.ply";
    LabelledCloud labelled = cloud;
    if (name == "a.vg") labelled.labels.assign(cloud.points.size(), 0);  // one plane group: all of them
    paco::io::saveCloud(dir.file(name), labelled, options);
    const LabelledCloud back = paco::io::loadCloud(dir.file(name));
    if (paco::io::extensionOf(name) == ".pcd") {
      // PCD stores float32, for PCL's point types: within half of float32's 0.5 step at the
      // northing, and the box centre moves with it, so the tidy offset may round the other way.
      EXPECT_FALSE(back.coordinate_offset.isZero(0.0));
      EXPECT_LT(largestError(back, truth), 0.25);
    } else {
      EXPECT_EQ(back.coordinate_offset, cloud.coordinate_offset);
      EXPECT_LT(largestError(back, truth), 1e-5);
    }
  }
  // Text keeps the file's own digits: 123.45f plus the offset prints as the decimal it was read from.
  EXPECT_NE(readBytes(dir.file("a.xyz")).find("500000.12 5412345.81 100.5\n"), std::string::npos);
}

TEST(CloudIoFarCoordinates, CloudsNearTheOriginHaveNoOffsetAndWriteFloat32) {
  TempDir dir;
  writeBytes(dir.file("near.xyz"), "0 0 0\n1.5 2 3\n-20 4 1\n");
  const LabelledCloud cloud = paco::io::loadCloud(dir.file("near.xyz"));
  EXPECT_TRUE(cloud.coordinate_offset.isZero(0.0));
  EXPECT_EQ(cloud.points[1].x, 1.5f);
  paco::io::saveCloud(dir.file("near.ply"), cloud);
  EXPECT_NE(readBytes(dir.file("near.ply")).find("property float x\n"), std::string::npos);
  // 1 m at 100 m from the origin: float32 rounds by 6e-6 of the size at most, below the 1e-5 bound.
  writeBytes(dir.file("aside.xyz"), "100 100 100\n101 100 100\n100 101 100.5\n");
  EXPECT_TRUE(paco::io::loadCloud(dir.file("aside.xyz")).coordinate_offset.isZero(0.0));
}

TEST(CloudIoFarCoordinates, TheOffsetCanBeTurnedOff) {
  TempDir dir;
  const std::vector<Eigen::Vector3d> truth = utmBoxPoints();
  writeBytes(dir.file("utm.xyz"), xyzText(truth));
  paco::io::CloudReadOptions options;
  options.offset_far_coordinates = false;
  const LabelledCloud cloud = paco::io::loadCloud(dir.file("utm.xyz"), options);
  EXPECT_TRUE(cloud.coordinate_offset.isZero(0.0));
  for (std::size_t i = 0; i < truth.size(); ++i)
    EXPECT_LE((cloud.points[i].getVector3fMap().cast<double>() - truth[i]).norm(), 0.5) << i;  // float32's step
  EXPECT_GT(largestError(cloud, truth), 0.01);
}

TEST(CloudIoFarCoordinates, ThePointOfANonFiniteErrorIsNamedInFileCoordinates) {
  TempDir dir;
  writeBytes(dir.file("utm.xyz"), xyzText(utmBoxPoints()) + "500001.25 5412346.5 nan\n");
  try {
    paco::io::loadCloud(dir.file("utm.xyz"));
    FAIL() << "no error";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("(500001.25, 5412346.5, nan)"), std::string::npos) << e.what();
  }
}
