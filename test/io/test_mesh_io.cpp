#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/io/mesh_io.h>

#include <gtest/gtest.h>

#include <random>

#include <Eigen/Geometry>

#include "shapes.h"
#include "test_support.h"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>

namespace {

using paco::IoError;
using paco::SurfaceMesh;
using paco::test::TempDir;
using paco::test::readBytes;
using paco::test::writeBytes;

/// A closed polygon mesh with awkward coordinates (rotated, far from the origin).
SurfaceMesh makeTestMesh() {
  SurfaceMesh mesh = paco::test::makeLBracket(1.0, 0.4, 0.6);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  paco::test::transformMesh(mesh, r, Eigen::Vector3d(1234.5678, -0.001, 1e-7));
  return mesh;
}

void expectSameMesh(const SurfaceMesh& a, const SurfaceMesh& b) {
  ASSERT_EQ(a.vertices.size(), b.vertices.size());
  for (std::size_t i = 0; i < a.vertices.size(); ++i) EXPECT_EQ(a.vertices[i], b.vertices[i]) << i;
  EXPECT_EQ(a.faces, b.faces);
}

void expectMeshError(const std::string& path, const std::string& problem) {
  try {
    paco::io::loadMesh(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const IoError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path), std::string::npos) << msg;
    EXPECT_NE(msg.find(problem), std::string::npos) << "expected '" << problem << "' in: " << msg;
  }
}

TEST(MeshIo, ObjOffPlyRoundTripExactlyWithPolygonFaces) {
  TempDir dir;
  const SurfaceMesh mesh = makeTestMesh();
  bool has_polygon = false;
  for (const auto& f : mesh.faces) has_polygon |= f.size() > 4;
  ASSERT_TRUE(has_polygon);  // the L-shaped caps have 6 corners
  for (const char* ext : {".obj", ".off", ".ply"}) {
    SCOPED_TRACE(ext);
    const std::string path = dir.file(std::string("m") + ext);
    paco::io::saveMesh(path, mesh);
    expectSameMesh(mesh, paco::io::loadMesh(path));
  }
}

TEST(MeshIo, StlRoundTripWeldsVerticesAndKeepsTheSolid) {
  TempDir dir;
  const SurfaceMesh mesh = paco::test::makeLBracket(1.0, 0.4, 0.6);  // float-exact coordinates
  paco::io::saveMesh(dir.file("m.stl"), mesh);
  const SurfaceMesh back = paco::io::loadMesh(dir.file("m.stl"));
  EXPECT_EQ(back.vertices.size(), mesh.vertices.size());  // welded back to shared vertices
  EXPECT_EQ(back.faces.size(), paco::triangulated(mesh).faces.size());
  EXPECT_TRUE(paco::analyseTopology(back).isClosedManifold());
  EXPECT_NEAR(paco::signedVolume(back), paco::signedVolume(mesh), 1e-6);
  EXPECT_NEAR(paco::surfaceArea(back), paco::surfaceArea(mesh), 1e-6);
  // Same triangles as the fan triangulation, corner by corner (to float precision).
  const SurfaceMesh tri = paco::triangulated(mesh);
  for (std::size_t f = 0; f < tri.faces.size(); ++f)
    for (int c = 0; c < 3; ++c)
      EXPECT_EQ(back.vertices[back.faces[f][c]], tri.vertices[tri.faces[f][c]].cast<float>().cast<double>());
  EXPECT_EQ(readBytes(dir.file("m.stl")).size(), 84 + 50 * tri.faces.size());
}

TEST(MeshIo, ReadsObjWithTexturesNormalsNegativeIndicesAndPolygons) {
  TempDir dir;
  writeBytes(dir.file("a.obj"),
             "# comment\nmtllib x.mtl\no part\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvt 0 0\nvn 0 0 1\n"
             "g top\nusemtl m\ns off\nf 1/1/1 2/1/1 3/1/1 4/1/1\nv 0.5 0.5 1\nf -5//1 -4//1 -1//1\nf 2/1 3/1 5/1\n");
  const SurfaceMesh m = paco::io::loadMesh(dir.file("a.obj"));
  ASSERT_EQ(m.vertices.size(), 5u);
  ASSERT_EQ(m.faces.size(), 3u);
  EXPECT_EQ(m.faces[0], (std::vector<std::uint32_t>{0, 1, 2, 3}));
  EXPECT_EQ(m.faces[1], (std::vector<std::uint32_t>{0, 1, 4}));
  EXPECT_EQ(m.faces[2], (std::vector<std::uint32_t>{1, 2, 4}));
}

TEST(MeshIo, ReadsOffWithCommentsAndColours) {
  TempDir dir;
  writeBytes(dir.file("a.off"),
             "COFF\n# a comment\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 255 0 0 255\n1 1 0 0 0 0 255\n0 1 0 0 0 0 255\n"
             "3 0 1 2 255 0 0\n3 0 2 3\n");
  const SurfaceMesh m = paco::io::loadMesh(dir.file("a.off"));
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.faces[1], (std::vector<std::uint32_t>{0, 2, 3}));
  EXPECT_EQ(m.vertices[2], Eigen::Vector3d(1, 1, 0));
}

TEST(MeshIo, ReadsAsciiPlyWithIntCountsAndAsciiStl) {
  TempDir dir;
  writeBytes(dir.file("a.ply"),
             "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list int uint vertex_index\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  SurfaceMesh m = paco::io::loadMesh(dir.file("a.ply"));
  ASSERT_EQ(m.faces.size(), 1u);
  EXPECT_EQ(m.faces[0].size(), 4u);

  writeBytes(dir.file("a.stl"),
             "solid square made of two facets\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n"
             "   vertex 1 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n"
             "   vertex 1 1 0\n   vertex -0 1 0\n  endloop\n endfacet\nendsolid square\n");
  m = paco::io::loadMesh(dir.file("a.stl"));
  EXPECT_EQ(m.vertices.size(), 4u);  // shared corners welded
  EXPECT_EQ(m.faces.size(), 2u);
  EXPECT_EQ(paco::analyseTopology(m).boundary_edges, 4u);
}

TEST(MeshIo, BinaryStlStartingWithSolidIsReadAsBinary) {
  TempDir dir;
  paco::io::saveMesh(dir.file("m.stl"), paco::test::makeBox({0, 0, 0}, {1, 2, 3}));
  std::string bytes = readBytes(dir.file("m.stl"));
  std::memcpy(&bytes[0], "solid box", 9);  // some exporters do this
  writeBytes(dir.file("solid.stl"), bytes);
  const SurfaceMesh m = paco::io::loadMesh(dir.file("solid.stl"));
  EXPECT_EQ(m.vertices.size(), 8u);
  EXPECT_EQ(m.faces.size(), 12u);
  EXPECT_NEAR(paco::signedVolume(m), 6.0, 1e-9);
}

TEST(MeshIo, PolygonMeshRoundTrip) {
  TempDir dir;
  const SurfaceMesh mesh = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  paco::io::savePolygonMesh(dir.file("p.ply"), paco::toPolygonMesh(mesh));
  const pcl::PolygonMesh back = paco::io::loadPolygonMesh(dir.file("p.ply"));
  EXPECT_EQ(back.polygons.size(), 6u);
  EXPECT_EQ(back.cloud.width * back.cloud.height, 8u);
}

TEST(MeshIoErrors, MissingEmptyAndUnknownExtension) {
  TempDir dir;
  for (const char* ext : {".obj", ".off", ".ply", ".stl"}) {
    expectMeshError(dir.file(std::string("absent") + ext), "file not found");
    writeBytes(dir.file(std::string("empty") + ext), "");
    expectMeshError(dir.file(std::string("empty") + ext), "empty");
  }
  writeBytes(dir.file("a.3ds"), "x");
  expectMeshError(dir.file("a.3ds"), "unknown mesh extension");
}

TEST(MeshIoErrors, TruncatedFiles) {
  TempDir dir;
  const SurfaceMesh mesh = makeTestMesh();
  const struct {
    const char* ext;
    const char* problem;
  } cases[] = {{".off", "truncated: header says"}, {".ply", "truncated: header says"}, {".stl", "truncated: header says"}};
  for (const auto& c : cases) {
    paco::io::saveMesh(dir.file(std::string("full") + c.ext), mesh);
    std::string bytes = readBytes(dir.file(std::string("full") + c.ext));
    bytes.resize(bytes.size() * 3 / 4);
    writeBytes(dir.file(std::string("cut") + c.ext), bytes);
    expectMeshError(dir.file(std::string("cut") + c.ext), c.problem);
  }
  // An OBJ cut short loses faces that refer to vertices never written.
  writeBytes(dir.file("cut.obj"), "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  expectMeshError(dir.file("cut.obj"), "face uses vertex 3 but the file has 2 vertices");
  writeBytes(dir.file("short.stl"), std::string(50, 'x'));
  expectMeshError(dir.file("short.stl"), "truncated: a binary STL needs at least 84 bytes");
  writeBytes(dir.file("cut_ascii.stl"), "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n");
  expectMeshError(dir.file("cut_ascii.stl"), "truncated");
}

TEST(MeshIoErrors, MalformedFiles) {
  TempDir dir;
  const struct {
    const char* name;
    std::string bytes;
    const char* problem;
  } cases[] = {
      {"a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n", "bad face index 'x'"},
      {"b.obj", "v 0 zero 0\n", "'zero' is not a number"},
      {"c.obj", "\x7f\x45LF\x02\x01\x01 binary", "is this an OBJ file?"},
      {"d.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n", "at least 3 vertices"},
      {"e.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "bad face index '0'"},
      {"a.off", "PLY\n3 1 0\n", "must start with 'OFF'"},
      {"b.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", "face 0 uses vertex 7 but there are 3 vertices"},
      {"c.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "expected \"<n >= 3>"},
      {"d.off", "OFF\nthree 1 0\n", "expected \"<vertices> <faces> <edges>\""},
      {"a.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
       "property list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
       "face 0 uses vertex 3 but there are 3 vertices"},
      {"b.ply",
       "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\n"
       "property int foo\nend_header\n0 0 0\n1 0 0\n0 1 0\n3\n",
       "no 'vertex_indices' list"},
      {"a.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0\nendloop\nendfacet\nendsolid\n",
       "'endloop' is not a number"},
      {"b.stl", "solid x\nbanana\nendsolid\n", "unexpected 'banana'"},
      {"c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "holds no faces (3 vertices only)"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    writeBytes(dir.file(c.name), c.bytes);
    expectMeshError(dir.file(c.name), c.problem);
  }
  // Faces are optional on request.
  EXPECT_EQ(paco::io::loadMesh(dir.file("c.obj"), true).vertices.size(), 3u);
}

TEST(MeshIoErrors, NonFiniteVertices) {
  TempDir dir;
  writeBytes(dir.file("nan.obj"), "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
  expectMeshError(dir.file("nan.obj"), "vertex 1 has non-finite");
  writeBytes(dir.file("inf.off"), "OFF\n3 1 0\n0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n");
  expectMeshError(dir.file("inf.off"), "vertex 1 has non-finite");
  SurfaceMesh mesh = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  mesh.vertices[3].z() = std::nan("");
  paco::io::saveMesh(dir.file("nan.ply"), mesh);
  expectMeshError(dir.file("nan.ply"), "vertex 3 has non-finite");
  paco::io::saveMesh(dir.file("nan.stl"), mesh);
  expectMeshError(dir.file("nan.stl"), "non-finite");
}

// A corrupt list count (0xFFFFFFFF in a file of a few hundred bytes) is reported with both
// numbers, so that the user can tell a cut-short file from a corrupt count.
TEST(MeshIoErrors, AListLongerThanTheFileSaysHowLong) {
  TempDir dir;
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uint int vertex_indices\nend_header\n";
  const float corners[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  bytes.append(reinterpret_cast<const char*>(corners), sizeof(corners));
  const std::uint32_t count = 0xFFFFFFFFu;
  bytes.append(reinterpret_cast<const char*>(&count), sizeof(count));
  const std::int32_t indices[3] = {0, 1, 2};
  bytes.append(reinterpret_cast<const char*>(indices), sizeof(indices));
  writeBytes(dir.file("corrupt.ply"), bytes);
  expectMeshError(dir.file("corrupt.ply"),
                  "face 0 has a list of 4294967295 items (17179869180 bytes) but the file ends 12 bytes later; "
                  "if the file is whole, that list count is corrupt");
}

TEST(MeshIoErrors, WriterFailures) {
  TempDir dir;
  const SurfaceMesh mesh = paco::test::makeBox({0, 0, 0}, {1, 1, 1});
  for (const char* name : {"no/dir/m.obj", "no/dir/m.off", "no/dir/m.ply", "no/dir/m.stl"}) {
    try {
      paco::io::saveMesh(dir.file(name), mesh);
      ADD_FAILURE() << "no error writing " << name;
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("cannot open for writing"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(paco::io::saveMesh(dir.file("m.dae"), mesh), IoError);
  SurfaceMesh bad = mesh;
  bad.faces[0][0] = 99;
  EXPECT_THROW(paco::io::saveMesh(dir.file("bad.obj"), bad), IoError);
  EXPECT_FALSE(std::filesystem::exists(dir.file("bad.obj")));
}

TEST(MeshIoRobustness, CorruptedFilesOnlyEverThrowIoError) {
  TempDir dir;
  const SurfaceMesh mesh = makeTestMesh();
  std::mt19937 rng(13);
  std::size_t loads = 0, failures = 0;
  for (const char* ext : {".obj", ".off", ".ply", ".stl"}) {
    const std::string file = dir.file(std::string("m") + ext);
    paco::io::saveMesh(file, mesh);
    const std::string original = readBytes(file);
    for (int trial = 0; trial < 40; ++trial) {
      std::string bytes = original;
      if (trial % 3 == 0) bytes.resize(rng() % bytes.size());
      else
        for (int k = 0; k < 1 + trial % 5; ++k) bytes[rng() % bytes.size()] = static_cast<char>(rng());
      const std::string bad = dir.file(std::string("bad") + ext);
      writeBytes(bad, bytes);
      ++loads;
      try {
        paco::io::loadMesh(bad);
      } catch (const IoError&) {
        ++failures;
      } catch (const std::exception& e) {
        ADD_FAILURE() << ext << " trial " << trial << ": " << e.what();
      }
    }
  }
  EXPECT_GT(failures, loads / 4);
}

}  // namespace

namespace {

TEST(MeshIo, PlyKeepsFacesWithMoreThan255Vertices) {
  paco::test::TempDir dir;
  std::vector<Eigen::Vector2d> circle;
  for (int i = 0; i < 300; ++i)
    circle.emplace_back(std::cos(2 * paco::kPi * i / 300.0), std::sin(2 * paco::kPi * i / 300.0));
  const paco::SurfaceMesh prism = paco::test::makePrism(circle, 0.5);
  paco::io::saveMesh(dir.file("p.ply"), prism);
  const paco::SurfaceMesh back = paco::io::loadMesh(dir.file("p.ply"));
  EXPECT_EQ(back.faces, prism.faces);
  EXPECT_EQ(back.vertices, prism.vertices);
}

}  // namespace
