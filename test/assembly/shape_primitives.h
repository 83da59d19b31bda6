#pragma once
// Exact planar primitives of the generated test shapes (points sampled on each face plane), shared
// by the assembly tests.
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>

#include <cstddef>
#include <random>
#include <vector>

namespace paco::test {

/// Bounding-box diagonal of a mesh.
double diagonalOf(const SurfaceMesh& mesh);
/// The distinct planes of a mesh's faces, outward oriented: faces whose normals agree to
/// `angle_cosine` and whose offsets agree to `offset_fraction` of the diagonal are grouped.
/// Optionally the plane index of every face.
std::vector<Plane> facePlanes(const SurfaceMesh& mesh, std::vector<int>* face_plane = nullptr,
                              double angle_cosine = 1 - 1e-6, double offset_fraction = 1e-6);
/// One primitive per distinct face plane, with `samples` points (area-uniform, seeded) in total.
std::vector<PlanarPrimitive> primitivesOf(const SurfaceMesh& mesh, std::size_t samples = 6000,
                                          double angle_cosine = 1 - 1e-6, double offset_fraction = 1e-6);
/// Both meshes in one, the second's vertex indices shifted past the first's (no vertex shared).
SurfaceMesh bothMeshes(const SurfaceMesh& a, const SurfaceMesh& b);
/// Pairs of faces that cross or touch although they share no vertex position (triangulateFace's
/// triangles against each other, exact predicates); zero for a surface without self-intersections.
/// analyseTopology counts edges by vertex index and so cannot see two faces passing through each
/// other. The assemblers keep solids touching at an edge or corner apart by duplicating vertices
/// there; faces that meet only at such shared positions do not count.
std::size_t crossingFacePairs(const SurfaceMesh& mesh);
/// Planar faces after merging edge-adjacent coplanar polygons.
std::size_t countPlanarRegions(const SurfaceMesh& mesh);
/// The plane x[axis] = at with outward normal sign * e_axis, and `count` points spread at random
/// over the box [lo, hi]'s cross-section there.
PlanarPrimitive coveredAxisPlane(int axis, double at, double sign, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                 int count, std::mt19937& random);
/// The six planes of the unit cube and `inner` planes per axis at random offsets, each with 150
/// points over the whole cube's cross-section: the floors and walls of a building, a cell complex
/// of (inner + 1)^3 cells and more.
std::vector<PlanarPrimitive> latticeOfCoveredPlanes(int inner, unsigned seed);
/// primitivesOf(mesh, samples) with every plane and point normal facing into the solid, as a
/// scanner inside a room gives them.
std::vector<PlanarPrimitive> primitivesFacingInwards(const SurfaceMesh& mesh, std::size_t samples = 6000);

}  // namespace paco::test
