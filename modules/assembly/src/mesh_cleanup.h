#pragma once
// Clean-up of assembled polygon meshes, shared by the backends (no CGAL here).
#include <paco/common/surface_mesh.h>

namespace paco::detail {

/// Inserts every vertex that lies on a face edge (within `tolerance`) into that edge, so that
/// neighbouring faces cut differently share their corners: no T-junctions.
void insertTJunctionVertices(SurfaceMesh& mesh, double tolerance);

/// Makes the faces of each edge-connected component traverse shared edges in opposite directions.
void orientConsistently(SurfaceMesh& mesh);

/// Everything after the backend, for an oriented, welded mesh: merges edge-connected coplanar
/// faces into one polygon per planar region (when its boundary is one simple loop), drops
/// collinear vertices left on straight edges, and separates sheets that touch along an edge or
/// at a vertex by duplicating the shared vertices (so the result is manifold).
void cleanUpPolygonMesh(SurfaceMesh& mesh);

/// What PolygonalAssembler does to every backend's raw output: welds (1e-7), orients the faces
/// consistently and outward, cleans up (cleanUpPolygonMesh). Returns the final topology.
MeshTopology finishAssembledMesh(SurfaceMesh& mesh);

}  // namespace paco::detail
