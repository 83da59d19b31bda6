#pragma once
// Exact planar primitives of the generated test shapes (points sampled on each face plane), shared
// by the assembly tests.
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>

#include <cstddef>
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
/// Planar faces after merging edge-adjacent coplanar polygons.
std::size_t countPlanarRegions(const SurfaceMesh& mesh);

}  // namespace paco::test
