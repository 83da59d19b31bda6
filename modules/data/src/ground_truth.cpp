#include <paco/data/ground_truth.h>

#include <paco/common/angles.h>
#include <paco/common/error.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <sstream>
#include <unordered_map>

namespace paco::data {
namespace {

struct TriangleGeometry {
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  double area = 0.0;
};

std::string number(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

GroundTruth extractGroundTruth(const SurfaceMesh& input, const GroundTruthOptions& options) {
  if (!(options.normal_tolerance_deg > 0.0) || !(options.offset_tolerance > 0.0))
    throw InvalidInputError("extractGroundTruth: normal and offset tolerances must be > 0");
  if (input.empty()) throw InvalidInputError("mesh has no faces");
  input.validate("mesh");

  GroundTruth gt;
  gt.mesh = triangulated(input);  // ear clipping: CAD faces are often not convex
  Eigen::Vector3d lo, hi;
  boundingBox(gt.mesh, lo, hi);
  gt.diagonal = (hi - lo).norm();
  if (!(gt.diagonal > 0.0)) throw InvalidInputError("mesh has a zero bounding-box diagonal");

  if (options.require_closed) {
    const MeshTopology topology = analyseTopology(gt.mesh);
    if (topology.boundary_edges > 0)
      throw InvalidInputError("mesh is not closed: " + std::to_string(topology.boundary_edges) +
                              " boundary edges (holes in the surface)");
    if (topology.non_manifold_edges > 0)
      throw InvalidInputError("mesh is not manifold: " + std::to_string(topology.non_manifold_edges) +
                              " edges are shared by more than two faces");
    if (topology.inconsistent_edges > 0)
      throw InvalidInputError("mesh is not consistently oriented: " +
                              std::to_string(topology.inconsistent_edges) + " edges");
    // A closed, oriented mesh turned inside out: flip it so that normals point outward.
    if (signedVolume(gt.mesh) < 0.0) flipFaces(gt.mesh);
  }

  const std::size_t n = gt.mesh.faces.size();
  std::vector<TriangleGeometry> geometry(n);
  const double degenerate_area = 1e-14 * gt.diagonal * gt.diagonal;
  for (std::size_t t = 0; t < n; ++t) {
    const auto& f = gt.mesh.faces[t];
    const Eigen::Vector3d& a = gt.mesh.vertices[f[0]];
    const Eigen::Vector3d& b = gt.mesh.vertices[f[1]];
    const Eigen::Vector3d& c = gt.mesh.vertices[f[2]];
    const Eigen::Vector3d cross = (b - a).cross(c - a);
    geometry[t].area = 0.5 * cross.norm();
    geometry[t].centroid = (a + b + c) / 3.0;
    if (geometry[t].area > degenerate_area) geometry[t].normal = cross.normalized();
  }

  // Greedy grouping, largest triangles first: their normals are the most accurate, so each group
  // is anchored on a reliable plane. A triangle joins a group when its normal is within the angle
  // tolerance and all three vertices are within the offset tolerance of the anchor plane.
  // Slivers (height below 1e-3 of the diagonal) come last: rounded coordinates make their normals
  // unreliable, so one that matches no group by normal joins the group whose plane its vertices
  // lie on (within the offset tolerance), instead of making a spurious plane of no area.
  std::vector<char> sliver(n, 0);
  for (std::size_t t = 0; t < n; ++t) {
    const auto& f = gt.mesh.faces[t];
    double longest = 0;
    for (int k = 0; k < 3; ++k)
      longest = std::max(longest, (gt.mesh.vertices[f[k]] - gt.mesh.vertices[f[(k + 1) % 3]]).norm());
    sliver[t] = longest > 0 && 2.0 * geometry[t].area / longest < 1e-3 * gt.diagonal;
  }
  std::vector<std::uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](std::uint32_t x, std::uint32_t y) {
    if (sliver[x] != sliver[y]) return sliver[x] < sliver[y];
    return geometry[x].area > geometry[y].area;
  });
  const double cos_tolerance = std::cos(degreesToRadians(options.normal_tolerance_deg));
  const double offset_tolerance = options.offset_tolerance * gt.diagonal;
  std::vector<Plane> anchors;
  gt.triangle_face.assign(n, -1);
  auto vertexDistance = [&](const Plane& plane, std::uint32_t t) {
    double worst = 0;
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, std::abs(plane.signedDistance(gt.mesh.vertices[gt.mesh.faces[t][k]])));
    return worst;
  };
  for (std::uint32_t t : order) {
    if (geometry[t].area <= degenerate_area) continue;
    int found = -1;
    for (std::size_t g = 0; g < anchors.size() && found < 0; ++g)
      if (anchors[g].normal.dot(geometry[t].normal) >= cos_tolerance && vertexDistance(anchors[g], t) <= offset_tolerance)
        found = static_cast<int>(g);
    if (found < 0 && sliver[t]) {
      double best = offset_tolerance;
      for (std::size_t g = 0; g < anchors.size(); ++g) {
        const double d = vertexDistance(anchors[g], t);
        if (anchors[g].normal.dot(geometry[t].normal) > 0.0 && d <= best) best = d, found = static_cast<int>(g);
      }
    }
    if (found < 0) {
      found = static_cast<int>(anchors.size());
      anchors.push_back(Plane::fromPointAndNormal(geometry[t].centroid, geometry[t].normal));
    }
    gt.triangle_face[t] = found;
  }

  // Refit each plane to all of its triangles (area-weighted normal and centroid).
  const std::size_t groups = anchors.size();
  std::vector<Eigen::Vector3d> normal_sum(groups, Eigen::Vector3d::Zero()), centroid_sum(groups, Eigen::Vector3d::Zero());
  std::vector<double> area(groups, 0.0);
  for (std::size_t t = 0; t < n; ++t) {
    const int g = gt.triangle_face[t];
    if (g < 0) continue;
    normal_sum[g] += geometry[t].area * geometry[t].normal;
    centroid_sum[g] += geometry[t].area * geometry[t].centroid;
    area[g] += geometry[t].area;
  }
  std::vector<std::uint32_t> by_area(groups);
  std::iota(by_area.begin(), by_area.end(), 0u);
  std::stable_sort(by_area.begin(), by_area.end(), [&](std::uint32_t x, std::uint32_t y) { return area[x] > area[y]; });
  std::vector<int> new_index(groups);
  gt.faces.resize(groups);
  for (std::size_t k = 0; k < groups; ++k) {
    const std::uint32_t g = by_area[k];
    new_index[g] = static_cast<int>(k);
    gt.faces[k].plane = Plane::fromPointAndNormal(centroid_sum[g] / area[g], normal_sum[g].normalized());
    gt.faces[k].area = area[g];
  }
  for (std::size_t t = 0; t < n; ++t)
    if (gt.triangle_face[t] >= 0) {
      gt.triangle_face[t] = new_index[gt.triangle_face[t]];
      gt.faces[gt.triangle_face[t]].triangles.push_back(static_cast<std::uint32_t>(t));
    }

  if (gt.faces.empty()) throw InvalidInputError("mesh has no triangle of non-zero area");
  if (static_cast<int>(gt.faces.size()) > options.max_planes)
    throw InvalidInputError("not plane-only: " + std::to_string(gt.faces.size()) + " planes (more than " +
                            std::to_string(options.max_planes) + "), like a tessellated curved surface");

  // Plane-only test. A tessellated curved surface is a strip of planes, each meeting the next at
  // a shallow crease: so count the planes with shallow creases to at least two other planes.
  // (A single shallow slope between two faces has one such plane, and is accepted.)
  std::unordered_map<std::uint64_t, int> edge_face;  // undirected edge -> plane of the first triangle seen
  edge_face.reserve(3 * n);
  std::vector<std::vector<int>> shallow_neighbours(gt.faces.size());
  const double cos_shallow = std::cos(degreesToRadians(options.shallow_crease_deg));
  for (std::size_t t = 0; t < n; ++t) {
    const int g = gt.triangle_face[t];
    if (g < 0) continue;
    const auto& f = gt.mesh.faces[t];
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t a = std::min(f[k], f[(k + 1) % 3]), b = std::max(f[k], f[(k + 1) % 3]);
      const auto [it, inserted] = edge_face.emplace((a << 32) | b, g);
      const int h = it->second;
      if (inserted || h == g) continue;
      if (gt.faces[g].plane.normal.dot(gt.faces[h].plane.normal) > cos_shallow) {
        shallow_neighbours[g].push_back(h);
        shallow_neighbours[h].push_back(g);
      }
    }
  }
  int strip_planes = 0;
  for (auto& neighbours : shallow_neighbours) {
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
    strip_planes += neighbours.size() >= 2;
  }
  if (strip_planes >= options.max_shallow_crease_planes)
    throw InvalidInputError("not plane-only: " + std::to_string(strip_planes) + " of " +
                            std::to_string(gt.faces.size()) + " planes meet two others at shallow creases (< " +
                            number(options.shallow_crease_deg) + " deg), like a tessellated curved surface");
  return gt;
}

GtPoints sampleGroundTruth(const GroundTruth& gt, std::size_t count, std::uint64_t seed) {
  const SurfaceSample sample = sampleSurface(gt.mesh, count, seed);
  GtPoints out;
  out.points = sample.points;
  out.normals.reserve(count);
  out.labels.reserve(count);
  for (std::size_t i = 0; i < sample.faces.size(); ++i) {
    int label = gt.triangle_face[sample.faces[i]];
    if (label < 0) {  // a (numerically) degenerate triangle: take the nearest plane
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t g = 0; g < gt.faces.size(); ++g) {
        const double d = std::abs(gt.faces[g].plane.signedDistance(sample.points[i]));
        if (d < best) best = d, label = static_cast<int>(g);
      }
    }
    out.labels.push_back(label);
    out.normals.push_back(gt.faces[label].plane.normal);
  }
  return out;
}

}  // namespace paco::data
