#include "mesh_cleanup.h"

#include <paco/common/disjoint_sets.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <unordered_map>
#include <vector>

namespace paco::detail {
namespace {

using EdgeKey = std::pair<std::uint32_t, std::uint32_t>;
struct EdgeKeyHash {
  std::size_t operator()(const EdgeKey& e) const { return (static_cast<std::size_t>(e.first) << 32) ^ e.second; }
};

// Replaces each edge-connected group of coplanar faces (same outward normal) by one polygon when
// its boundary is a single simple loop; groups with holes keep their convex pieces.
void mergeCoplanarFaces(SurfaceMesh& mesh) {
  const std::size_t nf = mesh.faces.size();
  std::unordered_map<EdgeKey, std::vector<std::uint32_t>, EdgeKeyHash> edge_faces;
  for (std::uint32_t f = 0; f < nf; ++f) {
    const auto& face = mesh.faces[f];
    for (std::size_t i = 0; i < face.size(); ++i) {
      std::uint32_t a = face[i], b = face[(i + 1) % face.size()];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  }
  DisjointSets<std::uint32_t> groups(nf);
  std::vector<Eigen::Vector3d> normals(nf);
  for (std::size_t f = 0; f < nf; ++f) normals[f] = faceNormal(mesh, f);
  for (const auto& [edge, faces] : edge_faces)
    if (faces.size() == 2 && faces[0] != faces[1] && normals[faces[0]].dot(normals[faces[1]]) > 1 - 1e-8)
      groups.join(faces[0], faces[1]);
  std::map<std::uint32_t, std::vector<std::uint32_t>> components;
  for (std::uint32_t f = 0; f < nf; ++f) components[groups.find(f)].push_back(f);

  std::vector<std::vector<std::uint32_t>> faces;
  for (const auto& [root, members] : components) {
    bool merged = false;
    if (members.size() > 1) {
      std::map<EdgeKey, int> directed;  // directed edge -> multiplicity
      for (std::uint32_t f : members) {
        const auto& face = mesh.faces[f];
        for (std::size_t i = 0; i < face.size(); ++i) ++directed[{face[i], face[(i + 1) % face.size()]}];
      }
      std::map<std::uint32_t, std::vector<std::uint32_t>> next;
      std::size_t boundary_edges = 0;
      bool clean = true;
      for (const auto& [e, count] : directed) {
        const auto reverse = directed.find({e.second, e.first});
        if (reverse != directed.end()) continue;
        clean &= count == 1;
        next[e.first].push_back(e.second);
        ++boundary_edges;
      }
      for (const auto& [v, outs] : next) clean &= outs.size() == 1;
      if (clean && boundary_edges >= 3) {
        std::vector<std::uint32_t> loop;
        std::uint32_t v = next.begin()->first;
        do {
          loop.push_back(v);
          v = next[v].front();
        } while (v != loop.front() && loop.size() <= boundary_edges);
        if (loop.size() == boundary_edges) {
          faces.push_back(std::move(loop));
          merged = true;
        }
      }
    }
    if (!merged)
      for (std::uint32_t f : members) faces.push_back(mesh.faces[f]);
  }
  mesh.faces = std::move(faces);
}

// Drops vertices that only two faces use and that sit between the same two neighbours in both:
// they are collinear points left on a straight edge by merging.
void removeCollinearVertices(SurfaceMesh& mesh) {
  std::vector<std::vector<std::uint32_t>> faces_of(mesh.vertices.size());
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f)
    for (std::uint32_t v : mesh.faces[f]) faces_of[v].push_back(f);
  auto neighbours = [&](std::uint32_t f, std::uint32_t v) {
    const auto& face = mesh.faces[f];
    const std::size_t n = face.size();
    for (std::size_t i = 0; i < n; ++i)
      if (face[i] == v) return std::make_pair(std::min(face[(i + n - 1) % n], face[(i + 1) % n]),
                                              std::max(face[(i + n - 1) % n], face[(i + 1) % n]));
    return std::make_pair(v, v);
  };
  std::vector<bool> drop(mesh.vertices.size(), false);
  for (std::uint32_t v = 0; v < mesh.vertices.size(); ++v) {
    const auto& fs = faces_of[v];
    if (fs.size() != 2 || fs[0] == fs[1]) continue;
    if (neighbours(fs[0], v) != neighbours(fs[1], v)) continue;
    const auto [a, b] = neighbours(fs[0], v);
    const Eigen::Vector3d ab = mesh.vertices[b] - mesh.vertices[a];
    const Eigen::Vector3d av = mesh.vertices[v] - mesh.vertices[a];
    if (ab.cross(av).norm() > 1e-9 * std::max(1e-12, ab.norm())) continue;  // not straight: keep
    drop[v] = true;
  }
  for (auto& face : mesh.faces) {
    std::vector<std::uint32_t> kept;
    for (std::uint32_t v : face)
      if (!drop[v]) kept.push_back(v);
    face = std::move(kept);
  }
  mesh.faces.erase(std::remove_if(mesh.faces.begin(), mesh.faces.end(), [](const auto& f) { return f.size() < 3; }),
                   mesh.faces.end());
}

// Separates sheets that touch along an edge (4+ faces) or at a vertex. At a non-manifold edge the
// faces are sorted by angle around it and paired across the solid wedges between them; then the
// faces around each vertex are grouped by edge connectivity (using that pairing) and each group
// beyond the first gets its own copy of the vertex.
void splitNonManifold(SurfaceMesh& mesh) {
  std::map<EdgeKey, std::vector<std::uint32_t>> edge_faces;
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (std::size_t i = 0; i < face.size(); ++i) {
      const std::uint32_t a = face[i], b = face[(i + 1) % face.size()];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  }
  auto goesForward = [&](std::uint32_t f, std::uint32_t a, std::uint32_t b) {
    const auto& face = mesh.faces[f];
    for (std::size_t i = 0; i < face.size(); ++i)
      if (face[i] == a && face[(i + 1) % face.size()] == b) return true;
    return false;
  };
  // Partner of each face across each edge.
  std::map<std::pair<EdgeKey, std::uint32_t>, std::uint32_t> partner;
  for (const auto& [edge, faces] : edge_faces) {
    if (faces.size() == 2) {
      partner[{edge, faces[0]}] = faces[1];
      partner[{edge, faces[1]}] = faces[0];
      continue;
    }
    if (faces.size() < 4 || faces.size() % 2) continue;
    const Eigen::Vector3d a = mesh.vertices[edge.first], b = mesh.vertices[edge.second];
    const Eigen::Vector3d e = (b - a).normalized();
    const Eigen::Vector3d u = e.unitOrthogonal(), w = e.cross(u);
    struct Around {
      double angle;
      std::uint32_t face;
      Eigen::Vector3d into, normal;
    };
    std::vector<Around> around;
    for (std::uint32_t f : faces) {
      const Eigen::Vector3d n = faceNormal(mesh, f);
      const Eigen::Vector3d direction = goesForward(f, edge.first, edge.second) ? e : Eigen::Vector3d(-e);
      const Eigen::Vector3d into = n.cross(direction);  // the face lies to the left of its edges
      around.push_back({std::atan2(into.dot(w), into.dot(u)), f, into, n});
    }
    std::sort(around.begin(), around.end(), [](const Around& x, const Around& y) { return x.angle < y.angle; });
    for (std::size_t i = 0; i < around.size(); ++i) {
      const Around& x = around[i];
      const Around& y = around[(i + 1) % around.size()];
      if (x.normal.dot(e.cross(x.into)) < 0.0) {  // the wedge from x to y is solid
        partner[{edge, x.face}] = y.face;
        partner[{edge, y.face}] = x.face;
      }
    }
  }
  std::vector<std::vector<std::uint32_t>> faces_of(mesh.vertices.size());
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f)
    for (std::uint32_t v : mesh.faces[f]) faces_of[v].push_back(f);
  // Grouping reads the edges with the original vertex indices (the keys of `partner`), so the
  // copies are applied only once every vertex is grouped: renaming as we went broke the lookups
  // at the next split vertex on the same face and tore a closed mesh open.
  struct Rename {
    std::uint32_t face, from, to;
  };
  std::vector<Rename> renames;
  const std::size_t num_vertices = mesh.vertices.size();
  for (std::uint32_t v = 0; v < num_vertices; ++v) {
    // A face that lists v twice appears here once: the groups are of faces, not of corners.
    std::vector<std::uint32_t> fs = faces_of[v];
    std::sort(fs.begin(), fs.end());
    fs.erase(std::unique(fs.begin(), fs.end()), fs.end());
    if (fs.size() < 2) continue;
    const auto slot = [&fs](std::uint32_t f) {
      return static_cast<std::size_t>(std::lower_bound(fs.begin(), fs.end(), f) - fs.begin());
    };
    DisjointSets<std::size_t> fans(fs.size());
    for (std::uint32_t f : fs) {
      const auto& face = mesh.faces[f];
      for (std::size_t i = 0; i < face.size(); ++i) {
        if (face[i] != v) continue;
        for (std::uint32_t other : {face[(i + 1) % face.size()], face[(i + face.size() - 1) % face.size()]}) {
          const EdgeKey edge{std::min(v, other), std::max(v, other)};
          const auto it = partner.find({edge, f});
          if (it == partner.end()) continue;
          const std::size_t there = slot(it->second);
          if (there < fs.size() && fs[there] == it->second) fans.join(slot(f), there);
        }
      }
    }
    std::map<std::size_t, std::vector<std::uint32_t>> groups;
    for (std::uint32_t f : fs) groups[fans.find(slot(f))].push_back(f);
    if (groups.size() < 2) continue;
    bool first = true;
    for (const auto& [root, members] : groups) {
      if (first) {
        first = false;
        continue;
      }
      const auto copy = static_cast<std::uint32_t>(mesh.vertices.size());
      mesh.vertices.push_back(mesh.vertices[v]);
      for (std::uint32_t f : members) renames.push_back({f, v, copy});
    }
  }
  for (const Rename& r : renames)
    for (auto& index : mesh.faces[r.face])
      if (index == r.from) index = r.to;
}

}  // namespace

void insertTJunctionVertices(SurfaceMesh& mesh, double tol) {
  const std::size_t nv = mesh.vertices.size();
  std::vector<std::uint32_t> by_x(nv);
  std::iota(by_x.begin(), by_x.end(), 0u);
  std::sort(by_x.begin(), by_x.end(),
            [&](std::uint32_t a, std::uint32_t b) { return mesh.vertices[a].x() < mesh.vertices[b].x(); });
  std::vector<double> xs(nv);
  for (std::size_t i = 0; i < nv; ++i) xs[i] = mesh.vertices[by_x[i]].x();
  for (auto& face : mesh.faces) {
    std::vector<std::uint32_t> out;
    for (std::size_t i = 0; i < face.size(); ++i) {
      const std::uint32_t a = face[i], b = face[(i + 1) % face.size()];
      out.push_back(a);
      const Eigen::Vector3d& pa = mesh.vertices[a];
      const Eigen::Vector3d ab = mesh.vertices[b] - pa;
      const double length2 = ab.squaredNorm();
      if (length2 <= 0.0) continue;
      const double x_lo = std::min(pa.x(), mesh.vertices[b].x()) - tol, x_hi = std::max(pa.x(), mesh.vertices[b].x()) + tol;
      std::vector<std::pair<double, std::uint32_t>> inside;
      for (auto it = std::lower_bound(xs.begin(), xs.end(), x_lo); it != xs.end() && *it <= x_hi; ++it) {
        const std::uint32_t w = by_x[static_cast<std::size_t>(it - xs.begin())];
        if (w == a || w == b) continue;
        const double t = (mesh.vertices[w] - pa).dot(ab) / length2;
        if (t <= 0.0 || t >= 1.0) continue;
        if ((pa + t * ab - mesh.vertices[w]).norm() < tol) inside.emplace_back(t, w);
      }
      std::sort(inside.begin(), inside.end());
      for (const auto& [t, w] : inside) out.push_back(w);
    }
    face = std::move(out);
  }
}

void orientConsistently(SurfaceMesh& mesh) {
  std::map<EdgeKey, std::vector<std::uint32_t>> edge_faces;
  for (std::uint32_t f = 0; f < mesh.faces.size(); ++f) {
    const auto& face = mesh.faces[f];
    for (std::size_t i = 0; i < face.size(); ++i) {
      const std::uint32_t a = face[i], b = face[(i + 1) % face.size()];
      edge_faces[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  }
  auto traverses = [&](std::uint32_t f, std::uint32_t a, std::uint32_t b) {  // does f go a -> b?
    const auto& face = mesh.faces[f];
    for (std::size_t i = 0; i < face.size(); ++i)
      if (face[i] == a && face[(i + 1) % face.size()] == b) return true;
    return false;
  };
  std::vector<bool> visited(mesh.faces.size(), false);
  for (std::uint32_t seed = 0; seed < mesh.faces.size(); ++seed) {
    if (visited[seed]) continue;
    visited[seed] = true;
    std::vector<std::uint32_t> stack = {seed};
    while (!stack.empty()) {
      const std::uint32_t f = stack.back();
      stack.pop_back();
      const auto face = mesh.faces[f];
      for (std::size_t i = 0; i < face.size(); ++i) {
        const std::uint32_t a = face[i], b = face[(i + 1) % face.size()];
        const auto& neighbours = edge_faces[{std::min(a, b), std::max(a, b)}];
        if (neighbours.size() != 2) continue;  // do not walk across non-manifold edges
        const std::uint32_t g = neighbours[0] == f ? neighbours[1] : neighbours[0];
        if (visited[g]) continue;
        visited[g] = true;
        if (traverses(g, a, b)) std::reverse(mesh.faces[g].begin(), mesh.faces[g].end());
        stack.push_back(g);
      }
    }
  }
}

void cleanUpPolygonMesh(SurfaceMesh& mesh) {
  mergeCoplanarFaces(mesh);
  removeCollinearVertices(mesh);
  splitNonManifold(mesh);
}

MeshTopology finishAssembledMesh(SurfaceMesh& mesh) {
  // CGAL's output repeats vertices, and the cell complex computes shared corners more than once.
  weldVertices(mesh, 1e-7);
  orientConsistently(mesh);
  if (signedVolume(mesh) < 0.0) flipFaces(mesh);
  cleanUpPolygonMesh(mesh);
  return analyseTopology(mesh);
}

}  // namespace paco::detail
