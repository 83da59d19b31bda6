#include <paco/data/procedural.h>

#include "random.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>

#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Nef_polyhedron_3.h>
#include <CGAL/Polyhedron_3.h>
#include <CGAL/boost/graph/convert_nef_polyhedron_to_polygon_mesh.h>
#include <CGAL/convex_hull_3.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <vector>

namespace paco::data {
namespace {

using Exact = CGAL::Exact_predicates_exact_constructions_kernel;
using Nef = CGAL::Nef_polyhedron_3<Exact>;
using ExactPolyhedron = CGAL::Polyhedron_3<Exact>;
using ExactPoint = Exact::Point_3;
using OutPoint = CGAL::Exact_predicates_inexact_constructions_kernel::Point_3;

// Coordinates are drawn on a grid of 1/16: exact in double, so every input plane is exact.
constexpr double kGrid = 1.0 / 16.0;

double snap(double value) { return std::round(value / kGrid) * kGrid; }

/// Convex hull of points as an exact Nef polyhedron (every solid we combine is convex).
Nef convexSolid(const std::vector<Eigen::Vector3d>& points) {
  std::vector<ExactPoint> exact;
  exact.reserve(points.size());
  for (const auto& p : points) exact.emplace_back(p.x(), p.y(), p.z());
  ExactPolyhedron hull;
  CGAL::convex_hull_3(exact.begin(), exact.end(), hull);
  return Nef(hull);
}

Nef box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < 8; ++i)
    corners.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
  return convexSolid(corners);
}

/// Extrusion of a convex polygon (in the plane of axes (u, v), at w in [w0, w1]).
Nef convexPrism(const std::vector<Eigen::Vector2d>& polygon, double w0, double w1, int axis) {
  std::vector<Eigen::Vector3d> points;
  for (const auto& q : polygon)
    for (double w : {w0, w1}) {
      Eigen::Vector3d p;
      p[(axis + 1) % 3] = q.x();
      p[(axis + 2) % 3] = q.y();
      p[axis] = w;
      points.push_back(p);
    }
  return convexSolid(points);
}

/// Regular n-gon of circumradius r around c, snapped to the grid (stays convex for r >= 3 cells).
std::vector<Eigen::Vector2d> regularPolygon(const Eigen::Vector2d& c, double r, int n, double phase) {
  std::vector<Eigen::Vector2d> polygon;
  for (int k = 0; k < n; ++k) {
    const double a = phase + 2.0 * kPi * k / n;
    polygon.emplace_back(snap(c.x() + r * std::cos(a)), snap(c.y() + r * std::sin(a)));
  }
  return polygon;
}

SurfaceMesh toSurfaceMesh(const Nef& nef) {
  std::vector<OutPoint> points;
  std::vector<std::vector<std::size_t>> polygons;
  CGAL::convert_nef_polyhedron_to_polygon_soup(nef, points, polygons, true);
  SurfaceMesh mesh;
  for (const auto& p : points) mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  for (const auto& polygon : polygons) mesh.faces.emplace_back(polygon.begin(), polygon.end());
  weldVertices(mesh, 0.0);  // shells share no vertex; merge exact duplicates only
  if (signedVolume(mesh) < 0.0) flipFaces(mesh);
  sortMeshCanonically(mesh);  // Nef's order follows heap addresses: the same seed, other bytes
  return mesh;
}

/// Random size in [lo, hi] on the grid.
double gridValue(detail::Rng& rng, double lo, double hi) { return snap(rng.uniform(lo, hi)); }

// Features cut from a stock box [-sx, sx] x [-sy, sy] x [-sz, sz] (top face at z = sz).
Nef featuredBox(detail::Rng& rng) {
  const Eigen::Vector3d half(gridValue(rng, 0.75, 1.5), gridValue(rng, 0.75, 1.5), gridValue(rng, 0.5, 1.25));
  Nef part = box(-half, half);
  const int features = rng.integer(1, 4);
  for (int f = 0; f < features; ++f) {
    const int type = rng.integer(0, 4);
    const double margin = 0.25;
    switch (type) {
      case 0: {  // rectangular pocket, blind, from the top
        const double wx = gridValue(rng, 0.25, half.x()), wy = gridValue(rng, 0.25, half.y());
        const double cx = gridValue(rng, -half.x() + wx / 2 + margin, half.x() - wx / 2 - margin);
        const double cy = gridValue(rng, -half.y() + wy / 2 + margin, half.y() - wy / 2 - margin);
        const double depth = gridValue(rng, 0.25, half.z());
        part -= box({cx - wx / 2, cy - wy / 2, half.z() - depth}, {cx + wx / 2, cy + wy / 2, half.z() + 1});
        break;
      }
      case 1: {  // step: a corner strip removed along x
        const double wy = gridValue(rng, 0.25, half.y()), depth = gridValue(rng, 0.25, half.z());
        const double side = rng.uniform() < 0.5 ? -1.0 : 1.0;
        const double y0 = side > 0 ? half.y() - wy : -half.y() - 1, y1 = side > 0 ? half.y() + 1 : -half.y() + wy;
        part -= box({-half.x() - 1, y0, half.z() - depth}, {half.x() + 1, y1, half.z() + 1});
        break;
      }
      case 2: {  // slot: a channel across the top along y
        const double w = gridValue(rng, 0.25, 0.5), depth = gridValue(rng, 0.25, half.z());
        const double cx = gridValue(rng, -half.x() + w / 2 + margin, half.x() - w / 2 - margin);
        part -= box({cx - w / 2, -half.y() - 1, half.z() - depth}, {cx + w / 2, half.y() + 1, half.z() + 1});
        break;
      }
      case 3: {  // chamfer of a vertical or top edge, by a triangular prism along the edge
        const double c = gridValue(rng, 0.125, 0.5);
        const double sx = rng.uniform() < 0.5 ? -1.0 : 1.0, sy = rng.uniform() < 0.5 ? -1.0 : 1.0;
        if (rng.uniform() < 0.5) {  // vertical edge at (sx*hx, sy*hy)
          const Eigen::Vector2d corner(sx * half.x(), sy * half.y());
          part -= convexPrism({corner + Eigen::Vector2d(sx * (-c - 0.5), sy * 0.5),
                               corner + Eigen::Vector2d(sx * 0.5, sy * (-c - 0.5)),
                               corner + Eigen::Vector2d(sx * 0.5, sy * 0.5)},
                              -half.z() - 1, half.z() + 1, 2);
        } else {  // top edge along y at x = sx*hx (prism axis y: polygon in (z, x))
          part -= convexPrism({{half.z() - c - 0.5, sx * (half.x() + 0.5)}, {half.z() + 0.5, sx * (half.x() - c - 0.5)},
                               {half.z() + 0.5, sx * (half.x() + 0.5)}},
                              -half.y() - 1, half.y() + 1, 1);
        }
        break;
      }
      default: {  // through-hole of polygonal section along z
        const int n = rng.integer(3, 8);
        const double r = gridValue(rng, 0.25, 0.5);
        const double cx = gridValue(rng, -half.x() + r + margin, half.x() - r - margin);
        const double cy = gridValue(rng, -half.y() + r + margin, half.y() - r - margin);
        part -= convexPrism(regularPolygon({cx, cy}, r, n, rng.uniform(0.0, kPi)), -half.z() - 1, half.z() + 1, 2);
        break;
      }
    }
  }
  return part;
}

Nef prismPart(detail::Rng& rng) {
  const int n = rng.integer(3, 8);
  const double r = gridValue(rng, 1.0, 1.75), h = gridValue(rng, 0.5, 2.0);
  Nef part = convexPrism(regularPolygon({0, 0}, r, n, rng.uniform(0.0, kPi)), -h / 2, h / 2, 2);
  if (rng.uniform() < 0.5)  // a through-hole of polygonal section
    part -= convexPrism(regularPolygon({0, 0}, gridValue(rng, 0.25, 0.5 * r), rng.integer(3, 8), 0.0), -h, h, 2);
  return part;
}

// L, T, U sections in the xy-plane, extruded along z; arms have thickness t.
Nef sectionPart(detail::Rng& rng, PartKind kind) {
  const double w = gridValue(rng, 1.0, 2.0), hgt = gridValue(rng, 1.0, 2.0), t = gridValue(rng, 0.25, 0.5 * std::min(w, hgt));
  const double z = gridValue(rng, 0.5, 2.0) / 2;
  Nef part;
  switch (kind) {
    case PartKind::LExtrusion:
      part = box({-w / 2, -hgt / 2, -z}, {-w / 2 + t, hgt / 2, z}) + box({-w / 2, -hgt / 2, -z}, {w / 2, -hgt / 2 + t, z});
      break;
    case PartKind::TExtrusion:
      part = box({-w / 2, hgt / 2 - t, -z}, {w / 2, hgt / 2, z}) + box({-t / 2, -hgt / 2, -z}, {t / 2, hgt / 2, z});
      break;
    default:  // U
      part = box({-w / 2, -hgt / 2, -z}, {w / 2, -hgt / 2 + t, z}) + box({-w / 2, -hgt / 2, -z}, {-w / 2 + t, hgt / 2, z}) +
             box({w / 2 - t, -hgt / 2, -z}, {w / 2, hgt / 2, z});
      break;
  }
  if (rng.uniform() < 0.5) {  // a chamfer along the extrusion on the outer corner at (-w/2, -hgt/2)
    const double c = snap(0.5 * t);
    const Eigen::Vector2d corner(-w / 2, -hgt / 2);
    part -= convexPrism({corner + Eigen::Vector2d(c + 0.5, -0.5), corner + Eigen::Vector2d(-0.5, c + 0.5),
                         corner + Eigen::Vector2d(-0.5, -0.5)},
                        -z - 1, z + 1, 2);
  }
  return part;
}

Nef boxUnion(detail::Rng& rng) {
  Eigen::Vector3d lo(-gridValue(rng, 0.5, 1.0), -gridValue(rng, 0.5, 1.0), -gridValue(rng, 0.5, 1.0));
  Eigen::Vector3d hi = -lo;
  Nef part = box(lo, hi);
  const int more = rng.integer(1, 3);
  for (int b = 0; b < more; ++b) {
    // A box that overlaps the previous one by a margin, so the union stays one solid.
    Eigen::Vector3d nlo, nhi;
    for (int a = 0; a < 3; ++a) {
      const double size = gridValue(rng, 0.5, 1.5);
      const double start = gridValue(rng, lo[a] - size + 0.25, hi[a] - 0.25);
      nlo[a] = start;
      nhi[a] = start + size;
    }
    part += box(nlo, nhi);
    lo = nlo;
    hi = nhi;
  }
  return part;
}

}  // namespace

std::string toString(PartKind kind) {
  switch (kind) {
    case PartKind::FeaturedBox: return "featured-box";
    case PartKind::Prism: return "prism";
    case PartKind::LExtrusion: return "L-extrusion";
    case PartKind::TExtrusion: return "T-extrusion";
    case PartKind::UExtrusion: return "U-extrusion";
    case PartKind::BoxUnion: return "box-union";
  }
  return "unknown";
}

PartKind partKindOf(std::uint64_t seed) {
  // Featured boxes (the MFCAD-like family) are drawn half of the time.
  const std::uint64_t r = detail::mixSeed(seed, 0) % 10;
  if (r < 5) return PartKind::FeaturedBox;
  static const PartKind others[5] = {PartKind::Prism, PartKind::LExtrusion, PartKind::TExtrusion,
                                     PartKind::UExtrusion, PartKind::BoxUnion};
  return others[r - 5];
}

SurfaceMesh generatePart(std::uint64_t seed) { return generatePart(seed, partKindOf(seed)); }

SurfaceMesh generatePart(std::uint64_t seed, PartKind kind) {
  // A draw can (rarely) give a solid that is not a manifold, e.g. boxes touching along an edge:
  // then draw again from the next sub-seed. Deterministic either way.
  for (std::uint64_t attempt = 0; attempt < 16; ++attempt) {
    detail::Rng rng(detail::mixSeed(seed, 1 + attempt));
    Nef nef;
    switch (kind) {
      case PartKind::FeaturedBox: nef = featuredBox(rng); break;
      case PartKind::Prism: nef = prismPart(rng); break;
      case PartKind::BoxUnion: nef = boxUnion(rng); break;
      default: nef = sectionPart(rng, kind); break;
    }
    if (nef.is_empty() || !nef.is_simple()) continue;
    SurfaceMesh mesh = toSurfaceMesh(nef);
    const MeshTopology topology = analyseTopology(mesh);
    if (mesh.empty() || !topology.isClosedManifold() || topology.components != 1 || !(signedVolume(mesh) > 0.0)) continue;
    return mesh;
  }
  throw InvalidInputError("generatePart: no valid " + toString(kind) + " part for seed " + std::to_string(seed));
}

std::string proceduralPartName(std::size_t index) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "proc-%06zu", index);
  return buffer;
}

}  // namespace paco::data
