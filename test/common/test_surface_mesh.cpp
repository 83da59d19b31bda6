#include <paco/common/error.h>
#include <paco/common/surface_mesh.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Geometry>

namespace {
// Axis-aligned box [0,a]x[0,b]x[0,c] with outward quads.
paco::SurfaceMesh box(double a, double b, double c) {
  paco::SurfaceMesh m;
  m.vertices = {{0, 0, 0}, {a, 0, 0}, {a, b, 0}, {0, b, 0}, {0, 0, c}, {a, 0, c}, {a, b, c}, {0, b, c}};
  m.faces = {{0, 3, 2, 1}, {4, 5, 6, 7}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 4, 7, 3}, {1, 2, 6, 5}};
  return m;
}
}  // namespace

TEST(SurfaceMesh, BoxIsClosedManifoldOrientedWithKnownAreaAndVolume) {
  const auto m = box(1, 2, 3);
  const auto t = paco::analyseTopology(m);
  EXPECT_TRUE(t.isClosedManifold()) << t.describe();
  EXPECT_EQ(t.components, 1u);
  EXPECT_NEAR(paco::surfaceArea(m), 2 * (2 + 3 + 6), 1e-12);
  EXPECT_NEAR(paco::signedVolume(m), 6.0, 1e-12);
  EXPECT_TRUE(paco::faceNormal(m, 1).isApprox(Eigen::Vector3d(0, 0, 1)));
  EXPECT_EQ(m.numTriangles(), 12u);
  EXPECT_NEAR(paco::signedVolume(paco::triangulated(m)), 6.0, 1e-12);
}

TEST(SurfaceMesh, DetectsHolesFlipsAndNonManifoldEdges) {
  auto open = box(1, 1, 1);
  open.faces.pop_back();
  auto t = paco::analyseTopology(open);
  EXPECT_FALSE(t.isClosed());
  EXPECT_EQ(t.boundary_edges, 4u);

  auto flipped = box(1, 1, 1);
  std::reverse(flipped.faces[0].begin(), flipped.faces[0].end());
  t = paco::analyseTopology(flipped);
  EXPECT_TRUE(t.isClosed());
  EXPECT_FALSE(t.isOriented());
  EXPECT_EQ(t.inconsistent_edges, 4u);

  auto inverted = box(1, 1, 1);
  paco::flipFaces(inverted);
  EXPECT_NEAR(paco::signedVolume(inverted), -1.0, 1e-12);

  auto fin = box(1, 1, 1);
  fin.vertices.push_back({0.5, 0.5, 2});
  fin.faces.push_back({4, 5, 8});  // a third face on edge 4-5
  t = paco::analyseTopology(fin);
  EXPECT_EQ(t.non_manifold_edges, 1u);
  EXPECT_FALSE(t.isClosedManifold());
}

TEST(SurfaceMesh, TwoBoxesTouchingAtAVertexAreNonManifold) {
  auto a = box(1, 1, 1);
  auto b = box(1, 1, 1);
  const auto offset = static_cast<std::uint32_t>(a.vertices.size());
  for (auto v : b.vertices) a.vertices.push_back(v + Eigen::Vector3d(1, 1, 1));
  for (auto f : b.faces) {
    for (auto& i : f) i = (i == 0) ? 6 : i + offset;  // share corner (1,1,1)
    a.faces.push_back(f);
  }
  const auto t = paco::analyseTopology(a);
  EXPECT_TRUE(t.isClosed());
  EXPECT_EQ(t.non_manifold_vertices, 1u);
  EXPECT_FALSE(t.isManifold());
}

TEST(SurfaceMesh, WeldMergesDuplicatedCorners) {
  // A "triangle soup" box: every quad has its own 4 vertices, as CGAL's raw output does.
  const auto ref = box(1, 1, 1);
  paco::SurfaceMesh soup;
  for (const auto& f : ref.faces) {
    std::vector<std::uint32_t> nf;
    for (auto i : f) {
      nf.push_back(static_cast<std::uint32_t>(soup.vertices.size()));
      soup.vertices.push_back(ref.vertices[i] + Eigen::Vector3d::Constant(1e-9));
    }
    soup.faces.push_back(nf);
  }
  EXPECT_FALSE(paco::analyseTopology(soup).isClosed());
  EXPECT_EQ(paco::weldVertices(soup, 1e-6), 16u);
  EXPECT_EQ(soup.vertices.size(), 8u);
  EXPECT_TRUE(paco::analyseTopology(soup).isClosedManifold());
}

// Tolerance 0 merges exact duplicates only, also far from the origin, where a neighbour 1e-3 away
// must stay; coordinates of 1e300 with a small tolerance merge as well (the cell index is clamped:
// the sanitizer build found it overflowing).
TEST(SurfaceMesh, WeldingMergesExactDuplicatesWithToleranceZeroAndFarFromTheOrigin) {
  for (const double at : {0.0, 1e12}) {
    SCOPED_TRACE(at);
    paco::SurfaceMesh m;
    m.vertices = {{at, 0, 0}, {at, 0, 0}, {at, 1, 0}, {at, 0, 1}, {at + 1e-3, 1, 1}};
    m.faces = {{0, 2, 3}, {1, 3, 4}};
    EXPECT_EQ(paco::weldVertices(m, 0.0), 1u);
    ASSERT_EQ(m.vertices.size(), 4u);
    EXPECT_EQ(m.faces[1][0], 0u);
  }
  paco::SurfaceMesh far;
  far.vertices = {{1e300, 0, 0}, {1e300, 0, 0}, {-1e300, 0, 0}, {0, 1, 0}};
  far.faces = {{0, 2, 3}, {1, 3, 2}};
  EXPECT_EQ(paco::weldVertices(far, 1e-6), 1u);
  EXPECT_EQ(far.vertices.size(), 3u);
}

TEST(SurfaceMesh, SamplingIsUniformByAreaAndDeterministic) {
  const auto m = box(1, 1, 4);  // side faces 4x larger than top and bottom
  const auto s1 = paco::sampleSurface(m, 20000, 7);
  const auto s2 = paco::sampleSurface(m, 20000, 7);
  ASSERT_EQ(s1.points.size(), 20000u);
  EXPECT_EQ(s1.points, s2.points);
  std::size_t top = 0;
  for (std::size_t i = 0; i < s1.points.size(); ++i) {
    EXPECT_NEAR(std::abs(s1.normals[i].norm()), 1.0, 1e-12);
    top += s1.faces[i] == 1;
    // Every sample lies on its own face plane.
    const Eigen::Vector3d n = paco::faceNormal(m, s1.faces[i]);
    EXPECT_NEAR(n.dot(s1.points[i] - m.vertices[m.faces[s1.faces[i]][0]]), 0, 1e-12);
  }
  EXPECT_NEAR(static_cast<double>(top) / 20000.0, 1.0 / 18.0, 0.01);  // area 1 of 18
  EXPECT_NE(paco::sampleSurface(m, 10, 8).points, paco::sampleSurface(m, 10, 7).points);
}

// An L-shaped face in z = 0 (area 3: a 2 x 2 square less its 1 x 1 corner at x, y > 1), its
// loop starting at the reflex corner (1, 1), with a straight corner at (0, 1) on the left edge. A
// fan from (1, 1) covers the missing corner too (area 4): the assemblers merge a plane's
// faces into such polygons, and the metrics sampled them by fans.
namespace {
paco::SurfaceMesh lFace() {
  paco::SurfaceMesh m;
  m.vertices = {{1, 1, 0}, {1, 2, 0}, {0, 2, 0}, {0, 1, 0}, {0, 0, 0}, {2, 0, 0}, {2, 1, 0}};
  m.faces = {{0, 1, 2, 3, 4, 5, 6}};
  return m;
}

bool insideL(const Eigen::Vector3d& p) {
  const double eps = 1e-9;
  return p.x() > -eps && p.y() > -eps && p.x() < 2 + eps && p.y() < 2 + eps && (p.x() < 1 + eps || p.y() < 1 + eps);
}
}  // namespace

TEST(SurfaceMesh, ANonConvexFaceIsTriangulatedAndSampledWithinItself) {
  const paco::SurfaceMesh m = lFace();
  std::vector<std::vector<std::uint32_t>> triangles;
  paco::triangulateFace(m, 0, triangles);
  EXPECT_EQ(triangles.size(), 4u);  // 7 corners, one straight: 6 - 2
  double area = 0;
  for (const auto& t : triangles) {
    const Eigen::Vector3d a = m.vertices[t[0]], b = m.vertices[t[1]], c = m.vertices[t[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    EXPECT_GT(n.z(), 0.0);  // the face's orientation
    area += 0.5 * n.norm();
    EXPECT_TRUE(insideL((a + b + c) / 3.0)) << ((a + b + c) / 3.0).transpose();
  }
  EXPECT_NEAR(area, 3.0, 1e-12);
  EXPECT_NEAR(paco::surfaceArea(m), 3.0, 1e-12);
  const paco::SurfaceMesh tri = paco::triangulated(m);
  EXPECT_EQ(tri.faces.size(), 4u);
  for (const auto& p : paco::sampleSurface(m, 5000, 3).points) ASSERT_TRUE(insideL(p)) << p.transpose();
  // Flipped, the same cover with the other orientation.
  paco::SurfaceMesh flipped = m;
  paco::flipFaces(flipped);
  triangles.clear();
  paco::triangulateFace(flipped, 0, triangles);
  ASSERT_EQ(triangles.size(), 4u);
  for (const auto& t : triangles)
    EXPECT_LT((flipped.vertices[t[1]] - flipped.vertices[t[0]]).cross(flipped.vertices[t[2]] - flipped.vertices[t[0]]).z(), 0.0);
  // In any plane: the face turned about a tilted axis keeps its area.
  paco::SurfaceMesh turned = m;
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  for (auto& v : turned.vertices) v = r * v;
  EXPECT_NEAR(paco::surfaceArea(turned), 3.0, 1e-9);
}

TEST(SurfaceMesh, RandomStarShapedFacesAreCutIntoTrianglesOfTheirExactArea) {
  // Star-shaped polygons with random radii are simple and mostly non-convex. Their triangles must
  // add up to the polygon's (shoelace) area, none may be flipped, and none may overlap another
  // (then the areas would add up to more).
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> radius(0.2, 1.0), jitter(-0.3, 0.3);
  std::size_t non_convex = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const int n = 4 + trial % 12;
    paco::SurfaceMesh m;
    std::vector<std::uint32_t> loop;
    double shoelace = 0.0;
    for (int k = 0; k < n; ++k) {
      const double angle = 2.0 * 3.14159265358979 * (k + 0.5 + jitter(rng)) / n, r = radius(rng);
      m.vertices.emplace_back(r * std::cos(angle), r * std::sin(angle), 0.0);
      loop.push_back(static_cast<std::uint32_t>(k));
    }
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d& a = m.vertices[k];
      const Eigen::Vector3d& b = m.vertices[(k + 1) % n];
      shoelace += 0.5 * (a.x() * b.y() - b.x() * a.y());
    }
    m.faces = {loop};
    bool convex = true;
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector3d e1 = m.vertices[(k + 1) % n] - m.vertices[k], e2 = m.vertices[(k + 2) % n] - m.vertices[(k + 1) % n];
      convex = convex && e1.cross(e2).z() >= 0.0;
    }
    non_convex += !convex;
    std::vector<std::vector<std::uint32_t>> triangles;
    paco::triangulateFace(m, 0, triangles);
    double area = 0.0;
    for (const auto& t : triangles) {
      const double z = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]).z();
      EXPECT_GE(z, -1e-12) << "trial " << trial;
      area += 0.5 * std::abs(z);
    }
    EXPECT_NEAR(area, shoelace, 1e-9 * std::max(1.0, shoelace)) << "trial " << trial << ", " << n << " corners";
  }
  EXPECT_GT(non_convex, 100u);  // the test is about non-convex faces
}

// The same box listed in a shuffled order, each face starting at another corner, one corner at -0:
// sorted, both lists are identical, and the box is still a closed outward solid.
TEST(SurfaceMesh, SortingCanonicallyListsTheSameSurfaceInOneOrder) {
  paco::SurfaceMesh a = box(1, 2, 3);
  paco::SurfaceMesh b = a;
  std::vector<std::uint32_t> to_shuffled = {5, 2, 7, 0, 3, 6, 1, 4};
  b.vertices.assign(8, Eigen::Vector3d::Zero());
  for (std::uint32_t v = 0; v < 8; ++v) b.vertices[to_shuffled[v]] = a.vertices[v];
  b.vertices[to_shuffled[0]].x() = -0.0;
  for (auto& face : b.faces) {
    for (auto& v : face) v = to_shuffled[v];
    std::rotate(face.begin(), face.begin() + 1, face.end());
  }
  std::reverse(b.faces.begin(), b.faces.end());
  ASSERT_NE(a.faces, b.faces);
  paco::sortMeshCanonically(a);
  paco::sortMeshCanonically(b);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_FALSE(std::signbit(b.vertices[0].x()));  // printed as 0, not -0
  EXPECT_EQ(b.vertices.front(), Eigen::Vector3d(0, 0, 0));
  EXPECT_EQ(b.vertices.back(), Eigen::Vector3d(1, 2, 3));
  for (const auto& face : b.faces) EXPECT_EQ(*std::min_element(face.begin(), face.end()), face.front());
  EXPECT_TRUE(paco::analyseTopology(b).isClosedManifold());
  EXPECT_NEAR(paco::signedVolume(b), 6.0, 1e-12);
}

TEST(SurfaceMesh, ValidateRejectsBadIndicesAndNaN) {
  auto m = box(1, 1, 1);
  m.faces.push_back({0, 1, 99});
  EXPECT_THROW(m.validate("box"), paco::InvalidInputError);
  auto n = box(1, 1, 1);
  n.vertices[0].x() = NAN;
  EXPECT_THROW(n.validate(), paco::InvalidInputError);
  paco::SurfaceMesh empty;
  EXPECT_THROW(paco::sampleSurface(empty, 10, 1), paco::InvalidInputError);
}

TEST(SurfaceMesh, PolygonMeshRoundTrip) {
  const auto m = box(1, 2, 3);
  const auto back = paco::fromPolygonMesh(paco::toPolygonMesh(m));
  ASSERT_EQ(back.vertices.size(), 8u);
  EXPECT_EQ(back.faces, m.faces);
  EXPECT_TRUE(back.vertices[6].isApprox(Eigen::Vector3d(1, 2, 3)));
}

#include "shapes.h"

TEST(TestShapes, AreClosedOrientedSolidsWithKnownVolumes) {
  struct Case { const char* name; paco::SurfaceMesh mesh; double volume; };
  const Case cases[] = {{"box", paco::test::makeBox({-1, 0, 0}, {1, 2, 3}), 12.0},
                        {"L", paco::test::makeLBracket(1.0, 0.4, 0.6), 0.6 * (1 - 0.36)},
                        {"chamfer", paco::test::makeChamferedCube(0.3), 1 - 0.045},
                        {"boss", paco::test::makeBossOnSlab(), 5.0},
                        {"tube", paco::test::makeSquareTube(0.6, 0.05, 1.0), 0.36 - 0.25},
                        {"channel", paco::test::makeUChannel(1.0, 0.6, 0.05, 1.0), 0.6 - 0.9 * 0.55}};
  for (const auto& c : cases) {
    const auto t = paco::analyseTopology(c.mesh);
    EXPECT_TRUE(t.isClosedManifold()) << c.name << ": " << t.describe();
    EXPECT_NEAR(paco::signedVolume(c.mesh), c.volume, 1e-12) << c.name;
  }
}
