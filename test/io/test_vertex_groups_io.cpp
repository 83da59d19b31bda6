#include <paco/common/error.h>
#include <paco/io/cloud_io.h>
#include <paco/io/vertex_groups_io.h>

#include <gtest/gtest.h>

#include "test_support.h"

#include <cmath>
#include <random>

namespace {

using paco::IoError;
using paco::PlanarPrimitive;
using paco::Plane;
using paco::test::TempDir;
using paco::test::readBytes;
using paco::test::writeBytes;

/// Three primitives of a box corner: points sampled on z = 0.5, x = -1 and y = 2 (in float-exact
/// coordinates), with confidences 1, 0.75 and 0.3.
std::vector<PlanarPrimitive> makePrimitives() {
  std::vector<PlanarPrimitive> prims(3);
  prims[0].plane = Plane({0, 0, 1}, -0.5);
  prims[1].plane = Plane({-1, 0, 0}, -1.0);
  prims[2].plane = Plane({0, 1, 0}, -2.0);
  prims[1].confidence = 0.75f;
  prims[2].confidence = 0.3f;
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> u(0, 64);
  for (std::size_t g = 0; g < prims.size(); ++g)
    for (int i = 0; i < 20 + 5 * static_cast<int>(g); ++i) {
      const float a = u(rng) / 64.0f, b = u(rng) / 64.0f;
      pcl::PointNormal p;
      const Eigen::Vector3d n = prims[g].plane.normal;
      if (g == 0) { p.x = a; p.y = b; p.z = 0.5f; }
      if (g == 1) { p.x = -1.0f; p.y = a; p.z = b; }
      if (g == 2) { p.x = a; p.y = 2.0f; p.z = b; }
      p.normal_x = static_cast<float>(n.x()); p.normal_y = static_cast<float>(n.y()); p.normal_z = static_cast<float>(n.z());
      p.curvature = 0;
      prims[g].points.push_back(p);
    }
  return prims;
}

void expectSameGroups(const paco::io::VertexGroups& a, const paco::io::VertexGroups& b) {
  ASSERT_EQ(a.points.size(), b.points.size());
  EXPECT_EQ(a.has_normals, b.has_normals);
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].getVector3fMap(), b.points[i].getVector3fMap()) << i;
    EXPECT_EQ(a.points[i].getNormalVector3fMap(), b.points[i].getNormalVector3fMap()) << i;
  }
  EXPECT_EQ(a.segmentation.labels, b.segmentation.labels);
  ASSERT_EQ(a.segmentation.size(), b.segmentation.size());
  for (std::size_t g = 0; g < a.segmentation.size(); ++g) {
    EXPECT_EQ(a.segmentation.segments[g].indices, b.segmentation.segments[g].indices);
    EXPECT_LT((a.segmentation.planes[g].normal - b.segmentation.planes[g].normal).norm(), 1e-7);
    EXPECT_NEAR(a.segmentation.planes[g].offset, b.segmentation.planes[g].offset, 1e-7);
  }
  EXPECT_EQ(a.group_labels, b.group_labels);
  EXPECT_EQ(a.group_colors, b.group_colors);
  EXPECT_EQ(a.confidences, b.confidences);
}

TEST(VertexGroupsIo, VgAndBvgRoundTripGroupsPlanesLabelsAndConfidences) {
  TempDir dir;
  const auto vg = paco::io::toVertexGroups(makePrimitives());
  ASSERT_EQ(vg.segmentation.size(), 3u);
  EXPECT_EQ(vg.group_labels[1], "confidence=0.75");
  for (const char* name : {"p.vg", "p.bvg"}) {
    SCOPED_TRACE(name);
    paco::io::saveVertexGroups(dir.file(name), vg);
    const auto back = paco::io::loadVertexGroups(dir.file(name));
    expectSameGroups(vg, back);
    const auto prims = paco::io::toPrimitives(back);
    const auto original = makePrimitives();
    ASSERT_EQ(prims.size(), original.size());
    for (std::size_t g = 0; g < prims.size(); ++g) {
      EXPECT_EQ(prims[g].points.size(), original[g].points.size());
      EXPECT_FLOAT_EQ(prims[g].confidence, original[g].confidence);
      EXPECT_NEAR(prims[g].plane.offset, original[g].plane.offset, 1e-7);
      for (const auto& p : prims[g].points)
        EXPECT_NEAR(prims[g].plane.signedDistance(p.getVector3fMap().cast<double>()), 0.0, 1e-6);
    }
  }
}

TEST(VertexGroupsIo, AsciiLayoutIsPolyFits) {
  TempDir dir;
  paco::io::saveVertexGroups(dir.file("p.vg"), paco::io::toVertexGroups(makePrimitives()));
  const std::string text = readBytes(dir.file("p.vg"));
  EXPECT_EQ(text.rfind("num_points: 75\n", 0), 0u);
  for (const char* key : {"\nnum_colors: 0\n", "\nnum_normals: 75\n", "\nnum_groups: 3\n", "\ngroup_type: 0\n",
                          "\nnum_group_parameters: 4\n", "\ngroup_parameters: 0 0 1 -0.5\n",
                          "\ngroup_label: confidence=0.3\n", "\ngroup_num_point: 30\n", "\nnum_children: 0\n"})
    EXPECT_NE(text.find(key), std::string::npos) << key;
  // The binary layout: int32 counts and float32 values; 75 points with normals and 3 groups.
  paco::io::saveVertexGroups(dir.file("p.bvg"), paco::io::toVertexGroups(makePrimitives()));
  const std::size_t labels = std::string("confidence=1").size() + std::string("confidence=0.75").size() +
                             std::string("confidence=0.3").size();
  EXPECT_EQ(readBytes(dir.file("p.bvg")).size(),
            4 + 75 * 12 + 4 + 4 + 75 * 12 + 4 + 3 * (4 + 4 + 16 + 4 + 12 + 4 + 4) + labels + 75 * 4);
}

TEST(VertexGroupsIo, ReadsEasy3dStyleFileWithZeroParametersColoursAndChildren) {
  TempDir dir;
  // Easy3D writes all points on one line, colours, zero plane parameters and "unknown" labels.
  writeBytes(dir.file("e.vg"),
             "num_points: 5\n0 0 1 1 0 1 0 1 1 1 1 1 5 5 5 \nnum_colors: 5\n"
             "0.1 0.2 0.3 0.1 0.2 0.3 0.1 0.2 0.3 0.1 0.2 0.3 0.1 0.2 0.3\nnum_normals: 0\nnum_groups: 1\n"
             "group_type: 0\nnum_group_parameters: 4\ngroup_parameters: 0 0 0 0\ngroup_label: unknown\n"
             "group_color: 0.3 0.6 1\ngroup_num_point: 4\n0 1 2 3\nnum_children: 1\n"
             "group_type: 0\nnum_group_parameters: 4\ngroup_parameters: 0 0 1 -1\ngroup_label: child\n"
             "group_color: 255 0 51\ngroup_num_points: 2\n0 1\n");
  const auto vg = paco::io::loadVertexGroups(dir.file("e.vg"));
  ASSERT_EQ(vg.points.size(), 5u);
  EXPECT_FALSE(vg.has_normals);
  ASSERT_EQ(vg.segmentation.size(), 1u);
  EXPECT_EQ(vg.segmentation.labels, (std::vector<int>{0, 0, 0, 0, -1}));
  // The plane is fitted to the group's points: z = 1.
  EXPECT_NEAR(std::abs(vg.segmentation.planes[0].normal.z()), 1.0, 1e-9);
  EXPECT_NEAR(vg.segmentation.planes[0].signedDistance({0.3, 0.3, 1.0}), 0.0, 1e-9);
  EXPECT_EQ(vg.group_labels[0], "unknown");
  EXPECT_EQ(vg.confidences[0], 1.0f);
  EXPECT_EQ(vg.group_colors[0], Eigen::Vector3f(0.3f, 0.6f, 1.0f));
  // As a cloud: labels from the groups; points without normals get the plane's as primitives.
  const auto cloud = paco::io::loadCloud(dir.file("e.vg"));
  EXPECT_EQ(cloud.labels, (std::vector<int>{0, 0, 0, 0, -1}));
  const auto prims = paco::io::toPrimitives(vg);
  EXPECT_NEAR(std::abs(prims[0].points[0].normal_z), 1.0f, 1e-6f);
}

TEST(VertexGroupsIoErrors, MissingEmptyTruncatedMalformedNonFinite) {
  TempDir dir;
  const auto vg = paco::io::toVertexGroups(makePrimitives());
  for (const char* ext : {".vg", ".bvg"}) {
    SCOPED_TRACE(ext);
    const std::string full = dir.file(std::string("full") + ext), cut = dir.file(std::string("cut") + ext);
    EXPECT_THROW(paco::io::loadVertexGroups(dir.file(std::string("absent") + ext)), IoError);
    writeBytes(dir.file(std::string("empty") + ext), "");
    EXPECT_THROW(paco::io::loadVertexGroups(dir.file(std::string("empty") + ext)), IoError);
    paco::io::saveVertexGroups(full, vg);
    std::string bytes = readBytes(full);
    for (std::size_t keep : {bytes.size() / 3, bytes.size() - 7}) {
      writeBytes(cut, bytes.substr(0, keep));
      try {
        paco::io::loadVertexGroups(cut);
        ADD_FAILURE() << "no error for " << keep << " bytes";
      } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find(cut), std::string::npos) << e.what();
      }
    }
  }
  const auto expectProblem = [&](const std::string& name, const std::string& bytes, const std::string& problem) {
    writeBytes(dir.file(name), bytes);
    try {
      paco::io::loadVertexGroups(dir.file(name));
      ADD_FAILURE() << "no error for " << name;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find(problem), std::string::npos) << e.what();
    }
  };
  const std::string head = "num_points: 3\n0 0 0\n1 0 0\n0 1 0\nnum_colors: 0\nnum_normals: 0\nnum_groups: 1\n";
  const std::string group = "group_type: 0\nnum_group_parameters: 4\ngroup_parameters: 0 0 1 0\ngroup_label: a\n"
                            "group_color: 1 0 0\ngroup_num_point: 3\n";
  expectProblem("garbage.vg", "solid x\nfacet\n", "expected 'num_points:'");
  expectProblem("range.vg", head + group + "0 1 3\nnum_children: 0\n", "group 0 uses point 3 of 3 points");
  expectProblem("type.vg", head + "group_type: 2\nnum_group_parameters: 0\ngroup_parameters:\ngroup_label: cyl\n"
                "group_color: 1 0 0\ngroup_num_point: 0\n\nnum_children: 0\n", "only planes");
  expectProblem("colors.vg", "num_points: 1\n0 0 0\nnum_colors: 2\n", "num_colors is 2");
  expectProblem("nan.vg", "num_points: 2\n0 0 0\n1 nan 0\nnum_colors: 0\nnum_normals: 0\nnum_groups: 0\n",
                "point 1 has non-finite");
  expectProblem("noplane.vg", "num_points: 2\n0 0 0\n1 0 0\nnum_colors: 0\nnum_normals: 0\nnum_groups: 1\n"
                "group_type: 0\nnum_group_parameters: 4\ngroup_parameters: 0 0 0 0\ngroup_label: a\n"
                "group_color: 1 0 0\ngroup_num_point: 2\n0 1\nnum_children: 0\n", "no valid plane");
  expectProblem("index.vg", head + group + "0 one 2\nnum_children: 0\n", "'one' (group point indices");
  expectProblem("huge.bvg", std::string("\xff\xff\xff\x7f", 4), "truncated: header says 2147483647 points");
  expectProblem("neg.bvg", std::string("\xff\xff\xff\xff", 4), "negative num_points");
  expectProblem("ext.vgx", "x", "unknown vertex group extension");
  // Writer errors: unwritable path and inconsistent groups.
  EXPECT_THROW(paco::io::saveVertexGroups(dir.file("no/dir/a.vg"), vg), IoError);
  auto bad = vg;
  bad.segmentation.segments[0].indices.push_back(1000);
  EXPECT_THROW(paco::io::saveVertexGroups(dir.file("bad.vg"), bad), IoError);
  bad = vg;
  bad.segmentation.planes.pop_back();
  EXPECT_THROW(paco::io::saveVertexGroups(dir.file("bad.vg"), bad), IoError);
}

}  // namespace

TEST(VertexGroupsIo, FarCoordinatesMoveToTheOffsetWithTheirPlanes) {
  // Four points of the wall x = 500003.5 at a UTM northing, and the wall's plane as PolyFit writes it.
  TempDir dir;
  writeBytes(dir.file("wall.vg"),
             "num_points: 4\n500003.5 5412345.25 100.5\n500003.5 5412349.75 100.5\n500003.5 5412345.25 106\n"
             "500003.5 5412349.75 106\nnum_colors: 0\nnum_normals: 0\nnum_groups: 1\ngroup_type: 0\n"
             "num_group_parameters: 4\ngroup_parameters: 1 0 0 -500003.5\ngroup_label: unknown\n"
             "group_color: 1 0 0\ngroup_num_point: 4\n0 1 2 3\nnum_children: 0\n");
  const paco::io::VertexGroups vg = paco::io::loadVertexGroups(dir.file("wall.vg"));
  // The centre (500003.5, 5412347.5, 103.25) rounded to the ten at or above the 7.1 m diagonal.
  EXPECT_EQ(vg.coordinate_offset, Eigen::Vector3d(500000.0, 5412350.0, 100.0));
  EXPECT_FLOAT_EQ(vg.points[1].y, -0.25f);
  // The plane moved with the points: it is x = 3.5 in the points' frame.
  const Plane& plane = vg.segmentation.planes.at(0);
  EXPECT_DOUBLE_EQ(plane.offset, -3.5);
  for (const auto& p : vg.points) EXPECT_NEAR(plane.signedDistance(p.getVector3fMap().cast<double>()), 0.0, 1e-9);

  // Written back, points and plane are in the file's coordinates again, digit for digit.
  paco::io::saveVertexGroups(dir.file("back.vg"), vg);
  const std::string text = readBytes(dir.file("back.vg"));
  EXPECT_NE(text.find("500003.5 5412349.75 106\n"), std::string::npos) << text;
  EXPECT_NE(text.find("group_parameters: 1 0 0 -500003.5\n"), std::string::npos) << text;
}
