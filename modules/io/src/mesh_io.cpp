// Polygon mesh readers (OBJ, OFF, PLY, STL) and writers (OBJ, OFF, PLY, binary STL).
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>

#include "io_detail.h"
#include "ply.h"

#include <paco/common/error.h>

#include <array>
#include <cctype>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>

namespace paco::io {

namespace {

using detail::fail;
using detail::parseDouble;
using detail::parseInt64;

/// A vertex index stored as a double (PLY) or integer; checked for range.
std::uint32_t checkedIndex(const std::string& path, double value, std::size_t num_vertices, std::size_t face) {
  if (!(value >= 0) || value >= static_cast<double>(num_vertices) || std::floor(value) != value)
    fail(path, "malformed: face " + std::to_string(face) + " uses vertex " + detail::numberText(value) + " but there are " +
                   detail::plural(num_vertices, "vertex"));
  return static_cast<std::uint32_t>(value);
}

SurfaceMesh readObj(const std::string& path, const std::string& bytes) {
  SurfaceMesh mesh;
  detail::TextCursor text(bytes);
  std::string_view line;
  std::vector<std::string_view> tok;
  std::vector<std::int64_t> raw_face;
  std::vector<std::vector<std::int64_t>> raw_faces;  // resolved after all vertices are known
  std::vector<std::size_t> face_lines;
  for (std::size_t line_number = 1; text.nextLine(line); ++line_number) {
    const std::size_t hash = line.find('#');
    if (hash != std::string_view::npos) line = line.substr(0, hash);
    detail::splitTokens(line, tok);
    if (tok.empty()) continue;
    const auto bad = [&](const std::string& why) {
      fail(path, "malformed: line " + std::to_string(line_number) + ": " + why);
    };
    if (tok[0] == "v") {
      if (tok.size() < 4) bad("a vertex needs x y z");
      Eigen::Vector3d v;
      for (int k = 0; k < 3; ++k)
        if (!parseDouble(tok[static_cast<std::size_t>(k) + 1], v[k]))
          bad("'" + std::string(tok[static_cast<std::size_t>(k) + 1]) + "' is not a number");
      mesh.vertices.push_back(v);
    } else if (tok[0] == "f") {
      if (tok.size() < 4) bad("a face needs at least 3 vertices");
      raw_face.clear();
      for (std::size_t k = 1; k < tok.size(); ++k) {
        // "v", "v/vt", "v//vn" or "v/vt/vn": the vertex index comes first.
        const std::string_view index_text = tok[k].substr(0, tok[k].find('/'));
        std::int64_t index = 0;
        if (!parseInt64(index_text, index) || index == 0) bad("bad face index '" + std::string(tok[k]) + "'");
        // Negative indices count back from the latest vertex.
        if (index < 0) index += static_cast<std::int64_t>(mesh.vertices.size());
        else index -= 1;
        raw_face.push_back(index);
      }
      raw_faces.push_back(raw_face);
      face_lines.push_back(line_number);
    } else {
      // vt, vn, g, o, s, usemtl, mtllib, l, p and other keywords carry nothing we keep; binary
      // garbage is not a keyword.
      for (char c : tok[0])
        if (!std::isalpha(static_cast<unsigned char>(c)) && c != '_')
          bad("unexpected '" + std::string(tok[0]).substr(0, 20) + "' (is this an OBJ file?)");
    }
  }
  mesh.faces.reserve(raw_faces.size());
  for (std::size_t f = 0; f < raw_faces.size(); ++f) {
    std::vector<std::uint32_t> face;
    for (std::int64_t index : raw_faces[f]) {
      if (index < 0 || index >= static_cast<std::int64_t>(mesh.vertices.size()))
        fail(path, "malformed: line " + std::to_string(face_lines[f]) + ": face uses vertex " +
                       std::to_string(index + 1) + " but the file has " + detail::plural(mesh.vertices.size(), "vertex"));
      face.push_back(static_cast<std::uint32_t>(index));
    }
    mesh.faces.push_back(std::move(face));
  }
  return mesh;
}

SurfaceMesh readOff(const std::string& path, const std::string& bytes) {
  SurfaceMesh mesh;
  detail::TextCursor text(bytes);
  std::string_view line;
  std::vector<std::string_view> tok;
  std::size_t line_number = 0;
  // Next line with content (comments and blank lines skipped).
  const auto nextContent = [&]() -> bool {
    while (text.nextLine(line)) {
      ++line_number;
      const std::size_t hash = line.find('#');
      if (hash != std::string_view::npos) line = line.substr(0, hash);
      detail::splitTokens(line, tok);
      if (!tok.empty()) return true;
    }
    return false;
  };
  if (!nextContent()) fail(path, "malformed: OFF file has no header");
  const std::string keyword(tok[0]);
  if (keyword.size() < 3 || keyword.compare(keyword.size() - 3, 3, "OFF") != 0)
    fail(path, "malformed: OFF file must start with 'OFF', found '" + keyword.substr(0, 20) + "'");
  if (keyword.find('4') != std::string::npos || keyword.find('n') != std::string::npos)
    fail(path, "unsupported OFF variant '" + keyword + "'; only 3-D OFF files are read");
  tok.erase(tok.begin());
  if (tok.empty() && !nextContent()) fail(path, "truncated: OFF file has no counts line");
  std::int64_t nv = 0, nf = 0;
  if (tok.size() < 2 || !parseInt64(tok[0], nv) || !parseInt64(tok[1], nf) || nv < 0 || nf < 0)
    fail(path, "malformed: line " + std::to_string(line_number) + ": expected \"<vertices> <faces> <edges>\"");
  const std::size_t max_items = bytes.size();  // each vertex or face takes at least one byte
  if (static_cast<std::size_t>(nv) > max_items || static_cast<std::size_t>(nf) > max_items)
    fail(path, "truncated: header says " + detail::plural(static_cast<std::size_t>(nv), "vertex") + " and " +
                   detail::plural(static_cast<std::size_t>(nf), "face") + ", more than the file can hold");
  mesh.vertices.reserve(static_cast<std::size_t>(nv));
  for (std::int64_t i = 0; i < nv; ++i) {
    if (!nextContent())
      fail(path, "truncated: header says " + detail::plural(static_cast<std::size_t>(nv), "vertex") +
                     ", data holds " + std::to_string(i));
    Eigen::Vector3d v;
    if (tok.size() < 3 && text.atEnd())
      fail(path, "truncated: header says " + detail::plural(static_cast<std::size_t>(nv), "vertex") +
                     ", the file ends in vertex " + std::to_string(i));
    if (tok.size() < 3) fail(path, "malformed: line " + std::to_string(line_number) + ": a vertex needs x y z");
    for (int k = 0; k < 3; ++k)
      if (!parseDouble(tok[static_cast<std::size_t>(k)], v[k]))
        fail(path, "malformed: line " + std::to_string(line_number) + ": '" +
                       std::string(tok[static_cast<std::size_t>(k)]) + "' is not a number");
    mesh.vertices.push_back(v);
  }
  mesh.faces.reserve(static_cast<std::size_t>(nf));
  for (std::int64_t f = 0; f < nf; ++f) {
    if (!nextContent())
      fail(path, "truncated: header says " + detail::plural(static_cast<std::size_t>(nf), "face") +
                     ", data holds " + std::to_string(f));
    std::int64_t n = 0;
    if (parseInt64(tok[0], n) && static_cast<std::size_t>(n) + 1 > tok.size() && text.atEnd() && bytes.back() != '\n')
      fail(path, "truncated: header says " + detail::plural(static_cast<std::size_t>(nf), "face") +
                     ", the file ends in face " + std::to_string(f));
    if (!parseInt64(tok[0], n) || n < 3 || static_cast<std::size_t>(n) + 1 > tok.size())
      fail(path, "malformed: line " + std::to_string(line_number) + ": expected \"<n >= 3> <n vertex indices>\"");
    std::vector<std::uint32_t> face;
    for (std::int64_t k = 1; k <= n; ++k) {
      double index = 0;
      if (!parseDouble(tok[static_cast<std::size_t>(k)], index))
        fail(path, "malformed: line " + std::to_string(line_number) + ": bad index '" +
                       std::string(tok[static_cast<std::size_t>(k)]) + "'");
      face.push_back(checkedIndex(path, index, mesh.vertices.size(), static_cast<std::size_t>(f)));
    }
    mesh.faces.push_back(std::move(face));
  }
  return mesh;
}

SurfaceMesh readPlyMesh(const std::string& path, const std::string& bytes) {
  const detail::PlyFile ply = detail::readPly(path, bytes);
  const detail::PlyElement* vertex = ply.element("vertex");
  if (!vertex) fail(path, "malformed: PLY file has no 'vertex' element");
  const int ix = vertex->find({"x"}), iy = vertex->find({"y"}), iz = vertex->find({"z"});
  if (ix < 0 || iy < 0 || iz < 0 || vertex->properties[static_cast<std::size_t>(ix)].is_list)
    fail(path, "malformed: PLY vertices have no x, y, z properties");
  SurfaceMesh mesh;
  mesh.vertices.resize(vertex->count);
  for (std::size_t i = 0; i < vertex->count; ++i)
    mesh.vertices[i] = {vertex->scalars[static_cast<std::size_t>(ix)][i], vertex->scalars[static_cast<std::size_t>(iy)][i],
                        vertex->scalars[static_cast<std::size_t>(iz)][i]};
  const detail::PlyElement* face = ply.element("face");
  if (!face) return mesh;
  const int il = face->find({"vertex_indices", "vertex_index"});
  if (il < 0 || !face->properties[static_cast<std::size_t>(il)].is_list)
    fail(path, "malformed: PLY faces have no 'vertex_indices' list");
  const auto& items = face->list_items[static_cast<std::size_t>(il)];
  const auto& offsets = face->list_offsets[static_cast<std::size_t>(il)];
  mesh.faces.resize(face->count);
  for (std::size_t f = 0; f < face->count; ++f) {
    if (offsets[f + 1] - offsets[f] < 3)
      fail(path, "malformed: face " + std::to_string(f) + " has " + std::to_string(offsets[f + 1] - offsets[f]) +
                     " vertices (at least 3 needed)");
    for (std::size_t k = offsets[f]; k < offsets[f + 1]; ++k)
      mesh.faces[f].push_back(checkedIndex(path, items[k], mesh.vertices.size(), f));
  }
  return mesh;
}

/// Builds a mesh from STL triangle corners, sharing vertices with exactly equal coordinates.
SurfaceMesh weldedTriangles(const std::string& path, const std::vector<std::array<float, 9>>& triangles) {
  for (std::size_t t = 0; t < triangles.size(); ++t)
    for (float v : triangles[t])
      if (!std::isfinite(v)) fail(path, "triangle " + std::to_string(t) + " has non-finite (NaN/Inf) coordinates");
  SurfaceMesh mesh;
  std::map<std::array<float, 3>, std::uint32_t> index_of;
  std::size_t degenerate = 0;
  for (const auto& t : triangles) {
    std::vector<std::uint32_t> face;
    for (int c = 0; c < 3; ++c) {
      // +0.0f turns -0 into 0 so that the two weld.
      const std::array<float, 3> key = {t[3 * c] + 0.0f, t[3 * c + 1] + 0.0f, t[3 * c + 2] + 0.0f};
      const auto [it, inserted] = index_of.emplace(key, static_cast<std::uint32_t>(mesh.vertices.size()));
      if (inserted) mesh.vertices.emplace_back(key[0], key[1], key[2]);
      face.push_back(it->second);
    }
    if (face[0] == face[1] || face[1] == face[2] || face[0] == face[2]) {
      ++degenerate;
      continue;
    }
    mesh.faces.push_back(std::move(face));
  }
  if (degenerate > 0)
    std::cerr << "warning: STL: skipped " << detail::plural(degenerate, "degenerate triangle")
              << " (two corners at the same point)" << std::endl;
  return mesh;
}

SurfaceMesh readStl(const std::string& path, const std::string& bytes) {
  // Binary STL: 80-byte header, uint32 count, 50 bytes per triangle. Some binary files start with
  // "solid" too, so the size decides first.
  if (bytes.size() >= 84) {
    detail::ByteCursor in(bytes, 80);
    const std::uint32_t count = in.read<std::uint32_t>();
    const std::size_t expected = 84 + static_cast<std::size_t>(count) * 50;
    const bool looks_ascii = bytes.compare(0, 5, "solid") == 0 && bytes.find("facet", 5) != std::string::npos;
    if (bytes.size() == expected || (!looks_ascii && bytes.size() > expected)) {
      std::vector<std::array<float, 9>> triangles(count);
      for (auto& t : triangles) {
        in.skip(12);  // stored normal: recomputed from the corners when needed
        for (float& v : t) v = in.read<float>();
        in.skip(2);
      }
      return weldedTriangles(path, triangles);
    }
    if (!looks_ascii)
      fail(path, "truncated: header says " + detail::plural(count, "triangle") + ", data holds " +
                     std::to_string((bytes.size() - 84) / 50));
  } else if (bytes.compare(0, 5, "solid") != 0) {
    fail(path, "truncated: a binary STL needs at least 84 bytes, the file has " + std::to_string(bytes.size()));
  }
  detail::TextCursor text(bytes);
  std::string_view token;
  std::vector<std::array<float, 9>> triangles;
  std::vector<float> loop;
  bool in_loop = false, saw_endsolid = false;
  std::string_view name_line;
  text.nextLine(name_line);  // "solid <name>"
  while (text.nextToken(token)) {
    if (token == "solid") {
      // A further solid in the same file; skip its name up to the end of the line.
      std::string_view rest;
      text.nextLine(rest);
      continue;
    }
    if (token == "vertex") {
      if (!in_loop) fail(path, "malformed: line " + std::to_string(text.line()) + ": 'vertex' outside 'outer loop'");
      for (int k = 0; k < 3; ++k) {
        double v = 0;
        if (!text.nextToken(token))
          fail(path, "truncated: file ends inside a vertex (line " + std::to_string(text.line()) + ")");
        if (!parseDouble(token, v))
          fail(path, "malformed: line " + std::to_string(text.line()) + ": '" + std::string(token) + "' is not a number");
        loop.push_back(static_cast<float>(v));
      }
    } else if (token == "outer") {
      in_loop = true;
      loop.clear();
    } else if (token == "endloop") {
      if (loop.size() < 9)
        fail(path, "malformed: line " + std::to_string(text.line()) + ": a facet needs 3 vertices, it has " +
                       std::to_string(loop.size() / 3));
      // Fan-triangulate the rare loops with more than 3 corners.
      for (std::size_t k = 2; k * 3 < loop.size(); ++k)
        triangles.push_back({loop[0], loop[1], loop[2], loop[3 * (k - 1)], loop[3 * (k - 1) + 1],
                             loop[3 * (k - 1) + 2], loop[3 * k], loop[3 * k + 1], loop[3 * k + 2]});
      in_loop = false;
    } else if (token == "endsolid") {
      saw_endsolid = true;
      std::string_view rest;
      text.nextLine(rest);
    } else if (token == "facet" || token == "normal" || token == "loop" || token == "endfacet") {
      if (token == "normal")
        for (int k = 0; k < 3; ++k) text.nextToken(token);
    } else {
      fail(path, "malformed: line " + std::to_string(text.line()) + ": unexpected '" + std::string(token).substr(0, 20) +
                     "' in ASCII STL");
    }
  }
  if (in_loop || !saw_endsolid)
    fail(path, "truncated: ASCII STL ends without 'endsolid' after " + detail::plural(triangles.size(), "facet"));
  return weldedTriangles(path, triangles);
}

std::string writeObj(const SurfaceMesh& mesh) {
  std::string out = "# written by paco\n";
  for (const auto& v : mesh.vertices) {
    out += "v ";
    detail::appendDouble(out, v.x());
    out += ' ';
    detail::appendDouble(out, v.y());
    out += ' ';
    detail::appendDouble(out, v.z());
    out += '\n';
  }
  for (const auto& f : mesh.faces) {
    out += 'f';
    for (std::uint32_t i : f) out += ' ' + std::to_string(i + 1);
    out += '\n';
  }
  return out;
}

std::string writeOff(const SurfaceMesh& mesh) {
  std::string out = "OFF\n" + std::to_string(mesh.vertices.size()) + " " + std::to_string(mesh.faces.size()) + " 0\n";
  for (const auto& v : mesh.vertices) {
    detail::appendDouble(out, v.x());
    out += ' ';
    detail::appendDouble(out, v.y());
    out += ' ';
    detail::appendDouble(out, v.z());
    out += '\n';
  }
  for (const auto& f : mesh.faces) {
    out += std::to_string(f.size());
    for (std::uint32_t i : f) out += ' ' + std::to_string(i);
    out += '\n';
  }
  return out;
}

std::string writePlyMesh(const SurfaceMesh& mesh) {
  // The usual uchar vertex counts, unless a face has more than 255 vertices.
  bool small_faces = true;
  for (const auto& f : mesh.faces) small_faces &= f.size() <= 255;
  std::string out = "ply\nformat binary_little_endian 1.0\ncomment written by paco\nelement vertex " +
                    std::to_string(mesh.vertices.size()) +
                    "\nproperty double x\nproperty double y\nproperty double z\nelement face " +
                    std::to_string(mesh.faces.size()) + "\nproperty list " + (small_faces ? "uchar" : "int") +
                    " int vertex_indices\nend_header\n";
  for (const auto& v : mesh.vertices)
    for (int k = 0; k < 3; ++k) detail::appendBinary(out, v[k]);
  for (const auto& f : mesh.faces) {
    if (small_faces) detail::appendBinary(out, static_cast<std::uint8_t>(f.size()));
    else detail::appendBinary(out, static_cast<std::int32_t>(f.size()));
    for (std::uint32_t i : f) detail::appendBinary(out, static_cast<std::int32_t>(i));
  }
  return out;
}

std::string writeStl(const SurfaceMesh& mesh) {
  const SurfaceMesh tri = triangulated(mesh);
  std::string out = "binary STL written by paco";
  out.resize(80, ' ');
  detail::appendBinary(out, static_cast<std::uint32_t>(tri.faces.size()));
  for (std::size_t f = 0; f < tri.faces.size(); ++f) {
    const Eigen::Vector3d n = faceNormal(tri, f);
    for (int k = 0; k < 3; ++k) detail::appendBinary(out, static_cast<float>(n[k]));
    for (std::uint32_t i : tri.faces[f])
      for (int k = 0; k < 3; ++k) detail::appendBinary(out, static_cast<float>(tri.vertices[i][k]));
    detail::appendBinary(out, static_cast<std::uint16_t>(0));
  }
  return out;
}

}  // namespace

SurfaceMesh loadMesh(const std::string& path, bool allow_no_faces) {
  const std::string ext = extensionOf(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(path, "unknown mesh extension '" + ext + "'; use .obj, .off, .ply or .stl");
  const std::string bytes = detail::readWholeFile(path);
  SurfaceMesh mesh;
  if (ext == ".obj") mesh = readObj(path, bytes);
  else if (ext == ".off") mesh = readOff(path, bytes);
  else if (ext == ".ply") mesh = readPlyMesh(path, bytes);
  else mesh = readStl(path, bytes);
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i)
    if (!mesh.vertices[i].allFinite())
      fail(path, "vertex " + std::to_string(i) + " has non-finite (NaN/Inf) coordinates");
  if (mesh.vertices.empty() && !allow_no_faces) fail(path, "holds no vertices");
  if (mesh.faces.empty() && !allow_no_faces) fail(path, "holds no faces (" + detail::plural(mesh.vertices.size(), "vertex") + " only)");
  return mesh;
}

void saveMesh(const std::string& path, const SurfaceMesh& mesh) {
  const std::string ext = extensionOf(path);
  if (ext != ".obj" && ext != ".off" && ext != ".ply" && ext != ".stl")
    fail(path, "cannot write meshes with extension '" + ext + "'; use .obj, .off, .ply or .stl");
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (mesh.faces[f].size() < 3)
      throw IoError("saveMesh('" + path + "'): face " + std::to_string(f) + " has " +
                    detail::plural(mesh.faces[f].size(), "vertex") + " (3 or more needed)");
    for (std::uint32_t i : mesh.faces[f])
      if (i >= mesh.vertices.size())
        throw IoError("saveMesh('" + path + "'): face " + std::to_string(f) + " uses vertex " + std::to_string(i) +
                      " of " + std::to_string(mesh.vertices.size()));
  }
  std::string bytes;
  if (ext == ".obj") bytes = writeObj(mesh);
  else if (ext == ".off") bytes = writeOff(mesh);
  else if (ext == ".ply") bytes = writePlyMesh(mesh);
  else bytes = writeStl(mesh);
  detail::writeWholeFile(path, bytes);
}

pcl::PolygonMesh loadPolygonMesh(const std::string& path) { return toPolygonMesh(loadMesh(path)); }

void savePolygonMesh(const std::string& path, const pcl::PolygonMesh& mesh) {
  SurfaceMesh surface;
  try {
    surface = fromPolygonMesh(mesh);
  } catch (const Error& e) {
    throw IoError("savePolygonMesh('" + path + "'): " + e.what());
  }
  saveMesh(path, surface);
}

}  // namespace paco::io
