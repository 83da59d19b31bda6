#pragma once
// Usage:
//   paco::data::GroundTruth gt = paco::data::extractGroundTruth(mesh);  // throws if not plane-only/closed
//   for (const auto& face : gt.faces) std::cout << face.plane.normal.transpose() << " " << face.area;
//   paco::data::GtPoints pts = paco::data::sampleGroundTruth(gt, 8192, seed);
#include <paco/common/plane.h>
#include <paco/common/surface_mesh.h>

#include <cstdint>
#include <string>
#include <vector>

namespace paco::data {

/// Tolerances of the coplanar grouping and of the plane-only test. Lengths are fractions of the
/// mesh's bounding-box diagonal, so the result does not depend on the mesh's units.
struct GroundTruthOptions {
  /// Two triangles are coplanar when their normals differ by less than this (degrees, > 0; 0.06).
  double normal_tolerance_deg = 0.06;
  /// ... and every vertex lies within this distance of the group's plane (fraction of diagonal; 5e-4).
  double offset_tolerance = 5e-4;
  /// Two different planes sharing an edge at less than this dihedral turn (degrees) form a
  /// "shallow crease", the signature of a tessellated curved surface (default 20).
  double shallow_crease_deg = 20.0;
  /// Reject the mesh when at least this many planes have shallow creases with two or more other
  /// planes (default 3): the inner facets of a tessellated strip do, a single shallow slope or
  /// chamfer between two faces does not.
  int max_shallow_crease_planes = 3;
  /// Reject the mesh when it has more planes than this (default 200).
  int max_planes = 200;
  /// Reject meshes with boundary or non-manifold edges, or inconsistent orientation (default true).
  bool require_closed = true;
};

/// One planar face of the ground truth: every triangle of the mesh on one plane (n, d). Disjoint
/// coplanar regions with the same orientation are ONE face (one plane per distinct (n, d)).
struct PlanarFace {
  paco::Plane plane;                     ///< outward normal, fitted to the face's triangles
  double area = 0.0;                     ///< total area of its triangles (mesh units squared)
  std::vector<std::uint32_t> triangles;  ///< indices into GroundTruth::mesh.faces
};

/// The ground truth of a plane-only mesh: its triangles grouped into planar faces.
struct GroundTruth {
  SurfaceMesh mesh;                      ///< the input, triangulated (paco::triangulated)
  std::vector<PlanarFace> faces;         ///< sorted by decreasing area
  std::vector<int> triangle_face;        ///< per triangle: index into faces, -1 for a degenerate one
  double diagonal = 0.0;                 ///< bounding-box diagonal of the mesh
};

/// Groups the coplanar triangles of a closed plane-only mesh into planar faces. Throws
/// InvalidInputError naming the reason when the mesh is empty, not closed / not consistently
/// oriented (with require_closed), has inward orientation (negative volume), or is not plane-only
/// (tessellated curved surfaces, too many planes).
GroundTruth extractGroundTruth(const SurfaceMesh& mesh, const GroundTruthOptions& options = {});

/// Points on the ground truth surface with their plane label and plane normal.
struct GtPoints {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;   ///< the (outward) normal of the point's plane
  std::vector<int> labels;                ///< index into GroundTruth::faces
};

/// `count` points uniform by area (paco::sampleSurface), deterministic for a seed.
GtPoints sampleGroundTruth(const GroundTruth& gt, std::size_t count, std::uint64_t seed);

}  // namespace paco::data
