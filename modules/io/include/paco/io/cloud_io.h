#pragma once
// Usage:
//   paco::io::LabelledCloud scan = paco::io::loadCloud("scan.ply");      // format by extension
//   if (!scan.has_normals) ... estimate them ...
//   paco::io::saveCloud("labelled.pcd", scan);                           // PCD with a label field
// A scan in national-grid coordinates (e.g. x 85123.45, y 446012.30) is read with the far part
// of its coordinates moved to scan.coordinate_offset, so that the float32 points keep their
// precision; saveCloud adds it back.
#include <paco/common/primitive.h>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <string>
#include <vector>

namespace paco::io {

/// A point cloud as read from a file: positions, optional normals, optional per-point labels.
struct LabelledCloud {
  /// A point's normal is 0 where the file gives none for it (a NaN/Inf normal reads as 0, the
  /// zero normal that the segmenter estimates); all are 0 when has_normals is false.
  pcl::PointCloud<pcl::PointNormal> points;
  bool has_normals = false;  ///< false too when the file's normals are all 0 or NaN/Inf
  std::vector<int> labels;  ///< one per point (-1 = none), or empty for no labels
  /// One packed 0xRRGGBB colour per point, or empty. Written to PCD only (field "rgb", as PCL's
  /// PointXYZRGB); readers leave it empty.
  std::vector<std::uint32_t> colours;
  /// The file's coordinates are points[i] + coordinate_offset. Readers set it when float32 would
  /// round the file's coordinates by more than 1e-5 of the cloud's size (coordinates far from 0
  /// for the cloud's size, as in UTM or national grids): it is then the cloud's centre rounded to
  /// a tidy number, and points hold small coordinates around it. Writers add it back (in double
  /// precision in .ply, .xyz, .npy and .vg; see saveCloud). Zero for clouds near the origin.
  Eigen::Vector3d coordinate_offset = Eigen::Vector3d::Zero();
  bool hasLabels() const { return !labels.empty(); }
  bool hasColours() const { return !colours.empty(); }
};

/// What to do with points whose coordinates are NaN or Inf. (A NaN/Inf normal is not a bad point:
/// it reads as a missing normal, 0.)
enum class NonFinitePolicy {
  Reject,  ///< throw IoError naming the file and the first bad point (default)
  Drop,    ///< drop them and print one warning to stderr with the count
};

struct CloudReadOptions {
  NonFinitePolicy non_finite = NonFinitePolicy::Reject;
  /// Move far coordinates to LabelledCloud::coordinate_offset (see there). false stores the
  /// file's coordinates in the points as they are, rounded to float32, with a zero offset.
  bool offset_far_coordinates = true;
};

enum class PcdEncoding { Ascii, Binary, BinaryCompressed };

struct CloudWriteOptions {
  PcdEncoding pcd_encoding = PcdEncoding::Binary;  ///< for .pcd only
  bool ascii_ply = false;                          ///< for .ply: ascii instead of binary
};

/// Reads a cloud, choosing the reader by extension (case-insensitive):
///   .pcd  PCL PCD (ascii, binary, binary_compressed); fields x y z [normal_x normal_y normal_z] [label]
///   .ply  PLY vertices (ascii or binary); properties x y z [nx ny nz] [label|plane_id|segment_index]
///   .xyz  text, one point a line: "x y z" or "x y z nx ny nz", separated by blanks or commas
///         ('#' starts a comment)
///   .npy  the authors' (N,7) float32/float64 array: x y z nx ny nz plane_id (N,3 and N,6 too)
///   .vg/.bvg  PolyFit vertex groups (points, normals, group labels); NaN/Inf values of any kind
///         fail there (loadVertexGroups)
/// A UTF-8 byte-order mark before an .xyz file or a .ply/.pcd header is skipped.
/// Throws paco::IoError for a missing, empty, truncated or malformed file, naming file and problem.
LabelledCloud loadCloud(const std::string& path, const CloudReadOptions& options = {});

/// Writes a cloud by extension (.pcd, .ply, .xyz, .npy, .vg, .bvg). Labels are written when present
/// (PCD field "label", PLY property "label", .npy column 7 with zero normals when there are none;
/// .vg/.bvg: one group per label with its fitted plane). Positions are written as
/// points + coordinate_offset. With a zero offset binary formats store float32 and text formats
/// the shortest text that reads back to the same float (at most 9 digits); with an offset, .ply
/// and .npy store double positions, .xyz and .vg double-precision text. .pcd stays float32, the
/// type PCL's point types and pcl_viewer read (a double x loads as 0 into pcl::PointXYZ), and so
/// does .bvg, the format's only type: far coordinates lose precision in those two; write .ply,
/// .xyz or .npy to keep it (PCL's loadPLYFile reads double x y z into its float point types as
/// zeros, as it does for PCD; loadCloud, CloudCompare and Open3D read them). Throws paco::IoError on
/// failure (unwritable path, unknown extension, labels.size() != points.size()).
void saveCloud(const std::string& path, const LabelledCloud& cloud, const CloudWriteOptions& options = {});

/// The points of all primitives as one cloud with normals, labelled by primitive index and
/// coloured by primitiveColour(), e.g. to look at completed primitives in pcl_viewer. Primitives
/// made from a cloud read with a coordinate offset pass it on (LabelledCloud::coordinate_offset).
LabelledCloud primitivesToCloud(const std::vector<PlanarPrimitive>& primitives,
                                const Eigen::Vector3d& coordinate_offset = Eigen::Vector3d::Zero());
/// A colour for primitive i, packed 0xRRGGBB, from a palette of 12 well-separated colours.
std::uint32_t primitiveColour(std::size_t i);

/// Lower-case extension with the dot (".pcd"), or "" when there is none.
std::string extensionOf(const std::string& path);

}  // namespace paco::io
