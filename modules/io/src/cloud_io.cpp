#include <paco/io/cloud_io.h>
#include <paco/io/npy_io.h>
#include <paco/io/vertex_groups_io.h>

#include "cloud_formats.h"
#include "io_detail.h"
#include "ply.h"

#include <paco/common/error.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <iostream>

namespace paco::io {

namespace detail {

LabelledCloud readPlyCloud(const std::string& path, const std::string& bytes) {
  const PlyFile ply = readPly(path, bytes);
  const PlyElement* vertex = ply.element("vertex");
  if (!vertex) fail(path, "malformed: PLY file has no 'vertex' element");
  const int ix = vertex->find({"x"}), iy = vertex->find({"y"}), iz = vertex->find({"z"});
  if (ix < 0 || iy < 0 || iz < 0) fail(path, "malformed: PLY vertices have no x, y, z properties");
  int inx = vertex->find({"nx", "normal_x"}), iny = vertex->find({"ny", "normal_y"}),
      inz = vertex->find({"nz", "normal_z"});
  const bool has_normals = inx >= 0 && iny >= 0 && inz >= 0;
  const int ilabel = vertex->find({"label", "plane_id", "segment_index"});
  for (int i : {ix, iy, iz, inx, iny, inz, ilabel})
    if (i >= 0 && vertex->properties[static_cast<std::size_t>(i)].is_list)
      fail(path, "malformed: PLY vertex property '" + vertex->properties[static_cast<std::size_t>(i)].name +
                     "' is a list");
  LabelledCloud cloud;
  cloud.has_normals = has_normals;
  const std::size_t n = vertex->count;
  cloud.points.resize(n);
  if (ilabel >= 0) cloud.labels.resize(n);
  cloud.coordinate_offset = storePositionsNearZero(cloud.points, [&](std::size_t p) {
    return Eigen::Vector3d(vertex->scalars[ix][p], vertex->scalars[iy][p], vertex->scalars[iz][p]);
  });
  for (std::size_t p = 0; p < n; ++p) {
    pcl::PointNormal& q = cloud.points[p];
    q.normal_x = has_normals ? static_cast<float>(vertex->scalars[inx][p]) : 0.0f;
    q.normal_y = has_normals ? static_cast<float>(vertex->scalars[iny][p]) : 0.0f;
    q.normal_z = has_normals ? static_cast<float>(vertex->scalars[inz][p]) : 0.0f;
    q.curvature = 0.0f;
    if (ilabel >= 0) cloud.labels[p] = labelFromValue(path, vertex->scalars[ilabel][p], p);
  }
  return cloud;
}

std::string writePlyCloud(const LabelledCloud& cloud, bool ascii) {
  const std::size_t n = cloud.points.size();
  const bool labels = cloud.hasLabels();
  const Eigen::Vector3d& offset = cloud.coordinate_offset;
  const bool offset_positions = !offset.isZero(0.0);
  std::string out = "ply\nformat ";
  out += ascii ? "ascii 1.0\n" : "binary_little_endian 1.0\n";
  out += "comment written by paco\nelement vertex " + std::to_string(n) + "\n";
  out += offset_positions ? "property double x\nproperty double y\nproperty double z\n"
                          : "property float x\nproperty float y\nproperty float z\n";
  if (cloud.has_normals) out += "property float nx\nproperty float ny\nproperty float nz\n";
  if (labels) out += "property int label\n";
  out += "end_header\n";
  for (std::size_t i = 0; i < n; ++i) {
    const pcl::PointNormal& p = cloud.points[i];
    const float v[6] = {p.x, p.y, p.z, p.normal_x, p.normal_y, p.normal_z};
    const std::size_t count = cloud.has_normals ? 6 : 3;
    if (ascii) {
      for (std::size_t k = 0; k < count; ++k) {
        if (k) out += ' ';
        appendCoordinate(out, v[k], k < 3 ? offset[static_cast<Eigen::Index>(k)] : 0.0);
      }
      if (labels) out += ' ' + std::to_string(cloud.labels[i]);
      out += '\n';
    } else {
      for (std::size_t k = 0; k < count; ++k) {
        if (k < 3 && offset_positions) appendBinary(out, unshift(v[k], offset[static_cast<Eigen::Index>(k)]));
        else appendBinary(out, v[k]);
      }
      if (labels) appendBinary(out, static_cast<std::int32_t>(cloud.labels[i]));
    }
  }
  return out;
}

LabelledCloud readXyz(const std::string& path, const std::string& bytes) {
  LabelledCloud cloud;
  TextCursor text(bytes, utf8BomLength(bytes));
  std::string_view line;
  std::vector<std::string_view> tok;
  std::vector<double> positions;  // x y z of each point
  std::size_t columns = 0;
  for (std::size_t line_number = 1; text.nextLine(line); ++line_number) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    if (!splitValues(line, tok))
      fail(path, "malformed: line " + std::to_string(line_number) +
                     " has an empty value (two commas in a row, or a comma at the start or end of the line)");
    if (tok.empty()) continue;
    if (columns == 0) {
      if (tok.size() != 3 && tok.size() != 6)
        fail(path, "malformed: line " + std::to_string(line_number) + " has " + std::to_string(tok.size()) +
                       " values; XYZ lines hold \"x y z\" or \"x y z nx ny nz\", separated by blanks or commas");
      columns = tok.size();
      cloud.has_normals = columns == 6;
    } else if (tok.size() != columns) {
      fail(path, "malformed: line " + std::to_string(line_number) + " has " + std::to_string(tok.size()) +
                     " values, earlier lines have " + std::to_string(columns));
    }
    double v[6] = {0, 0, 0, 0, 0, 0};
    for (std::size_t k = 0; k < columns; ++k)
      if (!parseDouble(tok[k], v[k]))
        fail(path, "malformed: '" + std::string(tok[k]) + "' on line " + std::to_string(line_number) +
                       " is not a number");
    // Positions stay in double until the offset is known; normals go to the points now.
    positions.insert(positions.end(), v, v + 3);
    pcl::PointNormal q;
    q.normal_x = static_cast<float>(v[3]);
    q.normal_y = static_cast<float>(v[4]);
    q.normal_z = static_cast<float>(v[5]);
    q.curvature = 0.0f;
    cloud.points.push_back(q);
  }
  cloud.coordinate_offset = storePositionsNearZero(
      cloud.points, [&](std::size_t p) { return Eigen::Vector3d(positions[3 * p], positions[3 * p + 1], positions[3 * p + 2]); });
  return cloud;
}

std::string writeXyz(const LabelledCloud& cloud) {
  std::string out;
  out.reserve(cloud.points.size() * (cloud.has_normals ? 80 : 40));
  const Eigen::Vector3d& offset = cloud.coordinate_offset;
  for (const auto& p : cloud.points) {
    const float v[6] = {p.x, p.y, p.z, p.normal_x, p.normal_y, p.normal_z};
    const std::size_t count = cloud.has_normals ? 6 : 3;
    for (std::size_t k = 0; k < count; ++k) {
      if (k) out += ' ';
      appendCoordinate(out, v[k], k < 3 ? offset[static_cast<Eigen::Index>(k)] : 0.0);
    }
    out += '\n';
  }
  return out;
}

}  // namespace detail

namespace {

using detail::fail;

LabelledCloud cloudFromNpy(const std::string& path, const NpyArray& a) {
  if (a.cols != 3 && a.cols != 6 && a.cols != 7)
    fail(path, "malformed: array has " + std::to_string(a.cols) +
                   " columns; a cloud needs 3 (x y z), 6 (+ normals) or 7 (+ plane_id)");
  LabelledCloud cloud;
  cloud.points.resize(a.rows);
  cloud.has_normals = a.cols >= 6;
  cloud.coordinate_offset = detail::storePositionsNearZero(
      cloud.points, [&](std::size_t r) { return Eigen::Vector3d(a.at(r, 0), a.at(r, 1), a.at(r, 2)); });
  for (std::size_t r = 0; r < a.rows; ++r) {
    pcl::PointNormal& q = cloud.points[r];
    q.normal_x = cloud.has_normals ? static_cast<float>(a.at(r, 3)) : 0.0f;
    q.normal_y = cloud.has_normals ? static_cast<float>(a.at(r, 4)) : 0.0f;
    q.normal_z = cloud.has_normals ? static_cast<float>(a.at(r, 5)) : 0.0f;
    q.curvature = 0.0f;
  }
  if (a.cols == 7) {
    // Zero normals (written for a labelled cloud without normals) read back as has_normals false
    // in loadCloud, as in every format.
    cloud.labels.resize(a.rows);
    for (std::size_t r = 0; r < a.rows; ++r) cloud.labels[r] = detail::labelFromValue(path, a.at(r, 6), r);
  }
  return cloud;
}

NpyArray npyFromCloud(const LabelledCloud& cloud) {
  NpyArray a;
  a.rows = cloud.points.size();
  // Labels need the 7-column layout; without normals those columns are written as zeros.
  a.cols = cloud.hasLabels() ? 7 : cloud.has_normals ? 6 : 3;
  a.data.assign(a.rows * a.cols, 0.0);
  for (std::size_t r = 0; r < a.rows; ++r) {
    const pcl::PointNormal& p = cloud.points[r];
    double* row = a.data.data() + r * a.cols;
    for (int k = 0; k < 3; ++k) row[k] = detail::unshift(p.data[k], cloud.coordinate_offset[k]);
    if (a.cols >= 6 && cloud.has_normals) {
      row[3] = p.normal_x; row[4] = p.normal_y; row[5] = p.normal_z;
    }
    if (a.cols == 7) row[6] = cloud.labels[r];
  }
  return a;
}

/// One group per label value (-1 is no group), each with the plane fitted to its points.
VertexGroups vertexGroupsFromCloud(const std::string& path, const LabelledCloud& cloud) {
  VertexGroups vg;
  vg.points = cloud.points;
  vg.has_normals = cloud.has_normals;
  vg.coordinate_offset = cloud.coordinate_offset;
  PlanarSegmentation& seg = vg.segmentation;
  seg.labels = cloud.hasLabels() ? cloud.labels : std::vector<int>(cloud.points.size(), -1);
  int max_label = -1;
  for (int l : seg.labels) {
    if (l < -1) fail(path, "cannot write label " + std::to_string(l) + " as a vertex group (labels are -1 or >= 0)");
    max_label = std::max(max_label, l);
  }
  // Label values become group indices; unused values would be empty groups, so renumber densely.
  std::vector<int> group_of(static_cast<std::size_t>(max_label + 1), -1);
  for (int& l : seg.labels) {
    if (l < 0) continue;
    int& g = group_of[static_cast<std::size_t>(l)];
    if (g < 0) {
      g = static_cast<int>(seg.segments.size());
      seg.segments.emplace_back();
    }
    l = g;
  }
  for (std::size_t i = 0; i < seg.labels.size(); ++i)
    if (seg.labels[i] >= 0) seg.segments[static_cast<std::size_t>(seg.labels[i])].indices.push_back(static_cast<int>(i));
  for (std::size_t g = 0; g < seg.segments.size(); ++g) {
    std::vector<Eigen::Vector3d> members;
    Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
    for (int i : seg.segments[g].indices) {
      const auto& p = cloud.points[static_cast<std::size_t>(i)];
      members.push_back(p.getVector3fMap().cast<double>());
      normal_sum += p.getNormalVector3fMap().cast<double>();
    }
    try {
      seg.planes.push_back(Plane::fit(members, cloud.has_normals ? normal_sum : Eigen::Vector3d::Zero()));
    } catch (const Error& e) {
      fail(path, "cannot write group " + std::to_string(g) + " as a plane: " + e.what());
    }
  }
  return vg;
}

LabelledCloud cloudFromVertexGroups(VertexGroups vg) {
  LabelledCloud cloud;
  cloud.points = std::move(vg.points);
  cloud.has_normals = vg.has_normals;
  cloud.coordinate_offset = vg.coordinate_offset;
  cloud.labels = std::move(vg.segmentation.labels);
  if (vg.segmentation.segments.empty()) cloud.labels.clear();
  return cloud;
}

/// Rejects (or drops, with one warning) points with NaN/Inf coordinates. Normals do not count:
/// see treatNonFiniteNormalsAsMissing.
void applyNonFinitePolicy(const std::string& path, LabelledCloud& cloud, NonFinitePolicy policy) {
  const auto finite = [](const pcl::PointNormal& p) {
    return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
  };
  std::size_t bad = 0, first_bad = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i)
    if (!finite(cloud.points[i]) && bad++ == 0) first_bad = i;
  if (bad == 0) return;
  if (policy == NonFinitePolicy::Reject) {
    const auto& p = cloud.points[first_bad];
    fail(path, std::to_string(bad) + " of " + detail::plural(cloud.points.size(), "point") +
                   " have non-finite (NaN/Inf) coordinates, the first is point " + std::to_string(first_bad) +
                   " (" + detail::numberText(detail::unshift(p.x, cloud.coordinate_offset.x())) + ", " +
                   detail::numberText(detail::unshift(p.y, cloud.coordinate_offset.y())) + ", " +
                   detail::numberText(detail::unshift(p.z, cloud.coordinate_offset.z())) +
                   "); drop them with NonFinitePolicy::Drop (the tools' --drop-non-finite)");
  }
  std::size_t kept = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (!finite(cloud.points[i])) continue;
    cloud.points[kept] = cloud.points[i];
    if (cloud.hasLabels()) cloud.labels[kept] = cloud.labels[i];
    ++kept;
  }
  cloud.points.resize(kept);
  if (cloud.hasLabels()) cloud.labels.resize(kept);
  std::cerr << "warning: '" << path << "': dropped " << bad << " of " << (kept + bad)
            << " points with non-finite (NaN/Inf) coordinates" << std::endl;
}

/// A NaN/Inf normal is a normal the writer could not compute (PCL writes NaN there), not a bad
/// point: it becomes the zero normal that means "estimate this one" downstream. A cloud left
/// without any non-zero normal reports has_normals false, so that callers estimate them all.
void treatNonFiniteNormalsAsMissing(LabelledCloud& cloud) {
  if (!cloud.has_normals) return;
  bool any_normal = false;
  for (auto& p : cloud.points) {
    if (!std::isfinite(p.normal_x) || !std::isfinite(p.normal_y) || !std::isfinite(p.normal_z))
      p.normal_x = p.normal_y = p.normal_z = 0.0f;
    any_normal = any_normal || p.normal_x != 0.0f || p.normal_y != 0.0f || p.normal_z != 0.0f;
  }
  cloud.has_normals = any_normal;
}

}  // namespace

std::string extensionOf(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext;
}

LabelledCloud loadCloud(const std::string& path, const CloudReadOptions& options) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) fail(path, "is a folder, not a point cloud file");
  const std::string ext = extensionOf(path);
  LabelledCloud cloud;
  if (ext == ".npy") {
    cloud = cloudFromNpy(path, loadNpy(path));
  } else if (ext == ".vg" || ext == ".bvg") {
    cloud = cloudFromVertexGroups(loadVertexGroups(path));
  } else if (ext == ".pcd" || ext == ".ply" || ext == ".xyz") {
    const std::string bytes = detail::readWholeFile(path);
    if (ext == ".pcd") cloud = detail::readPcd(path, bytes);
    else if (ext == ".ply") cloud = detail::readPlyCloud(path, bytes);
    else cloud = detail::readXyz(path, bytes);
  } else {
    fail(path, "unknown point cloud extension '" + ext + "'; use .pcd, .ply, .xyz, .npy, .vg or .bvg");
  }
  if (!options.offset_far_coordinates && !cloud.coordinate_offset.isZero(0.0)) {
    for (auto& p : cloud.points)
      p.getVector3fMap() = (p.getVector3fMap().cast<double>() + cloud.coordinate_offset).cast<float>();
    cloud.coordinate_offset.setZero();
  }
  applyNonFinitePolicy(path, cloud, options.non_finite);
  treatNonFiniteNormalsAsMissing(cloud);
  if (cloud.points.empty()) fail(path, "holds no points");
  cloud.points.width = static_cast<std::uint32_t>(cloud.points.size());
  cloud.points.height = 1;
  cloud.points.is_dense = true;
  return cloud;
}

void saveCloud(const std::string& path, const LabelledCloud& cloud, const CloudWriteOptions& options) {
  if (cloud.hasLabels() && cloud.labels.size() != cloud.points.size())
    throw IoError("saveCloud('" + path + "'): " + std::to_string(cloud.labels.size()) + " labels for " +
                  detail::plural(cloud.points.size(), "point"));
  if (cloud.hasColours() && cloud.colours.size() != cloud.points.size())
    throw IoError("saveCloud('" + path + "'): " + std::to_string(cloud.colours.size()) + " colours for " +
                  detail::plural(cloud.points.size(), "point"));
  const std::string ext = extensionOf(path);
  if (ext == ".pcd") {
    detail::writeWholeFile(path, detail::writePcd(cloud, options.pcd_encoding));
  } else if (ext == ".ply") {
    detail::writeWholeFile(path, detail::writePlyCloud(cloud, options.ascii_ply));
  } else if (ext == ".xyz") {
    detail::writeWholeFile(path, detail::writeXyz(cloud));
  } else if (ext == ".npy") {
    saveNpy(path, npyFromCloud(cloud), /*float64=*/!cloud.coordinate_offset.isZero(0.0));
  } else if (ext == ".vg" || ext == ".bvg") {
    saveVertexGroups(path, vertexGroupsFromCloud(path, cloud));
  } else {
    fail(path, "cannot write point clouds with extension '" + ext + "'; use .pcd, .ply, .xyz, .npy, .vg or .bvg");
  }
}

std::uint32_t primitiveColour(std::size_t i) {
  static const std::uint32_t palette[] = {0xe6194b, 0x3cb44b, 0xffe119, 0x4363d8, 0xf58231, 0x911eb4,
                                          0x46f0f0, 0xf032e6, 0xbcf60c, 0xfabebe, 0x008080, 0x9a6324};
  return palette[i % (sizeof(palette) / sizeof(palette[0]))];
}

LabelledCloud primitivesToCloud(const std::vector<PlanarPrimitive>& primitives, const Eigen::Vector3d& coordinate_offset) {
  LabelledCloud cloud;
  cloud.has_normals = true;
  cloud.coordinate_offset = coordinate_offset;
  for (std::size_t i = 0; i < primitives.size(); ++i)
    for (const auto& p : primitives[i].points) {
      cloud.points.push_back(p);
      cloud.labels.push_back(static_cast<int>(i));
      cloud.colours.push_back(primitiveColour(i));
    }
  return cloud;
}

}  // namespace paco::io
