// The clean-up every assembled mesh goes through (src/mesh_cleanup.h): solids that touch along an
// edge or at a corner are separated into manifold sheets by copying the shared vertices.
#include "mesh_cleanup.h"

#include "shape_primitives.h"
#include "shapes.h"

#include <gtest/gtest.h>

namespace {

using paco::SurfaceMesh;

// Both meshes in one, with the second's vertex indices shifted; shared positions are welded.
SurfaceMesh joined(const SurfaceMesh& a, const SurfaceMesh& b) {
  SurfaceMesh m = paco::test::bothMeshes(a, b);
  paco::weldVertices(m, 1e-9);
  return m;
}

TEST(MeshCleanup, TwoCubesSharingAnEdgeBecomeTwoClosedManifoldSolids) {
  SurfaceMesh mesh = joined(paco::test::makeBox({0, 0, 0}, {1, 1, 1}), paco::test::makeBox({1, 1, 0}, {2, 2, 1}));
  ASSERT_EQ(mesh.vertices.size(), 14u);
  ASSERT_EQ(paco::analyseTopology(mesh).non_manifold_edges, 1u);

  paco::detail::cleanUpPolygonMesh(mesh);

  const paco::MeshTopology topology = paco::analyseTopology(mesh);
  EXPECT_TRUE(topology.isClosedManifold()) << topology.describe();
  EXPECT_EQ(topology.components, 2u);
  EXPECT_EQ(mesh.vertices.size(), 16u);  // each end of the shared edge copied once
  EXPECT_EQ(mesh.faces.size(), 12u);
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 1e-12);
}

TEST(MeshCleanup, TwoCubesSharingACornerGetACornerEach) {
  SurfaceMesh mesh = joined(paco::test::makeBox({0, 0, 0}, {1, 1, 1}), paco::test::makeBox({1, 1, 1}, {2, 2, 2}));
  ASSERT_EQ(mesh.vertices.size(), 15u);
  ASSERT_EQ(paco::analyseTopology(mesh).non_manifold_vertices, 1u);

  paco::detail::cleanUpPolygonMesh(mesh);

  const paco::MeshTopology topology = paco::analyseTopology(mesh);
  EXPECT_TRUE(topology.isClosedManifold()) << topology.describe();
  EXPECT_EQ(topology.components, 2u);
  EXPECT_EQ(mesh.vertices.size(), 16u);
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 1e-12);
}

// The same two cubes on an edge, but as one prism whose top and bottom are figure-eights: each
// lists the shared corner twice. Those faces hold all the faces at the corner together, so no copy
// can separate them, and the corner must stay one vertex in both places the face lists it; copying
// it for one of the two listings would tear the face from its sides.
TEST(MeshCleanup, AFaceThatTouchesItselfAtACornerKeepsThatCorner) {
  SurfaceMesh mesh = paco::test::makePrism({{0, 0}, {1, 0}, {1, 1}, {2, 1}, {2, 2}, {1, 2}, {1, 1}, {0, 1}}, 1.0);
  paco::weldVertices(mesh, 1e-9);
  ASSERT_EQ(mesh.vertices.size(), 14u);
  const paco::MeshTopology before = paco::analyseTopology(mesh);
  ASSERT_EQ(before.boundary_edges, 0u);
  ASSERT_EQ(before.inconsistent_edges, 0u);

  paco::detail::cleanUpPolygonMesh(mesh);

  const paco::MeshTopology after = paco::analyseTopology(mesh);
  EXPECT_EQ(mesh.vertices.size(), 14u);
  EXPECT_EQ(after.boundary_edges, 0u) << after.describe();
  EXPECT_EQ(after.inconsistent_edges, 0u) << after.describe();
  EXPECT_EQ(after.components, 1u);
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 1e-12);
}

}  // namespace
