#include "shape_primitives.h"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/intersections.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <iterator>
#include <map>
#include <numeric>

namespace paco::test {

SurfaceMesh bothMeshes(const SurfaceMesh& a, const SurfaceMesh& b) {
  SurfaceMesh both = a;
  const auto offset = static_cast<std::uint32_t>(a.vertices.size());
  both.vertices.insert(both.vertices.end(), b.vertices.begin(), b.vertices.end());
  for (auto face : b.faces) {
    for (auto& v : face) v += offset;
    both.faces.push_back(face);
  }
  return both;
}

std::size_t crossingFacePairs(const SurfaceMesh& mesh) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  // Vertices at one position share one index, so that faces meeting there count as adjacent.
  std::map<std::array<double, 3>, std::uint32_t> index_at;
  std::vector<std::uint32_t> same(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v) {
    const Eigen::Vector3d& p = mesh.vertices[v];
    same[v] = index_at.emplace(std::array<double, 3>{p.x(), p.y(), p.z()}, static_cast<std::uint32_t>(v)).first->second;
  }
  const std::size_t nf = mesh.faces.size();
  std::vector<std::vector<Kernel::Triangle_3>> triangles(nf);
  std::vector<std::vector<std::uint32_t>> corners(nf);
  std::vector<Eigen::AlignedBox3d> boxes(nf);
  auto point = [&](std::uint32_t v) {
    const Eigen::Vector3d& p = mesh.vertices[v];
    return Kernel::Point_3(p.x(), p.y(), p.z());
  };
  for (std::size_t f = 0; f < nf; ++f) {
    std::vector<std::vector<std::uint32_t>> pieces;
    paco::triangulateFace(mesh, f, pieces);
    for (const auto& t : pieces) {
      const Kernel::Triangle_3 triangle(point(t[0]), point(t[1]), point(t[2]));
      if (!triangle.is_degenerate()) triangles[f].push_back(triangle);
    }
    for (std::uint32_t v : mesh.faces[f]) {
      corners[f].push_back(same[v]);
      boxes[f].extend(mesh.vertices[v]);
    }
    std::sort(corners[f].begin(), corners[f].end());
  }
  std::size_t crossing = 0;
  for (std::size_t a = 0; a < nf; ++a)
    for (std::size_t b = a + 1; b < nf; ++b) {
      if (!boxes[a].intersects(boxes[b])) continue;
      std::vector<std::uint32_t> shared;
      std::set_intersection(corners[a].begin(), corners[a].end(), corners[b].begin(), corners[b].end(),
                            std::back_inserter(shared));
      if (!shared.empty()) continue;
      bool hit = false;
      for (const auto& s : triangles[a])
        for (const auto& t : triangles[b]) hit = hit || CGAL::do_intersect(s, t);
      crossing += hit;
    }
  return crossing;
}

double diagonalOf(const paco::SurfaceMesh& mesh) {
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  return (hi - lo).norm();
}

// The distinct planes of a mesh's faces (coplanar faces grouped), outward oriented.
std::vector<paco::Plane> facePlanes(const paco::SurfaceMesh& mesh, std::vector<int>* face_plane, double angle_cosine,
                                    double offset_fraction) {
  std::vector<paco::Plane> planes;
  const double tol = offset_fraction * diagonalOf(mesh);
  if (face_plane) face_plane->assign(mesh.faces.size(), -1);
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3d n = paco::faceNormal(mesh, f);
    const paco::Plane plane = paco::Plane::fromPointAndNormal(mesh.vertices[mesh.faces[f][0]], n);
    int found = -1;
    for (std::size_t k = 0; k < planes.size() && found < 0; ++k)
      if (planes[k].normal.dot(n) > angle_cosine && std::abs(planes[k].offset - plane.offset) < tol) found = static_cast<int>(k);
    if (found < 0) {
      found = static_cast<int>(planes.size());
      planes.push_back(plane);
    }
    if (face_plane) (*face_plane)[f] = found;
  }
  return planes;
}

// Exact primitives of a shape: points sampled on its faces, grouped by face plane.
std::vector<paco::PlanarPrimitive> primitivesOf(const paco::SurfaceMesh& mesh, std::size_t samples, double angle_cosine,
                                               double offset_fraction) {
  std::vector<int> face_plane;
  const auto planes = facePlanes(mesh, &face_plane, angle_cosine, offset_fraction);
  const paco::SurfaceSample sample = paco::sampleSurface(mesh, samples, 7);
  std::vector<paco::PlanarPrimitive> primitives(planes.size());
  for (std::size_t k = 0; k < planes.size(); ++k) primitives[k].plane = planes[k];
  for (std::size_t i = 0; i < sample.points.size(); ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(sample.points[i].x());
    p.y = static_cast<float>(sample.points[i].y());
    p.z = static_cast<float>(sample.points[i].z());
    p.normal_x = static_cast<float>(sample.normals[i].x());
    p.normal_y = static_cast<float>(sample.normals[i].y());
    p.normal_z = static_cast<float>(sample.normals[i].z());
    primitives[face_plane[sample.faces[i]]].points.push_back(p);
  }
  return primitives;
}

// Planar faces after merging edge-adjacent coplanar polygons.
std::size_t countPlanarRegions(const paco::SurfaceMesh& mesh) {
  std::vector<int> face_plane;
  facePlanes(mesh, &face_plane);
  std::vector<std::size_t> parent(mesh.faces.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::function<std::size_t(std::size_t)> find = [&](std::size_t x) { return parent[x] == x ? x : parent[x] = find(parent[x]); };
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::vector<std::size_t>> edges;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    for (std::size_t i = 0; i < mesh.faces[f].size(); ++i) {
      std::uint32_t a = mesh.faces[f][i], b = mesh.faces[f][(i + 1) % mesh.faces[f].size()];
      edges[{std::min(a, b), std::max(a, b)}].push_back(f);
    }
  for (const auto& [e, fs] : edges)
    for (std::size_t i = 1; i < fs.size(); ++i)
      if (face_plane[fs[i]] == face_plane[fs[0]]) parent[find(fs[i])] = find(fs[0]);
  std::size_t regions = 0;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) regions += find(f) == f;
  return regions;
}

PlanarPrimitive coveredAxisPlane(int axis, double at, double sign, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
                                 int count, std::mt19937& random) {
  const Eigen::Vector3d n = sign * Eigen::Vector3d::Unit(axis);
  PlanarPrimitive primitive;
  primitive.plane = paco::Plane(n, -n[axis] * at);
  for (int i = 0; i < count; ++i) {
    Eigen::Vector3d x;
    for (int k = 0; k < 3; ++k) x[k] = std::uniform_real_distribution<double>(lo[k], hi[k])(random);
    x[axis] = at;
    pcl::PointNormal p;
    p.getVector3fMap() = x.cast<float>();
    p.getNormalVector3fMap() = n.cast<float>();
    primitive.points.push_back(p);
  }
  return primitive;
}

std::vector<PlanarPrimitive> latticeOfCoveredPlanes(int inner, unsigned seed) {
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> offset(0.05, 0.95);
  std::vector<PlanarPrimitive> primitives;
  for (int axis = 0; axis < 3; ++axis) {
    std::vector<double> offsets = {0.0, 1.0};
    for (int k = 0; k < inner; ++k) offsets.push_back(offset(random));
    for (double at : offsets)
      primitives.push_back(
          coveredAxisPlane(axis, at, 1.0, Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones(), 150, random));
  }
  return primitives;
}

std::vector<PlanarPrimitive> primitivesFacingInwards(const SurfaceMesh& mesh, std::size_t samples) {
  std::vector<PlanarPrimitive> primitives = primitivesOf(mesh, samples);
  for (auto& primitive : primitives) {
    primitive.plane = primitive.plane.flipped();
    for (auto& p : primitive.points) p.getNormalVector3fMap() = primitive.plane.normal.cast<float>();
  }
  return primitives;
}

}  // namespace paco::test
