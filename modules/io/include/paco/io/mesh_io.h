#pragma once
// Usage:
//   paco::SurfaceMesh mesh = paco::io::loadMesh("part.stl");   // OBJ, OFF, PLY, STL by extension
//   paco::io::saveMesh("part.obj", mesh);                      // OBJ, OFF, PLY
#include <paco/common/surface_mesh.h>

#include <pcl/PolygonMesh.h>

#include <string>

namespace paco::io {

/// Reads a polygon mesh by extension: .obj, .off, .ply (ascii/binary), .stl (ascii/binary).
/// Polygon faces are kept as they are (not triangulated); STL triangles share welded vertices
/// (exactly equal coordinates). Throws paco::IoError for a missing, empty, truncated or malformed
/// file, one without faces (unless allow_no_faces), or with non-finite vertices.
SurfaceMesh loadMesh(const std::string& path, bool allow_no_faces = false);

/// Writes a polygon mesh by extension: .obj, .off, .ply (binary little-endian, double
/// coordinates), .stl (binary float32, faces triangulated by paco::triangulated). Text formats write the shortest
/// text that reads back to the same double. Throws paco::IoError for an unwritable path, an
/// unknown extension, or faces with fewer than 3 vertices or indices out of range.
void saveMesh(const std::string& path, const SurfaceMesh& mesh);

/// The same for pcl::PolygonMesh, through paco::SurfaceMesh.
pcl::PolygonMesh loadPolygonMesh(const std::string& path);
void savePolygonMesh(const std::string& path, const pcl::PolygonMesh& mesh);

}  // namespace paco::io
