#include <paco/common/disjoint_sets.h>
#include <paco/common/error.h>
#include <paco/common/surface_mesh.h>

#include <Eigen/Geometry>
#include <pcl/conversions.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <unordered_map>

namespace paco {

namespace {
// Uniform double in [0, 1) from 53 random bits: identical on every standard library, unlike
// std::uniform_real_distribution, so a seed gives the same samples everywhere.
double unitUniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
}  // namespace

std::size_t SurfaceMesh::numTriangles() const {
  std::size_t n = 0;
  for (const auto& f : faces) n += f.size() >= 3 ? f.size() - 2 : 0;
  return n;
}

void SurfaceMesh::validate(const std::string& what) const {
  for (std::size_t v = 0; v < vertices.size(); ++v)
    if (!vertices[v].allFinite())
      throw InvalidInputError(what + ": vertex " + std::to_string(v) + " has a non-finite coordinate");
  for (std::size_t f = 0; f < faces.size(); ++f) {
    if (faces[f].size() < 3)
      throw InvalidInputError(what + ": face " + std::to_string(f) + " has " +
                              std::to_string(faces[f].size()) + " vertices; a face needs at least 3");
    for (auto i : faces[f])
      if (i >= vertices.size())
        throw InvalidInputError(what + ": face " + std::to_string(f) + " uses vertex " +
                                std::to_string(i) + " but the mesh has " +
                                std::to_string(vertices.size()) + " vertices");
  }
}

std::string MeshTopology::describe() const {
  std::string s = isClosed() ? "closed" : "open (" + std::to_string(boundary_edges) + " boundary edges)";
  s += isManifold() ? ", manifold" : ", non-manifold (" + std::to_string(non_manifold_edges) +
                                         " edges, " + std::to_string(non_manifold_vertices) + " vertices)";
  s += isOriented() ? ", oriented" : ", inconsistently oriented (" + std::to_string(inconsistent_edges) + " edges)";
  s += ", " + std::to_string(components) + (components == 1 ? " component" : " components");
  return s;
}

MeshTopology analyseTopology(const SurfaceMesh& mesh) {
  mesh.validate();
  MeshTopology t;
  struct EdgeUse { std::size_t face; bool forward; };
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<EdgeUse>> edges;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (std::size_t k = 0; k < face.size(); ++k) {
      const std::uint32_t a = face[k], b = face[(k + 1) % face.size()];
      if (a == b) continue;
      edges[{std::min(a, b), std::max(a, b)}].push_back({f, a < b});
    }
  }
  DisjointSets<std::size_t> face_sets(mesh.faces.size());
  for (const auto& [key, uses] : edges) {
    if (uses.size() == 1) ++t.boundary_edges;
    else if (uses.size() > 2) ++t.non_manifold_edges;
    else if (uses[0].forward == uses[1].forward) ++t.inconsistent_edges;
    for (std::size_t k = 1; k < uses.size(); ++k) face_sets.join(uses[0].face, uses[k].face);
  }
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) t.components += face_sets.find(f) == f;

  // A vertex is manifold when its faces form one fan: connected through edges at the vertex.
  std::vector<std::vector<std::size_t>> vertex_faces(mesh.vertices.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    for (auto v : mesh.faces[f]) vertex_faces[v].push_back(f);
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& fs = vertex_faces[v];
    if (fs.size() < 2) continue;
    std::map<std::uint32_t, std::vector<std::size_t>> by_neighbour;  // other end of an edge at v
    for (std::size_t k = 0; k < fs.size(); ++k) {
      const auto& face = mesh.faces[fs[k]];
      for (std::size_t j = 0; j < face.size(); ++j)
        if (face[j] == v) {
          by_neighbour[face[(j + 1) % face.size()]].push_back(k);
          by_neighbour[face[(j + face.size() - 1) % face.size()]].push_back(k);
        }
    }
    DisjointSets<std::size_t> fan(fs.size());
    for (const auto& [w, ks] : by_neighbour)
      for (std::size_t k = 1; k < ks.size(); ++k) fan.join(ks[0], ks[k]);
    std::size_t fans = 0;
    for (std::size_t k = 0; k < fs.size(); ++k) fans += fan.find(k) == k;
    if (fans > 1) ++t.non_manifold_vertices;
  }
  return t;
}

std::size_t weldVertices(SurfaceMesh& mesh, double tolerance) {
  if (mesh.vertices.empty()) return 0;
  // Any cell size finds the vertices within `tolerance` (the distance test below decides); the
  // size only sets how many share a bucket. Tolerance 0 (exact duplicates) takes a thousandth of
  // the extent: a cell of 1e-300 put every vertex in the few buckets of the clamped index below.
  double cell = tolerance;
  if (!(cell > 0.0)) {
    Eigen::Vector3d lo, hi;
    boundingBox(mesh, lo, hi);
    const double extent = (hi - lo).norm();
    cell = std::isfinite(extent) && extent > 0.0 ? extent / 1024.0 : 1.0;
  }
  auto key_of = [&](const Eigen::Vector3d& p, int dx, int dy, int dz) {
    // The cell index is clamped (and NaN taken as 0) so that converting it and adding the offset
    // stay defined for any coordinate; far cells then share a key, which only costs time. The
    // hash multiplies unsigned, which wraps.
    const auto q = [&](double c, int d) {
      double index = std::floor(c / cell);
      index = std::isnan(index) ? 0.0 : std::clamp(index, -0x1p62, 0x1p62);
      return static_cast<std::uint64_t>(static_cast<std::int64_t>(index) + d);
    };
    return (q(p.x(), dx) * 73856093u) ^ (q(p.y(), dy) * 19349663u) ^ (q(p.z(), dz) * 83492791u);
  };
  std::unordered_map<std::uint64_t, std::vector<std::uint32_t>> grid;
  std::vector<std::uint32_t> remap(mesh.vertices.size());
  std::vector<Eigen::Vector3d> kept;
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Eigen::Vector3d& p = mesh.vertices[v];
    std::int64_t found = -1;
    for (int dx = -1; dx <= 1 && found < 0; ++dx)
      for (int dy = -1; dy <= 1 && found < 0; ++dy)
        for (int dz = -1; dz <= 1 && found < 0; ++dz) {
          auto it = grid.find(key_of(p, dx, dy, dz));
          if (it == grid.end()) continue;
          for (auto k : it->second)
            if ((kept[k] - p).norm() <= tolerance) { found = k; break; }
        }
    if (found < 0) {
      found = static_cast<std::int64_t>(kept.size());
      kept.push_back(p);
      grid[key_of(p, 0, 0, 0)].push_back(static_cast<std::uint32_t>(found));
    }
    remap[v] = static_cast<std::uint32_t>(found);
  }
  const std::size_t removed = mesh.vertices.size() - kept.size();
  mesh.vertices = std::move(kept);
  std::vector<std::vector<std::uint32_t>> faces;
  faces.reserve(mesh.faces.size());
  for (const auto& face : mesh.faces) {
    std::vector<std::uint32_t> f;
    for (auto i : face) {
      const auto j = remap[i];
      if (f.empty() || f.back() != j) f.push_back(j);
    }
    while (f.size() > 1 && f.front() == f.back()) f.pop_back();
    if (f.size() >= 3) faces.push_back(std::move(f));
  }
  mesh.faces = std::move(faces);
  return removed;
}

Eigen::Vector3d faceNormal(const SurfaceMesh& mesh, std::size_t face) {
  const auto& f = mesh.faces[face];
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < f.size(); ++k)
    n += mesh.vertices[f[k]].cross(mesh.vertices[f[(k + 1) % f.size()]]);
  const double len = n.norm();
  return len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
}

namespace {
double triangleArea(const SurfaceMesh& mesh, const std::vector<std::uint32_t>& t) {
  return 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
}
}  // namespace

double surfaceArea(const SurfaceMesh& mesh) {
  double area = 0;
  std::vector<std::vector<std::uint32_t>> triangles;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    triangles.clear();
    triangulateFace(mesh, f, triangles);
    for (const auto& t : triangles) area += triangleArea(mesh, t);
  }
  return area;
}

double signedVolume(const SurfaceMesh& mesh) {
  double six_v = 0;
  for (const auto& f : mesh.faces)
    for (std::size_t k = 1; k + 1 < f.size(); ++k)
      six_v += mesh.vertices[f[0]].dot(mesh.vertices[f[k]].cross(mesh.vertices[f[k + 1]]));
  return six_v / 6.0;
}

void boundingBox(const SurfaceMesh& mesh, Eigen::Vector3d& min, Eigen::Vector3d& max) {
  min = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  max = -min;
  for (const auto& v : mesh.vertices) {
    min = min.cwiseMin(v);
    max = max.cwiseMax(v);
  }
}

void flipFaces(SurfaceMesh& mesh) {
  for (auto& f : mesh.faces) std::reverse(f.begin(), f.end());
}

void sortMeshCanonically(SurfaceMesh& mesh) {
  for (auto& v : mesh.vertices) v = v + Eigen::Vector3d::Zero();  // -0 + 0 is +0: one text for zero
  std::vector<std::uint32_t> order(mesh.vertices.size());
  std::iota(order.begin(), order.end(), 0u);
  const auto lexicographic = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    return std::lexicographical_compare(a.data(), a.data() + 3, b.data(), b.data() + 3);
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](std::uint32_t a, std::uint32_t b) { return lexicographic(mesh.vertices[a], mesh.vertices[b]); });
  std::vector<std::uint32_t> new_index(order.size());
  std::vector<Eigen::Vector3d> vertices(order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    new_index[order[i]] = static_cast<std::uint32_t>(i);
    vertices[i] = mesh.vertices[order[i]];
  }
  mesh.vertices = std::move(vertices);
  for (auto& face : mesh.faces) {
    for (auto& v : face) v = new_index.at(v);
    std::rotate(face.begin(), std::min_element(face.begin(), face.end()), face.end());
  }
  std::sort(mesh.faces.begin(), mesh.faces.end());
}

void triangulateFace(const SurfaceMesh& mesh, std::size_t face, std::vector<std::vector<std::uint32_t>>& out) {
  const std::vector<std::uint32_t>& polygon = mesh.faces[face];
  const auto fan = [&out](const std::vector<std::uint32_t>& loop) {
    for (std::size_t k = 1; k + 1 < loop.size(); ++k) out.push_back({loop[0], loop[k], loop[k + 1]});
  };
  const bool finite = std::all_of(polygon.begin(), polygon.end(), [&](std::uint32_t i) { return mesh.vertices[i].allFinite(); });
  if (polygon.size() == 3 || !finite) {  // a non-finite corner stays in a triangle, for validate() to find
    fan(polygon);
    return;
  }
  // Work in 2D: drop the largest coordinate of the (Newell) normal, keeping counter-clockwise
  // (seen from the normal's side) positive.
  const Eigen::Vector3d normal = faceNormal(mesh, face);
  int axis = 2;
  normal.cwiseAbs().maxCoeff(&axis);
  const int u = (axis + 1) % 3, v = (axis + 2) % 3;
  const double sign = normal[axis] >= 0 ? 1.0 : -1.0;
  const auto at = [&](std::uint32_t i) { return Eigen::Vector2d(mesh.vertices[i][u], mesh.vertices[i][v]); };
  const auto turn = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
    return sign * ((b - a).x() * (c - a).y() - (b - a).y() * (c - a).x());
  };
  // Below this a corner counts as straight: relative to the face's size, far above rounding.
  Eigen::AlignedBox2d box;
  for (std::uint32_t i : polygon) box.extend(at(i));
  const double straight = 1e-12 * box.diagonal().squaredNorm();

  const auto cornerAt = [&](const std::vector<std::uint32_t>& loop, std::size_t k) {
    return turn(at(loop[(k + loop.size() - 1) % loop.size()]), at(loop[k]), at(loop[(k + 1) % loop.size()]));
  };
  bool convex = true;
  for (std::size_t k = 0; k < polygon.size() && convex; ++k) convex = cornerAt(polygon, k) >= -straight;
  if (convex) {  // a fan, as always: convex faces sample exactly as before ear clipping existed
    fan(polygon);
    return;
  }
  // Straight corners first: dropping one leaves the same polygon, and ears never straddle it.
  std::vector<std::uint32_t> ring;
  for (std::size_t k = 0; k < polygon.size(); ++k)
    if (std::abs(cornerAt(polygon, k)) > straight) ring.push_back(polygon[k]);
  while (ring.size() > 3) {
    bool clipped = false;
    for (std::size_t k = 0; k < ring.size() && !clipped; ++k) {
      const std::size_t p = (k + ring.size() - 1) % ring.size(), q = (k + 1) % ring.size();
      const Eigen::Vector2d a = at(ring[p]), b = at(ring[k]), c = at(ring[q]);
      const double corner = turn(a, b, c);
      if (std::abs(corner) <= straight) {  // straight after an ear was cut next to it
        ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(k));
        clipped = true;
        continue;
      }
      if (corner < 0) continue;  // reflex: not an ear
      bool empty = true;  // no other corner inside or on the candidate ear
      for (std::size_t j = 0; j < ring.size() && empty; ++j) {
        if (j == p || j == k || j == q) continue;
        const Eigen::Vector2d x = at(ring[j]);
        empty = !(turn(a, b, x) >= 0 && turn(b, c, x) >= 0 && turn(c, a, x) >= 0);
      }
      if (!empty) continue;
      out.push_back({ring[p], ring[k], ring[q]});
      ring.erase(ring.begin() + static_cast<std::ptrdiff_t>(k));
      clipped = true;
    }
    if (!clipped) break;
  }
  if (ring.size() == 3 && std::abs(turn(at(ring[0]), at(ring[1]), at(ring[2]))) <= straight) return;
  fan(ring);
}

SurfaceMesh triangulated(const SurfaceMesh& mesh) {
  SurfaceMesh out;
  out.vertices = mesh.vertices;
  out.faces.reserve(mesh.numTriangles());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) triangulateFace(mesh, f, out.faces);
  return out;
}

SurfaceSample sampleSurface(const SurfaceMesh& mesh, std::size_t count, std::uint64_t seed) {
  mesh.validate();
  struct Triangle { std::uint32_t face, a, b, c; };
  std::vector<Triangle> triangles;
  std::vector<double> cumulative;
  double total = 0;
  std::vector<std::vector<std::uint32_t>> pieces;
  for (std::size_t fi = 0; fi < mesh.faces.size(); ++fi) {
    pieces.clear();
    triangulateFace(mesh, fi, pieces);
    for (const auto& t : pieces) {
      const double a = triangleArea(mesh, t);
      if (!(a > 0)) continue;
      total += a;
      triangles.push_back({static_cast<std::uint32_t>(fi), t[0], t[1], t[2]});
      cumulative.push_back(total);
    }
  }
  if (!(total > 0)) throw InvalidInputError("sampleSurface: the mesh has no area to sample");
  std::vector<Eigen::Vector3d> face_normals(mesh.faces.size());
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) face_normals[f] = faceNormal(mesh, f);

  SurfaceSample s;
  s.points.reserve(count); s.normals.reserve(count); s.faces.reserve(count);
  std::mt19937_64 rng(seed);
  for (std::size_t i = 0; i < count; ++i) {
    const double r = unitUniform(rng) * total;
    std::size_t t = std::upper_bound(cumulative.begin(), cumulative.end(), r) - cumulative.begin();
    t = std::min(t, triangles.size() - 1);
    double u = unitUniform(rng), v = unitUniform(rng);
    if (u + v > 1) { u = 1 - u; v = 1 - v; }
    const Triangle& tri = triangles[t];
    const Eigen::Vector3d& A = mesh.vertices[tri.a];
    s.points.push_back(A + u * (mesh.vertices[tri.b] - A) + v * (mesh.vertices[tri.c] - A));
    s.normals.push_back(face_normals[tri.face]);
    s.faces.push_back(tri.face);
  }
  return s;
}

pcl::PolygonMesh toPolygonMesh(const SurfaceMesh& mesh) {
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.reserve(mesh.vertices.size());
  for (const auto& v : mesh.vertices)
    cloud.push_back(pcl::PointXYZ(static_cast<float>(v.x()), static_cast<float>(v.y()), static_cast<float>(v.z())));
  pcl::PolygonMesh out;
  pcl::toPCLPointCloud2(cloud, out.cloud);
  out.polygons.reserve(mesh.faces.size());
  for (const auto& f : mesh.faces) {
    pcl::Vertices poly;
    poly.vertices.assign(f.begin(), f.end());
    out.polygons.push_back(std::move(poly));
  }
  return out;
}

SurfaceMesh fromPolygonMesh(const pcl::PolygonMesh& mesh) {
  bool has_x = false, has_y = false, has_z = false;
  for (const auto& field : mesh.cloud.fields) {
    has_x |= field.name == "x"; has_y |= field.name == "y"; has_z |= field.name == "z";
  }
  if (!(has_x && has_y && has_z) && !mesh.polygons.empty())
    throw InvalidInputError("fromPolygonMesh: the mesh cloud has no x, y, z fields");
  SurfaceMesh out;
  if (has_x && has_y && has_z) {
    pcl::PointCloud<pcl::PointXYZ> cloud;
    pcl::fromPCLPointCloud2(mesh.cloud, cloud);
    out.vertices.reserve(cloud.size());
    for (const auto& p : cloud) out.vertices.emplace_back(p.x, p.y, p.z);
  }
  out.faces.reserve(mesh.polygons.size());
  for (const auto& poly : mesh.polygons) out.faces.emplace_back(poly.vertices.begin(), poly.vertices.end());
  return out;
}

}  // namespace paco
