#pragma once
// PolyFit / Easy3D "vertex group" files: a point cloud plus planar groups of point indices, each
// with its plane. This is how paco's primitives reach PolyFit, Easy3D and abspy, and come back.
// Usage:
//   auto vg = paco::io::toVertexGroups(primitives);
//   paco::io::saveVertexGroups("planes.vg", vg);            // .vg ascii, .bvg binary
//   auto back = paco::io::toPrimitives(paco::io::loadVertexGroups("planes.bvg"));
#include <paco/common/primitive.h>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <string>
#include <vector>

namespace paco::io {

struct VertexGroups {
  pcl::PointCloud<pcl::PointNormal> points;
  bool has_normals = false;
  /// Planes and the point indices of each group; labels mark points of no group with -1.
  PlanarSegmentation segmentation;
  /// Per group: its label text (PolyFit writes "unknown") and colour (r, g, b in [0, 1]).
  std::vector<std::string> group_labels;
  std::vector<Eigen::Vector3f> group_colors;
  /// Per group: the confidence of a completed primitive (1 for observed segments). Stored in the
  /// group label as "confidence=<value>" so that other readers still open the file.
  std::vector<float> confidences;
  /// The file's coordinates are points[i] + coordinate_offset, and its planes are the planes
  /// moved by it; as LabelledCloud::coordinate_offset (zero near the origin).
  Eigen::Vector3d coordinate_offset = Eigen::Vector3d::Zero();
};

/// Reads .vg (ascii) or .bvg (binary) by extension. A group whose stored plane is missing or zero
/// (Easy3D writes zeros) gets the plane fitted to its points; child groups are read and skipped;
/// a point in two groups is labelled with the first. Throws paco::IoError for a missing, empty,
/// truncated or malformed file (bad counts, indices out of range, non-finite values, non-plane
/// groups). Coordinates far from 0 for the cloud's size are moved to coordinate_offset.
VertexGroups loadVertexGroups(const std::string& path);
/// Writes .vg (ascii) or .bvg (binary) by extension, in the layout PolyFit and Easy3D read. Each
/// group's label is "confidence=<v>" when `confidences` is filled, else its group_labels entry
/// (blanks become '_'), else "unknown"; colours default to a fixed palette. Point colours and
/// child groups are not written. Points and planes are moved back by coordinate_offset: .vg
/// writes them as double-precision text, .bvg as float32 (the format's only type, so far
/// coordinates lose precision there). Throws paco::IoError for an unwritable path or groups that
/// disagree with the points (index out of range, sizes that differ).
void saveVertexGroups(const std::string& path, const VertexGroups& groups);

/// One group per primitive; the points of all primitives are concatenated. Primitives made from
/// a cloud read with a coordinate offset pass it on, so that the file gets the input's coordinates.
VertexGroups toVertexGroups(const std::vector<PlanarPrimitive>& primitives,
                            const Eigen::Vector3d& coordinate_offset = Eigen::Vector3d::Zero());
/// One primitive per group, with the group's plane (the stored one, or a fit if it is missing).
std::vector<PlanarPrimitive> toPrimitives(const VertexGroups& groups);

}  // namespace paco::io
