#pragma once
// Usage:
//   paco::SurfaceMesh mesh;                       // vertices + polygon faces (any valence)
//   mesh.vertices = {...}; mesh.faces = {{0, 1, 2}, ...};
//   paco::MeshTopology t = paco::analyseTopology(mesh);
//   if (t.isClosedManifold()) std::cout << paco::signedVolume(mesh);
//   pcl::PolygonMesh pm = paco::toPolygonMesh(mesh);
#include <Eigen/Core>
#include <pcl/PolygonMesh.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace paco {

/// A polygon mesh with double-precision vertices; faces are vertex-index loops (counter-clockwise
/// seen from outside for an outward-oriented solid). The plain type used between paco stages;
/// convert to pcl::PolygonMesh at the API boundary.
struct SurfaceMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::vector<std::uint32_t>> faces;

  bool empty() const { return faces.empty(); }
  std::size_t numTriangles() const;  ///< sum of (valence - 2): at most the triangles of triangulateFace
  /// Throws InvalidInputError for indices out of range, faces with < 3 vertices or non-finite
  /// vertices. `what` names the mesh in the message.
  void validate(const std::string& what = "mesh") const;
};

/// What analyseTopology finds. A closed, manifold, consistently oriented mesh is a valid solid.
struct MeshTopology {
  std::size_t boundary_edges = 0;       ///< edges used by one face only
  std::size_t non_manifold_edges = 0;   ///< edges used by more than two faces
  std::size_t inconsistent_edges = 0;   ///< edges whose two faces traverse them the same way
  std::size_t non_manifold_vertices = 0;///< vertices whose faces form more than one fan
  std::size_t components = 0;           ///< connected components of faces
  bool isClosed() const { return boundary_edges == 0 && non_manifold_edges == 0; }
  bool isManifold() const { return non_manifold_edges == 0 && non_manifold_vertices == 0; }
  bool isOriented() const { return inconsistent_edges == 0; }
  bool isClosedManifold() const { return isClosed() && isManifold() && isOriented(); }
  std::string describe() const;  ///< e.g. "closed, manifold, oriented, 1 component"
};

MeshTopology analyseTopology(const SurfaceMesh& mesh);

/// Merges vertices closer than `tolerance` (absolute units), drops faces that degenerate and
/// repeated consecutive indices. Returns the number of vertices removed.
std::size_t weldVertices(SurfaceMesh& mesh, double tolerance);

/// Sum of face areas (of their triangles, triangulateFace).
double surfaceArea(const SurfaceMesh& mesh);
/// Signed volume by the divergence theorem: positive for a closed mesh with outward faces.
double signedVolume(const SurfaceMesh& mesh);
/// Unit normal of a polygon by Newell's method (zero vector for a degenerate face).
Eigen::Vector3d faceNormal(const SurfaceMesh& mesh, std::size_t face);
/// Axis-aligned bounding box of the vertices.
void boundingBox(const SurfaceMesh& mesh, Eigen::Vector3d& min, Eigen::Vector3d& max);
/// Flips every face (reverses the vertex order).
void flipFaces(SurfaceMesh& mesh);
/// Lists the same surface in one order, whatever order it came in: vertices sorted by their
/// coordinates (x, then y, then z; -0 becomes 0), each face starting at its smallest vertex index
/// (its orientation kept), faces sorted. CGAL's Nef_polyhedron_3 lists a solid's vertices and
/// faces in an order that follows heap addresses, which differ from run to run; sorted, a
/// procedural part's seed gives the same bytes in every process.
void sortMeshCanonically(SurfaceMesh& mesh);
/// The triangles of one face, appended to `out`. A convex face is fanned from its first corner. A
/// non-convex one (an L-shaped top, a step's side; the assemblers merge a plane's faces into such
/// polygons) is cut by ear clipping in its plane, after its straight corners are dropped, so
/// that its triangles cover it exactly; a fan from a reflex corner would cover its notch too. A
/// self-intersecting loop, which runs out of ears, gets the rest as a fan.
void triangulateFace(const SurfaceMesh& mesh, std::size_t face, std::vector<std::vector<std::uint32_t>>& out);
/// Every face as triangles (triangulateFace).
SurfaceMesh triangulated(const SurfaceMesh& mesh);

/// Points sampled uniformly by area on a mesh, each with the index of its face and the face normal.
struct SurfaceSample {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;
  std::vector<std::uint32_t> faces;
};
/// `count` points uniformly by area, deterministic for a seed. Throws InvalidInputError when the
/// mesh has no area.
SurfaceSample sampleSurface(const SurfaceMesh& mesh, std::size_t count, std::uint64_t seed);

pcl::PolygonMesh toPolygonMesh(const SurfaceMesh& mesh);
/// Reads the x, y, z fields of the mesh cloud; throws InvalidInputError if they are missing.
SurfaceMesh fromPolygonMesh(const pcl::PolygonMesh& mesh);

}  // namespace paco
