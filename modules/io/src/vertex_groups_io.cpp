// PolyFit / Easy3D vertex groups. Layout (ascii .vg; .bvg holds the same items as int32 counts,
// float32 values and length-prefixed label bytes):
//   num_points: N            then N lines "x y z"
//   num_colors: 0 or N       then N lines "r g b" (in [0, 1])
//   num_normals: 0 or N      then N lines "nx ny nz"
//   num_groups: G            then G times:
//     group_type: 0 (plane)   num_group_parameters: 4   group_parameters: a b c d
//     group_label: <one word> group_color: r g b        group_num_point: M   then M indices
//     num_children: C         then C groups as above, without num_children
#include <paco/io/cloud_io.h>
#include <paco/io/vertex_groups_io.h>

#include "io_detail.h"

#include <paco/common/error.h>

#include <cctype>
#include <cmath>
#include <functional>

namespace paco::io {

namespace {

using detail::fail;

constexpr int kPlaneType = 0;
const char kConfidencePrefix[] = "confidence=";

/// Distinct, deterministic colours: hues spaced by the golden angle.
Eigen::Vector3f paletteColor(std::size_t i) {
  const double h = std::fmod(0.13 + 0.618033988749895 * static_cast<double>(i), 1.0) * 6.0;
  const double s = 0.65, v = 0.9;
  const int sector = static_cast<int>(h);
  const double f = h - sector, p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r = v, g = t, b = p;
  switch (sector) {
    case 1: r = q; g = v; b = p; break;
    case 2: r = p; g = v; b = t; break;
    case 3: r = p; g = q; b = v; break;
    case 4: r = t; g = p; b = v; break;
    case 5: r = v; g = p; b = q; break;
    default: break;
  }
  return {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b)};
}

float confidenceFromLabel(const std::string& label) {
  const std::size_t n = sizeof(kConfidencePrefix) - 1;
  if (label.compare(0, n, kConfidencePrefix) != 0) return 1.0f;
  double value = 1.0;
  if (!detail::parseDouble(std::string_view(label).substr(n), value) || !std::isfinite(value)) return 1.0f;
  return static_cast<float>(value);
}

/// One group as read from a file, before it becomes a segment.
struct RawGroup {
  int type = kPlaneType;
  std::vector<double> parameters;
  std::string label;
  Eigen::Vector3f color = Eigen::Vector3f::Zero();
  std::vector<std::int64_t> indices;
};

/// Reads the items of a .vg (text) or .bvg (binary) file through one interface.
class VgSource {
 public:
  virtual ~VgSource() = default;
  virtual std::int64_t count(const char* key) = 0;
  virtual double value(const char* what) = 0;
  virtual std::int64_t index(const char* what) = 0;
  virtual std::string label() = 0;
  virtual void key(const char* name) = 0;
};

class VgText : public VgSource {
 public:
  VgText(const std::string& path, const std::string& bytes) : path_(path), text_(bytes) {}
  /// A bad last token may just be cut short: then the file is truncated, not malformed.
  [[noreturn]] void malformed(const std::string& problem, const char* what) {
    if (text_.atEnd()) fail(path_, std::string("truncated: file ends inside ") + what);
    fail(path_, "malformed: " + problem);
  }
  void key(const char* name) override {
    std::string_view token = next(name);
    std::string expected = std::string(name) + ":";
    // PolyFit writes "group_num_point:", some writers "group_num_points:".
    if (token != expected && !(std::string(name) == "group_num_point" && token == "group_num_points:"))
      malformed("expected '" + expected + "' on line " + std::to_string(text_.line()) + ", found '" +
                    std::string(token).substr(0, 30) + "'", name);
  }
  std::int64_t count(const char* key_name) override {
    key(key_name);
    std::string_view token = next(key_name);
    std::int64_t v = 0;
    if (!detail::parseInt64(token, v) || v < 0)
      malformed("'" + std::string(token) + "' after '" + key_name + ":' on line " + std::to_string(text_.line()) +
                    " is not a count", key_name);
    return v;
  }
  double value(const char* what) override {
    std::string_view token = next(what);
    double v = 0;
    if (!detail::parseDouble(token, v))
      malformed("'" + std::string(token).substr(0, 30) + "' (" + what + ", line " + std::to_string(text_.line()) +
                    ") is not a number", what);
    return v;
  }
  std::int64_t index(const char* what) override {
    std::string_view token = next(what);
    std::int64_t v = 0;
    if (!detail::parseInt64(token, v))
      malformed("'" + std::string(token).substr(0, 30) + "' (" + what + ", line " + std::to_string(text_.line()) +
                    ") is not an integer", what);
    return v;
  }
  std::string label() override { return std::string(next("group label")); }

 private:
  std::string_view next(const char* what) {
    std::string_view token;
    if (!text_.nextToken(token)) fail(path_, std::string("truncated: file ends while reading ") + what);
    return token;
  }
  const std::string& path_;
  detail::TextCursor text_;
};

class VgBinary : public VgSource {
 public:
  VgBinary(const std::string& path, const std::string& bytes) : path_(path), in_(bytes) {}
  void key(const char*) override {}
  std::int64_t count(const char* key_name) override {
    need(4, key_name);
    const std::int32_t v = in_.read<std::int32_t>();
    if (v < 0) fail(path_, std::string("malformed: negative ") + key_name + " " + std::to_string(v));
    return v;
  }
  double value(const char* what) override {
    need(4, what);
    return in_.read<float>();
  }
  std::int64_t index(const char* what) override {
    need(4, what);
    return in_.read<std::int32_t>();
  }
  std::string label() override {
    const std::int64_t n = count("label length");
    need(static_cast<std::size_t>(n), "group label");
    std::string text(in_.here(), static_cast<std::size_t>(n));
    in_.skip(static_cast<std::size_t>(n));
    return text;
  }
  std::size_t remaining() const { return in_.remaining(); }

 private:
  void need(std::size_t n, const char* what) {
    if (in_.remaining() < n) fail(path_, std::string("truncated: file ends while reading ") + what);
  }
  const std::string& path_;
  detail::ByteCursor in_;
};

RawGroup readGroup(const std::string& path, VgSource& in, std::size_t num_points, const std::string& name) {
  RawGroup g;
  g.type = static_cast<int>(in.count("group_type"));
  const std::int64_t num_parameters = in.count("num_group_parameters");
  if (num_parameters > 64) fail(path, "malformed: " + name + " has " + std::to_string(num_parameters) + " parameters");
  in.key("group_parameters");
  for (std::int64_t k = 0; k < num_parameters; ++k) g.parameters.push_back(in.value("group parameters"));
  in.key("group_label");
  g.label = in.label();
  in.key("group_color");
  for (int k = 0; k < 3; ++k) g.color[k] = static_cast<float>(in.value("group colour"));
  if (g.color.maxCoeff() > 1.0f) g.color /= 255.0f;  // some writers use 0..255, as PolyFit accepts
  const std::int64_t n = in.count("group_num_point");
  if (static_cast<std::size_t>(n) > num_points)
    fail(path, "malformed: " + name + " has " + std::to_string(n) + " points, the file " +
                   detail::plural(num_points, "point"));
  g.indices.reserve(static_cast<std::size_t>(n));
  for (std::int64_t k = 0; k < n; ++k) g.indices.push_back(in.index("group point indices"));
  return g;
}

}  // namespace

VertexGroups loadVertexGroups(const std::string& path) {
  const std::string ext = extensionOf(path);
  if (ext != ".vg" && ext != ".bvg") fail(path, "unknown vertex group extension '" + ext + "'; use .vg or .bvg");
  const std::string bytes = detail::readWholeFile(path);
  const bool binary = ext == ".bvg";
  VgText text(path, bytes);
  VgBinary bin(path, bytes);
  VgSource& in = binary ? static_cast<VgSource&>(bin) : static_cast<VgSource&>(text);

  VertexGroups vg;
  const std::int64_t n = in.count("num_points");
  // Each point takes at least 6 bytes in text and 12 in binary: bound the count before allocating.
  if (static_cast<std::size_t>(n) > bytes.size() / (binary ? 12 : 6))
    fail(path, "truncated: header says " + detail::plural(static_cast<std::size_t>(n), "point") +
                   ", the file is too short for them (" + std::to_string(bytes.size()) + " bytes)");
  const auto num_points = static_cast<std::size_t>(n);
  vg.points.resize(num_points);
  const auto readVectors = [&](const char* what, auto&& store) {
    for (std::size_t i = 0; i < num_points; ++i) {
      double v[3];
      for (int k = 0; k < 3; ++k) {
        v[k] = in.value(what);
        if (!std::isfinite(v[k]))
          fail(path, std::string("point ") + std::to_string(i) + " has non-finite (NaN/Inf) " + what);
      }
      store(i, v);
    }
  };
  // Positions stay in double until the coordinate offset is known.
  std::vector<Eigen::Vector3d> positions(num_points);
  readVectors("coordinates", [&](std::size_t i, const double* v) { positions[i] = Eigen::Vector3d(v[0], v[1], v[2]); });
  vg.coordinate_offset = detail::storePositionsNearZero(vg.points, [&](std::size_t i) { return positions[i]; });
  positions = {};
  for (auto& p : vg.points) {
    p.normal_x = p.normal_y = p.normal_z = 0.0f;
    p.curvature = 0.0f;
  }
  const std::int64_t num_colors = in.count("num_colors");
  if (num_colors != 0 && num_colors != n)
    fail(path, "malformed: num_colors is " + std::to_string(num_colors) + ", expected 0 or " + std::to_string(n));
  if (num_colors) readVectors("colours", [](std::size_t, const double*) {});
  const std::int64_t num_normals = in.count("num_normals");
  if (num_normals != 0 && num_normals != n)
    fail(path, "malformed: num_normals is " + std::to_string(num_normals) + ", expected 0 or " + std::to_string(n));
  vg.has_normals = num_normals > 0;
  if (num_normals)
    readVectors("normals", [&](std::size_t i, const double* v) {
      vg.points[i].normal_x = static_cast<float>(v[0]);
      vg.points[i].normal_y = static_cast<float>(v[1]);
      vg.points[i].normal_z = static_cast<float>(v[2]);
    });

  const std::int64_t num_groups = in.count("num_groups");
  if (static_cast<std::size_t>(num_groups) > bytes.size())
    fail(path, "truncated: header says " + std::to_string(num_groups) + " groups, more than the file can hold");
  PlanarSegmentation& seg = vg.segmentation;
  seg.labels.assign(num_points, -1);
  for (std::int64_t gi = 0; gi < num_groups; ++gi) {
    const std::string name = "group " + std::to_string(gi);
    RawGroup g = readGroup(path, in, num_points, name);
    const std::int64_t num_children = in.count("num_children");
    for (std::int64_t c = 0; c < num_children; ++c)  // sub-groups carry nothing paco uses
      readGroup(path, in, num_points, name + " child " + std::to_string(c));
    if (g.type != kPlaneType)
      fail(path, "unsupported: " + name + " has primitive type " + std::to_string(g.type) +
                     "; only planes (type 0) are read");
    pcl::PointIndices indices;
    for (std::int64_t idx : g.indices) {
      if (idx < 0 || static_cast<std::size_t>(idx) >= num_points)
        fail(path, "malformed: " + name + " uses point " + std::to_string(idx) + " of " +
                       detail::plural(num_points, "point"));
      indices.indices.push_back(static_cast<int>(idx));
      int& label = seg.labels[static_cast<std::size_t>(idx)];
      if (label < 0) label = static_cast<int>(gi);  // a point in two groups keeps its first
    }
    // The stored plane a x + b y + c z + d = 0, or a fit when it is missing (Easy3D writes zeros).
    Plane plane;
    bool have_plane = false;
    if (g.parameters.size() == 4) {
      const Eigen::Vector3d normal(g.parameters[0], g.parameters[1], g.parameters[2]);
      if (normal.allFinite() && std::isfinite(g.parameters[3]) && normal.norm() > 1e-12) {
        plane = Plane(normal, g.parameters[3]);
        plane.offset += plane.normal.dot(vg.coordinate_offset);  // into the points' frame
        have_plane = true;
      }
    }
    if (!have_plane) {
      std::vector<Eigen::Vector3d> members;
      for (int idx : indices.indices) members.push_back(vg.points[static_cast<std::size_t>(idx)].getVector3fMap().cast<double>());
      try {
        plane = Plane::fit(members);
      } catch (const Error& e) {
        fail(path, name + " has no valid plane parameters and its points do not define one: " + e.what());
      }
    }
    seg.planes.push_back(plane);
    seg.segments.push_back(std::move(indices));
    vg.group_labels.push_back(g.label);
    vg.group_colors.push_back(g.color);
    vg.confidences.push_back(confidenceFromLabel(g.label));
  }
  if (binary && bin.remaining() > 0)
    fail(path, "malformed: " + detail::plural(bin.remaining(), "unexpected byte") + " after the last group");
  return vg;
}

void saveVertexGroups(const std::string& path, const VertexGroups& vg) {
  const std::string ext = extensionOf(path);
  if (ext != ".vg" && ext != ".bvg") fail(path, "cannot write vertex groups with extension '" + ext + "'; use .vg or .bvg");
  const std::size_t n = vg.points.size();
  const PlanarSegmentation& seg = vg.segmentation;
  const std::size_t groups = seg.planes.size();
  const auto invalid = [&](const std::string& why) { throw IoError("saveVertexGroups('" + path + "'): " + why); };
  if (seg.segments.size() != groups)
    invalid(std::to_string(seg.segments.size()) + " segments for " + std::to_string(groups) + " planes");
  if (!vg.group_labels.empty() && vg.group_labels.size() != groups) invalid("group_labels size differs from the group count");
  if (!vg.group_colors.empty() && vg.group_colors.size() != groups) invalid("group_colors size differs from the group count");
  if (!vg.confidences.empty() && vg.confidences.size() != groups) invalid("confidences size differs from the group count");
  for (std::size_t g = 0; g < groups; ++g)
    for (int idx : seg.segments[g].indices)
      if (idx < 0 || static_cast<std::size_t>(idx) >= n)
        invalid("group " + std::to_string(g) + " uses point " + std::to_string(idx) + " of " + detail::plural(n, "point"));

  const auto labelOf = [&](std::size_t g) {
    std::string label;
    if (!vg.confidences.empty()) {
      label = kConfidencePrefix;
      detail::appendFloat(label, vg.confidences[g]);
    } else if (!vg.group_labels.empty() && !vg.group_labels[g].empty()) {
      label = vg.group_labels[g];
    } else {
      label = "unknown";
    }
    for (char& c : label)  // the ascii reader splits at blanks
      if (std::isspace(static_cast<unsigned char>(c))) c = '_';
    return label;
  };
  const auto colorOf = [&](std::size_t g) { return vg.group_colors.empty() ? paletteColor(g) : vg.group_colors[g]; };
  const auto normalOf = [&](std::size_t i) {
    const auto& p = vg.points[i];
    return Eigen::Vector3f(p.normal_x, p.normal_y, p.normal_z);
  };

  // Planes as the file holds them: n.(x - offset) + d = 0 is n.x + (d - n.offset) = 0.
  const Eigen::Vector3d& offset = vg.coordinate_offset;
  const auto fileOffset = [&](const Plane& plane) { return plane.offset - plane.normal.dot(offset); };

  std::string out;
  if (ext == ".vg") {
    const auto vec = [&](float a, float b, float c) {
      detail::appendFloat(out, a);
      out += ' ';
      detail::appendFloat(out, b);
      out += ' ';
      detail::appendFloat(out, c);
      out += '\n';
    };
    out += "num_points: " + std::to_string(n) + "\n";
    for (const auto& p : vg.points) {
      for (int k = 0; k < 3; ++k) {
        if (k) out += ' ';
        detail::appendCoordinate(out, p.data[k], offset[k]);
      }
      out += '\n';
    }
    out += "num_colors: 0\n";
    out += "num_normals: " + std::to_string(vg.has_normals ? n : 0) + "\n";
    if (vg.has_normals)
      for (std::size_t i = 0; i < n; ++i) vec(normalOf(i)[0], normalOf(i)[1], normalOf(i)[2]);
    out += "num_groups: " + std::to_string(groups) + "\n";
    for (std::size_t g = 0; g < groups; ++g) {
      const Plane& plane = seg.planes[g];
      out += "group_type: 0\nnum_group_parameters: 4\ngroup_parameters:";
      for (double v : {plane.normal.x(), plane.normal.y(), plane.normal.z()}) {
        out += ' ';
        detail::appendFloat(out, static_cast<float>(v));
      }
      out += ' ';
      if (offset.isZero(0.0)) detail::appendFloat(out, static_cast<float>(plane.offset));
      else detail::appendDouble(out, fileOffset(plane));
      out += "\ngroup_label: " + labelOf(g) + "\ngroup_color: ";
      const Eigen::Vector3f c = colorOf(g);
      vec(c[0], c[1], c[2]);
      out += "group_num_point: " + std::to_string(seg.segments[g].indices.size()) + "\n";
      for (std::size_t k = 0; k < seg.segments[g].indices.size(); ++k)
        out += (k ? " " : "") + std::to_string(seg.segments[g].indices[k]);
      out += "\nnum_children: 0\n";
    }
  } else {
    const auto i32 = [&](std::size_t v) { detail::appendBinary(out, static_cast<std::int32_t>(v)); };
    const auto f32 = [&](double v) { detail::appendBinary(out, static_cast<float>(v)); };
    i32(n);
    for (const auto& p : vg.points)
      for (int k = 0; k < 3; ++k) f32(detail::unshift(p.data[k], offset[k]));
    i32(0);  // no colours
    i32(vg.has_normals ? n : 0);
    if (vg.has_normals)
      for (std::size_t i = 0; i < n; ++i) { f32(normalOf(i)[0]); f32(normalOf(i)[1]); f32(normalOf(i)[2]); }
    i32(groups);
    for (std::size_t g = 0; g < groups; ++g) {
      const Plane& plane = seg.planes[g];
      i32(kPlaneType);
      i32(4);
      f32(plane.normal.x()); f32(plane.normal.y()); f32(plane.normal.z()); f32(fileOffset(plane));
      const std::string label = labelOf(g);
      i32(label.size());
      out += label;
      const Eigen::Vector3f c = colorOf(g);
      f32(c[0]); f32(c[1]); f32(c[2]);
      i32(seg.segments[g].indices.size());
      for (int idx : seg.segments[g].indices) detail::appendBinary(out, static_cast<std::int32_t>(idx));
      i32(0);  // no children
    }
  }
  detail::writeWholeFile(path, out);
}

VertexGroups toVertexGroups(const std::vector<PlanarPrimitive>& primitives, const Eigen::Vector3d& coordinate_offset) {
  VertexGroups vg;
  vg.has_normals = true;
  vg.coordinate_offset = coordinate_offset;
  for (std::size_t g = 0; g < primitives.size(); ++g) {
    const PlanarPrimitive& prim = primitives[g];
    pcl::PointIndices indices;
    for (const auto& p : prim.points) {
      indices.indices.push_back(static_cast<int>(vg.points.size()));
      vg.points.push_back(p);
      vg.segmentation.labels.push_back(static_cast<int>(g));
    }
    vg.segmentation.planes.push_back(prim.plane);
    vg.segmentation.segments.push_back(std::move(indices));
    std::string label = kConfidencePrefix;
    detail::appendFloat(label, prim.confidence);
    vg.group_labels.push_back(label);
    vg.group_colors.push_back(paletteColor(g));
    vg.confidences.push_back(prim.confidence);
  }
  return vg;
}

std::vector<PlanarPrimitive> toPrimitives(const VertexGroups& vg) {
  const PlanarSegmentation& seg = vg.segmentation;
  if (seg.segments.size() != seg.planes.size())
    throw InvalidInputError("toPrimitives: " + std::to_string(seg.segments.size()) + " segments for " +
                            std::to_string(seg.planes.size()) + " planes");
  std::vector<PlanarPrimitive> primitives(seg.planes.size());
  for (std::size_t g = 0; g < primitives.size(); ++g) {
    PlanarPrimitive& prim = primitives[g];
    prim.plane = seg.planes[g];
    prim.confidence = g < vg.confidences.size() ? vg.confidences[g] : 1.0f;
    for (int idx : seg.segments[g].indices) {
      if (idx < 0 || static_cast<std::size_t>(idx) >= vg.points.size())
        throw InvalidInputError("toPrimitives: group " + std::to_string(g) + " uses point " + std::to_string(idx) +
                                " of " + std::to_string(vg.points.size()));
      pcl::PointNormal p = vg.points[static_cast<std::size_t>(idx)];
      if (!vg.has_normals) {  // points without normals get the plane's
        p.normal_x = static_cast<float>(prim.plane.normal.x());
        p.normal_y = static_cast<float>(prim.plane.normal.y());
        p.normal_z = static_cast<float>(prim.plane.normal.z());
      }
      prim.points.push_back(p);
    }
  }
  return primitives;
}

}  // namespace paco::io
