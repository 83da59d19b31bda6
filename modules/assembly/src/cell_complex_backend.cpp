// The "cell-complex" backend (the idea behind KSR, COMPOD and abspy): an adaptive binary space
// partition of the enlarged bounding box by the primitives' planes, inside/outside labelling of
// the convex cells by an s-t min-cut, and the boundary between the labels as the mesh.
//
// Geometry is in doubles in the normalised frame (diagonal 1) with explicit tolerances: a vertex
// within kOnPlane of a plane is on it, and cells are only split by planes that leave vertices
// further than that on both sides. Shared corners computed twice differ by ~1e-15 and are welded.
#include "backends.h"
#include "mesh_cleanup.h"

#include <paco/common/disjoint_sets.h>
#include <paco/common/progress.h>

// Boost.Graph's edge iterators trip GCC's -Wmaybe-uninitialized after inlining (a false positive
// inside Boost, reported at Boost's lines).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <boost/graph/adjacency_list.hpp>
#include <boost/graph/boykov_kolmogorov_max_flow.hpp>
#pragma GCC diagnostic pop

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <vector>

namespace paco::detail {
namespace {

constexpr double kOnPlane = 1e-9;      // classification tolerance (normalised units)
constexpr double kMinArea = 1e-14;     // faces smaller than this are dropped
constexpr double kVoteOffset = 1e-6;   // how far off its plane a point is moved to find its cells
constexpr double kWeldTolerance = 1e-8;
// An empty labelling is retried with the smoothness halved up to this many times (down to 1/64).
constexpr int kSmoothnessHalvings = 6;

struct Face {
  std::vector<Eigen::Vector3d> polygon;  // counter-clockwise seen from outside the cell
  int plane = -1;                        // index into the plane list (primitives, then box planes)
  int sign = 1;                          // +1: outward normal == plane normal, -1: opposite
};

struct Cell {
  std::vector<Face> faces;
};

struct BspNode {
  int plane = -1;  // -1 for a leaf
  int negative = -1, positive = -1;
  int cell = -1;   // leaf: index of the cell
};

// An orthonormal basis (u, v) of a plane with u x v = n.
struct PlaneFrame {
  Eigen::Vector3d origin, u, v, n;
  explicit PlaneFrame(const Plane& plane) : origin(plane.foot()), n(plane.normal) {
    const Eigen::Vector3d helper = std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
    u = n.cross(helper).normalized();
    v = n.cross(u);
  }
  Eigen::Vector2d project(const Eigen::Vector3d& x) const { return {(x - origin).dot(u), (x - origin).dot(v)}; }
};

double cross2(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

double polygonArea2d(const std::vector<Eigen::Vector2d>& p) {
  double a = 0.0;
  for (std::size_t i = 0; i < p.size(); ++i) a += cross2(p[i], p[(i + 1) % p.size()]);
  return 0.5 * a;
}

double polygonArea3d(const std::vector<Eigen::Vector3d>& p) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) n += p[i].cross(p[(i + 1) % p.size()]);
  return 0.5 * n.norm();
}

// Andrew's monotone chain; counter-clockwise, no collinear points.
std::vector<Eigen::Vector2d> convexHull(std::vector<Eigen::Vector2d> points) {
  std::sort(points.begin(), points.end(),
            [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y()); });
  if (points.size() < 3) return points;
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross2(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0) --k;
    hull[k++] = points[i];
  }
  for (std::size_t i = points.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && cross2(hull[k - 1] - hull[k - 2], points[i] - hull[k - 2]) <= 0) --k;
    hull[k++] = points[i];
  }
  hull.resize(k - 1);
  return hull;
}

// Separating-axis test of two convex 2-D polygons: true when they come closer than `margin`.
bool convexPolygonsWithin(const std::vector<Eigen::Vector2d>& a, const std::vector<Eigen::Vector2d>& b, double margin) {
  auto separated_along_edges = [&](const std::vector<Eigen::Vector2d>& edges_of) {
    for (std::size_t i = 0; i < edges_of.size(); ++i) {
      const Eigen::Vector2d e = edges_of[(i + 1) % edges_of.size()] - edges_of[i];
      if (e.norm() < 1e-15) continue;
      const Eigen::Vector2d axis = Eigen::Vector2d(-e.y(), e.x()).normalized();
      double a_min = 1e300, a_max = -1e300, b_min = 1e300, b_max = -1e300;
      for (const auto& p : a) a_min = std::min(a_min, p.dot(axis)), a_max = std::max(a_max, p.dot(axis));
      for (const auto& p : b) b_min = std::min(b_min, p.dot(axis)), b_max = std::max(b_max, p.dot(axis));
      if (a_min > b_max + margin || b_min > a_max + margin) return true;
    }
    return false;
  };
  return !separated_along_edges(a) && !separated_along_edges(b);
}

// Where a primitive's plane may split cells: the convex hull of its points in the plane.
struct Extent {
  PlaneFrame frame;
  std::vector<Eigen::Vector2d> hull;
  double area = 0.0;
};

Extent makeExtent(const PlanarPrimitive& primitive) {
  Extent extent{PlaneFrame(primitive.plane), {}, 0.0};
  std::vector<Eigen::Vector2d> projected;
  projected.reserve(primitive.points.size());
  for (const auto& p : primitive.points) projected.push_back(extent.frame.project(Eigen::Vector3d(p.x, p.y, p.z)));
  extent.hull = convexHull(projected);
  extent.area = extent.hull.size() >= 3 ? polygonArea2d(extent.hull) : 0.0;
  if (extent.hull.size() < 3) {  // collinear points: use their bounding rectangle, slightly widened
    Eigen::Vector2d lo = projected.front(), hi = projected.front();
    for (const auto& q : projected) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
    lo.array() -= 1e-6;
    hi.array() += 1e-6;
    extent.hull = {lo, {hi.x(), lo.y()}, hi, {lo.x(), hi.y()}};
  }
  return extent;
}

// Clips a polygon to the side of `plane` given by `side` (-1: n.x + d <= 0, +1: >= 0); vertices
// within kOnPlane of the plane are kept on both sides.
std::vector<Eigen::Vector3d> clipPolygon(const std::vector<Eigen::Vector3d>& polygon, const std::vector<double>& s,
                                         int side) {
  std::vector<Eigen::Vector3d> out;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t j = (i + 1) % n;
    const double si = side * s[i], sj = side * s[j];
    if (si >= -kOnPlane) out.push_back(polygon[i]);
    if ((si > kOnPlane && sj < -kOnPlane) || (si < -kOnPlane && sj > kOnPlane))
      out.push_back(polygon[i] + (polygon[j] - polygon[i]) * (s[i] / (s[i] - s[j])));
  }
  return out;
}

// Splits `cell` by `plane` (index `plane_index`). Returns false when the plane does not cross the
// cell's interior or the cross-section does not reach `extent` (then nothing is changed).
bool splitCell(const Cell& cell, const Plane& plane, int plane_index, const Extent* extent, double margin,
               Cell& negative, Cell& positive) {
  bool below = false, above = false;
  for (const auto& f : cell.faces)
    for (const auto& x : f.polygon) {
      const double s = plane.signedDistance(x);
      below |= s < -kOnPlane;
      above |= s > kOnPlane;
    }
  if (!below || !above) return false;

  // The cross-section: vertices on the plane and edge crossings, ordered around their centroid.
  std::vector<Eigen::Vector3d> section;
  std::vector<std::vector<double>> distances(cell.faces.size());
  for (std::size_t fi = 0; fi < cell.faces.size(); ++fi) {
    const auto& poly = cell.faces[fi].polygon;
    auto& s = distances[fi];
    s.resize(poly.size());
    for (std::size_t i = 0; i < poly.size(); ++i) s[i] = plane.signedDistance(poly[i]);
    for (std::size_t i = 0; i < poly.size(); ++i) {
      const std::size_t j = (i + 1) % poly.size();
      if (std::abs(s[i]) <= kOnPlane) section.push_back(poly[i]);
      if ((s[i] > kOnPlane && s[j] < -kOnPlane) || (s[i] < -kOnPlane && s[j] > kOnPlane))
        section.push_back(poly[i] + (poly[j] - poly[i]) * (s[i] / (s[i] - s[j])));
    }
  }
  std::vector<Eigen::Vector3d> unique;
  for (const auto& x : section) {
    bool seen = false;
    for (const auto& y : unique) seen |= (x - y).squaredNorm() < kWeldTolerance * kWeldTolerance;
    if (!seen) unique.push_back(x);
  }
  if (unique.size() < 3) return false;
  const PlaneFrame frame(plane);
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& x : unique) centroid += x;
  centroid /= static_cast<double>(unique.size());
  std::vector<std::pair<double, Eigen::Vector3d>> by_angle;
  for (const auto& x : unique) {
    const Eigen::Vector3d d = x - centroid;
    by_angle.emplace_back(std::atan2(d.dot(frame.v), d.dot(frame.u)), x);
  }
  std::sort(by_angle.begin(), by_angle.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Eigen::Vector3d> cap;  // counter-clockwise around the plane normal
  for (const auto& [angle, x] : by_angle) cap.push_back(x);
  if (polygonArea3d(cap) < kMinArea) return false;

  if (extent) {
    std::vector<Eigen::Vector2d> cap2d;
    for (const auto& x : cap) cap2d.push_back(extent->frame.project(x));
    if (!convexPolygonsWithin(cap2d, extent->hull, margin)) return false;
  }

  negative.faces.clear();
  positive.faces.clear();
  for (std::size_t fi = 0; fi < cell.faces.size(); ++fi) {
    const Face& f = cell.faces[fi];
    for (int side : {-1, 1}) {
      Face piece{clipPolygon(f.polygon, distances[fi], side), f.plane, f.sign};
      if (piece.polygon.size() >= 3 && polygonArea3d(piece.polygon) >= kMinArea)
        (side < 0 ? negative : positive).faces.push_back(std::move(piece));
    }
  }
  negative.faces.push_back(Face{cap, plane_index, +1});
  std::reverse(cap.begin(), cap.end());
  positive.faces.push_back(Face{std::move(cap), plane_index, -1});
  return true;
}

// Intersection of two convex 2-D polygons (both counter-clockwise), carrying 3-D positions along.
struct Vertex2 {
  Eigen::Vector2d p;
  Eigen::Vector3d x;
};

std::vector<Vertex2> clipConvex(std::vector<Vertex2> subject, const std::vector<Vertex2>& clip) {
  for (std::size_t i = 0; i < clip.size() && !subject.empty(); ++i) {
    const Eigen::Vector2d a = clip[i].p, b = clip[(i + 1) % clip.size()].p;
    const Eigen::Vector2d edge = b - a;
    const double length = edge.norm();
    if (length < 1e-15) continue;
    auto side = [&](const Eigen::Vector2d& q) { return cross2(edge, q - a) / length; };  // > 0: inside
    std::vector<Vertex2> out;
    for (std::size_t k = 0; k < subject.size(); ++k) {
      const Vertex2& c = subject[k];
      const Vertex2& d = subject[(k + 1) % subject.size()];
      const double sc = side(c.p), sd = side(d.p);
      if (sc >= -kOnPlane) out.push_back(c);
      if ((sc > kOnPlane && sd < -kOnPlane) || (sc < -kOnPlane && sd > kOnPlane)) {
        const double t = sc / (sc - sd);
        out.push_back({c.p + (d.p - c.p) * t, c.x + (d.x - c.x) * t});
      }
    }
    subject = std::move(out);
  }
  return subject;
}

// A face of the output before welding, oriented outward.
struct OutputPolygon {
  std::vector<Eigen::Vector3d> polygon;
};

// The part [t0, t1] (arc length from `from`) of the segment (from, to) that an edge of the cell
// runs along; empty (t0 >= t1) when none does. A convex cell meets a line in one segment, so
// one interval suffices.
std::pair<double, double> edgeIntervalAlong(const Cell& cell, const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                                            double tolerance) {
  const double length = (to - from).norm();
  const Eigen::Vector3d u = (to - from) / length;
  std::pair<double, double> best{0.0, 0.0};
  for (const auto& f : cell.faces)
    for (std::size_t j = 0; j < f.polygon.size(); ++j) {
      const Eigen::Vector3d& r = f.polygon[j];
      const Eigen::Vector3d& q = f.polygon[(j + 1) % f.polygon.size()];
      if ((r - from).cross(u).norm() > tolerance || (q - from).cross(u).norm() > tolerance) continue;
      const double tr = (r - from).dot(u), tq = (q - from).dot(u);
      const double t0 = std::max(0.0, std::min(tr, tq)), t1 = std::min(length, std::max(tr, tq));
      if (t1 - t0 > best.second - best.first) best = {t0, t1};
    }
  return best;
}

// The longest overlap (longer than `min_length`) of a cell edge of `a` with one of `b` on a common
// line, as its two end points; false when the cells share no edge.
bool sharedEdge(const Cell& a, const Cell& b, double tolerance, double min_length, Eigen::Vector3d& from,
                Eigen::Vector3d& to) {
  double best = min_length;
  for (const auto& f : a.faces)
    for (std::size_t i = 0; i < f.polygon.size(); ++i) {
      const Eigen::Vector3d& p = f.polygon[i];
      const Eigen::Vector3d& q = f.polygon[(i + 1) % f.polygon.size()];
      if ((q - p).norm() <= min_length) continue;
      const auto [t0, t1] = edgeIntervalAlong(b, p, q, tolerance);
      if (t1 - t0 > best) {
        best = t1 - t0;
        const Eigen::Vector3d u = (q - p).normalized();
        from = p + t0 * u;
        to = p + t1 * u;
      }
    }
  return best > min_length;
}

// A labelling where two inside cells meet only along an edge, between two outside cells (or the
// reverse), gives a non-manifold edge: four boundary faces on one line, an "X". Each such
// configuration is removed by flipping the one of its four cells that raises the min-cut energy
// least; repeated until none is left (bounded: each flip can create others). Returns the flips.
// A cell can flip back and forth between two crossings until the bound; letting each cell flip
// only once was tried and cut a large piece off an MFCAD part's solid (doc/assembly.md).
int resolveEdgeCrossings(const std::vector<Cell>& cells, const std::vector<std::vector<std::pair<int, double>>>& neighbours,
                         const std::function<double(int)>& flip_cost, std::vector<bool>& inside) {
  const int num_cells = static_cast<int>(cells.size());
  auto adjacent = [&](int x, int y) {
    for (const auto& [n, w] : neighbours[x])
      if (n == y) return true;
    return false;
  };
  int flips = 0;
  const int max_flips = 4 * num_cells + 16;
  bool changed = true;
  while (changed && flips < max_flips) {
    changed = false;
    for (int a = 0; a < num_cells && !changed; ++a) {
      for (const auto& [c, wc] : neighbours[a]) {
        if (inside[c] == inside[a]) continue;
        for (const auto& [b, wb] : neighbours[c]) {
          if (b <= a || inside[b] != inside[a] || adjacent(a, b)) continue;
          // a and b share the label; c (and a d) of the other label touch both.
          for (const auto& [d, wd] : neighbours[b]) {
            if (d == c || inside[d] == inside[a] || adjacent(c, d) || !adjacent(a, d)) continue;
            // The four cells must meet around one common edge (not merely touch elsewhere).
            Eigen::Vector3d from, to;
            if (!sharedEdge(cells[a], cells[b], 1e-9, 1e-7, from, to)) continue;
            const auto along_c = edgeIntervalAlong(cells[c], from, to, 1e-9);
            const auto along_d = edgeIntervalAlong(cells[d], from, to, 1e-9);
            if (std::min(along_c.second, along_d.second) - std::max(along_c.first, along_d.first) <= 1e-7) continue;
            int best = a;
            double best_cost = flip_cost(a);
            for (int x : {b, c, d})
              if (const double cost = flip_cost(x); cost < best_cost) best = x, best_cost = cost;
            inside[best] = !inside[best];
            ++flips;
            changed = true;
            break;
          }
          if (changed) break;
        }
        if (changed) break;
      }
    }
  }
  return flips;
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// Two cells meeting on a primitive's plane, and the polygon they share.
struct Adjacency {
  int a, b;  // a: cell whose face has sign +1
  double area;
  std::vector<Eigen::Vector3d> polygon;  // counter-clockwise around the plane normal
  int plane;
};

// The boundary between inside and outside cells (and inside cells against the box), welded and
// without T-junctions.
SurfaceMesh extractBoundary(const std::vector<Cell>& cells, const std::vector<Adjacency>& adjacencies,
                            const std::vector<bool>& inside, int num_primitives) {
  std::vector<OutputPolygon> polygons;
  for (const auto& adjacency : adjacencies) {
    if (inside[adjacency.a] == inside[adjacency.b]) continue;
    OutputPolygon out{adjacency.polygon};
    if (inside[adjacency.b]) std::reverse(out.polygon.begin(), out.polygon.end());  // outward from b is -normal
    polygons.push_back(std::move(out));
  }
  for (std::size_t c = 0; c < cells.size(); ++c) {
    if (!inside[c]) continue;
    for (const auto& f : cells[c].faces)
      if (f.plane >= num_primitives) polygons.push_back(OutputPolygon{f.polygon});
  }
  // Shared corners and no T-junctions; merging into one polygon per plane region follows in
  // cleanUpPolygonMesh (called by PolygonalAssembler for every backend).
  SurfaceMesh mesh;
  for (const auto& p : polygons) {
    std::vector<std::uint32_t> face;
    for (const auto& x : p.polygon) {
      face.push_back(static_cast<std::uint32_t>(mesh.vertices.size()));
      mesh.vertices.push_back(x);
    }
    mesh.faces.push_back(std::move(face));
  }
  weldVertices(mesh, kWeldTolerance);
  insertTJunctionVertices(mesh, 10 * kWeldTolerance);
  return mesh;
}

// Edges of the mesh used by one face or by more than two: where the surface is open or pinched.
std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> defectiveEdges(const SurfaceMesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, int> uses;
  for (const auto& face : mesh.faces)
    for (std::size_t i = 0; i < face.size(); ++i) {
      const std::uint32_t u = face[i], v = face[(i + 1) % face.size()];
      ++uses[{std::min(u, v), std::max(u, v)}];
    }
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> edges;
  for (const auto& [edge, count] : uses)
    if (count != 2) edges.push_back({mesh.vertices[edge.first], mesh.vertices[edge.second]});
  return edges;
}

// Defects left once PolygonalAssembler has finished the mesh (it separates sheets that touch, for
// one, so the raw mesh's pinched vertices do not count), and optionally the finished mesh.
std::size_t defectsAfterFinishing(SurfaceMesh mesh, SurfaceMesh* finished = nullptr) {
  if (mesh.faces.empty()) return std::numeric_limits<std::size_t>::max();
  const MeshTopology t = finishAssembledMesh(mesh);
  if (finished) *finished = std::move(mesh);
  return t.boundary_edges + t.non_manifold_edges + t.inconsistent_edges + t.non_manifold_vertices;
}

// The cells with a face edge along one of `edges` for more than a point.
std::vector<int> cellsAlong(const std::vector<Cell>& cells,
                            const std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>>& edges) {
  std::vector<int> along;
  for (const auto& [from, to] : edges) {
    if ((to - from).norm() < 1e-12) continue;
    for (int c = 0; c < static_cast<int>(cells.size()); ++c) {
      const auto [t0, t1] = edgeIntervalAlong(cells[c], from, to, 1e-7);
      if (t1 - t0 > 1e-9) along.push_back(c);
    }
  }
  std::sort(along.begin(), along.end());
  along.erase(std::unique(along.begin(), along.end()), along.end());
  return along;
}

// What the X-pattern search cannot see (more than four cells around an edge, cells reaching an
// edge over part of its length): flips, one at a time, a cell along a defective edge of the
// extracted surface, the one raising the min-cut energy least among those that reduce the
// defects, until the surface is a closed manifold, no flip helps or `out_of_time()`. Returns the
// flips. The cells along the finished surface's defective edges are tried first, those along the
// raw surface's only when none helps: the raw surface has many more defective edges (sheets that
// touch, which finishing separates), and each trial extracts and finishes the whole surface, so
// trying all of the raw surface's cells made large complexes (thousands of cells) take tens of
// seconds.
int repairByRelabelling(const std::vector<Cell>& cells, const std::vector<Adjacency>& adjacencies, int num_primitives,
                        const std::function<double(int)>& flip_cost, const std::function<bool()>& out_of_time,
                        std::vector<bool>& inside) {
  int flips = 0;
  SurfaceMesh mesh = extractBoundary(cells, adjacencies, inside, num_primitives);
  SurfaceMesh finished;
  std::size_t defects = defectsAfterFinishing(mesh, &finished);
  // Flips the cheapest of `candidates` (by flip cost) that lowers the defects, if any.
  auto flipOneOf = [&](const std::vector<int>& candidates) {
    std::vector<std::pair<double, int>> by_cost;
    for (int c : candidates) by_cost.push_back({flip_cost(c), c});
    std::sort(by_cost.begin(), by_cost.end());
    for (const auto& [cost, c] : by_cost) {
      if (out_of_time()) return false;
      inside[c] = !inside[c];
      SurfaceMesh attempt = extractBoundary(cells, adjacencies, inside, num_primitives);
      SurfaceMesh attempt_finished;
      const std::size_t attempt_defects = defectsAfterFinishing(attempt, &attempt_finished);
      if (attempt_defects < defects) {
        mesh = std::move(attempt);
        finished = std::move(attempt_finished);
        defects = attempt_defects;
        ++flips;
        return true;
      }
      inside[c] = !inside[c];
    }
    return false;
  };
  for (int round = 0; defects > 0 && round < 32 && !out_of_time(); ++round) {
    const std::vector<int> first = cellsAlong(cells, defectiveEdges(finished));
    if (flipOneOf(first)) continue;
    std::vector<int> rest;
    const std::vector<int> raw = cellsAlong(cells, defectiveEdges(mesh));
    std::set_difference(raw.begin(), raw.end(), first.begin(), first.end(), std::back_inserter(rest));
    if (!flipOneOf(rest)) break;
  }
  return flips;
}

// The volume of a cell: its faces are counter-clockwise seen from outside (divergence theorem,
// one fan of triangles per face).
double cellVolume(const Cell& cell) {
  double six_volume = 0.0;
  for (const auto& face : cell.faces)
    for (std::size_t k = 1; k + 1 < face.polygon.size(); ++k)
      six_volume += face.polygon[0].dot(face.polygon[k].cross(face.polygon[k + 1]));
  return std::abs(six_volume) / 6.0;
}

// Groups of face-adjacent inside cells with less than this share of the largest group's volume
// are set outside (dropSmallInsideGroups).
constexpr double kMinInsideGroupShare = 0.01;

// Sets outside every group of face-adjacent inside cells smaller than kMinInsideGroupShare of the
// largest: a few points that vote inside a tiny cell off the solid leave a closed sliver of its
// own, a second component of the mesh (3 mm across on the milk carton of ../shared/data/scans
// and 0.5 m on AHN3_16627, both run with the scanner's view).
void dropSmallInsideGroups(const std::vector<Cell>& cells, const std::vector<Adjacency>& adjacencies,
                           std::vector<bool>& inside) {
  DisjointSets<int> groups(cells.size());
  for (const auto& adjacency : adjacencies)
    if (inside[adjacency.a] && inside[adjacency.b]) groups.join(adjacency.a, adjacency.b);
  std::vector<double> group_volume(cells.size(), 0.0);
  for (std::size_t c = 0; c < cells.size(); ++c)
    if (inside[c]) group_volume[groups.find(static_cast<int>(c))] += cellVolume(cells[c]);
  const double largest = *std::max_element(group_volume.begin(), group_volume.end());
  for (std::size_t c = 0; c < cells.size(); ++c)
    if (inside[c] && group_volume[groups.find(static_cast<int>(c))] < kMinInsideGroupShare * largest) inside[c] = false;
}

}  // namespace

BackendOutcome runCellComplex(const std::vector<PlanarPrimitive>& primitives, const CellComplexOptions& options,
                              SurfaceMesh& mesh) {
  const auto start = std::chrono::steady_clock::now();
  BackendOutcome outcome;
  mesh = SurfaceMesh{};
  const int num_primitives = static_cast<int>(primitives.size());

  // Planes: the primitives', then the six of the enlarged bounding box (outward normals).
  std::vector<Plane> planes;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  for (const auto& p : primitives) {
    planes.push_back(p.plane);
    for (const auto& q : p.points) {
      lo = lo.cwiseMin(Eigen::Vector3d(q.x, q.y, q.z));
      hi = hi.cwiseMax(Eigen::Vector3d(q.x, q.y, q.z));
    }
  }
  const double pad = 0.05 * std::max(1e-9, (hi - lo).norm());
  lo.array() -= pad;
  hi.array() += pad;
  for (int axis = 0; axis < 3; ++axis) {
    planes.emplace_back(-Eigen::Vector3d::Unit(axis), lo[axis]);   // -x + lo <= 0 inside
    planes.emplace_back(Eigen::Vector3d::Unit(axis), -hi[axis]);   //  x - hi <= 0 inside
  }

  // The box as the root cell: each face counter-clockwise seen from outside.
  Cell root;
  for (int axis = 0; axis < 3; ++axis) {
    const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
    for (int high = 0; high < 2; ++high) {
      auto corner = [&](int i, int j) {
        Eigen::Vector3d x;
        x[axis] = high ? hi[axis] : lo[axis];
        x[a1] = i ? hi[a1] : lo[a1];
        x[a2] = j ? hi[a2] : lo[a2];
        return x;
      };
      std::vector<Eigen::Vector3d> poly = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
      // (a1, a2, axis) is right-handed, so this order faces +axis; reverse it for the low side.
      if (!high) std::reverse(poly.begin(), poly.end());
      root.faces.push_back(Face{std::move(poly), num_primitives + 2 * axis + high, 1});
    }
  }

  // Adaptive BSP: large primitives first; a primitive splits a cell only where its extent reaches.
  std::vector<Extent> extents;
  extents.reserve(primitives.size());
  for (const auto& p : primitives) extents.push_back(makeExtent(p));
  std::vector<int> order(num_primitives);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return extents[a].area > extents[b].area; });

  std::vector<BspNode> nodes(1);
  std::vector<Cell> cells;
  struct Pending {
    int node;
    Cell cell;
    std::vector<int> candidates;
  };
  std::vector<Pending> stack;
  stack.push_back({0, std::move(root), order});
  std::size_t splits = 0;
  while (!stack.empty()) {
    Pending work = std::move(stack.back());
    stack.pop_back();
    bool was_split = false;
    for (std::size_t c = 0; c < work.candidates.size() && !was_split; ++c) {
      const int k = work.candidates[c];
      Cell negative, positive;
      if (!splitCell(work.cell, planes[k], k, &extents[k], options.extent_margin, negative, positive)) continue;
      was_split = true;
      std::vector<int> rest(work.candidates.begin() + static_cast<std::ptrdiff_t>(c) + 1, work.candidates.end());
      nodes[work.node].plane = k;
      nodes[work.node].negative = static_cast<int>(nodes.size());
      nodes[work.node].positive = static_cast<int>(nodes.size()) + 1;
      nodes.emplace_back();
      nodes.emplace_back();
      stack.push_back({nodes[work.node].positive, std::move(positive), rest});
      stack.push_back({nodes[work.node].negative, std::move(negative), std::move(rest)});
    }
    if (!was_split) {
      nodes[work.node].cell = static_cast<int>(cells.size());
      cells.push_back(std::move(work.cell));
    }
    if ((++splits & 255) == 0) {
      if (interruptRequested()) {
        outcome.status = AssemblyStatus::Interrupted;
        outcome.message = "interrupted while partitioning space";
        return outcome;
      }
      if (secondsSince(start) > options.seconds) {
        outcome.status = AssemblyStatus::TimeLimit;
        outcome.message = "the space partition did not finish within the time limit (" +
                          std::to_string(cells.size()) + " cells so far)";
        return outcome;
      }
    }
  }
  outcome.num_cells = cells.size();
  outcome.seconds_partition = secondsSince(start);
  const int num_cells = static_cast<int>(cells.size());

  auto locate = [&](const Eigen::Vector3d& x) {
    int n = 0;
    while (nodes[n].plane >= 0) n = planes[nodes[n].plane].signedDistance(x) < 0.0 ? nodes[n].negative : nodes[n].positive;
    return nodes[n].cell;
  };
  auto inBox = [&](const Eigen::Vector3d& x) { return (x.array() > lo.array()).all() && (x.array() < hi.array()).all(); };

  // Data terms, in units of area: each point stands for its primitive's area / point count. The
  // side its normal points to is empty (outside), the other side is solid (inside).
  std::vector<double> cost_inside(num_cells, 0.0), cost_outside(num_cells, 0.0);
  for (int k = 0; k < num_primitives; ++k) {
    const auto& primitive = primitives[k];
    if (primitive.points.empty()) continue;
    const double weight = std::max(extents[k].area, 1e-12) / static_cast<double>(primitive.points.size());
    const Eigen::Vector3d& n = primitive.plane.normal;
    for (const auto& p : primitive.points) {
      const Eigen::Vector3d x = primitive.plane.project(Eigen::Vector3d(p.x, p.y, p.z));
      const double facing = Eigen::Vector3d(p.normal_x, p.normal_y, p.normal_z).dot(n) >= 0.0 ? 1.0 : -1.0;
      const Eigen::Vector3d front = x + kVoteOffset * facing * n, back = x - kVoteOffset * facing * n;
      if (inBox(front)) cost_inside[locate(front)] += weight;
      if (inBox(back)) cost_outside[locate(back)] += weight;
    }
  }

  // Adjacency: faces of different cells on the same plane with opposite sides overlap.
  struct FaceRef {
    int cell;
    const Face* face;
    std::vector<Vertex2> polygon;  // counter-clockwise in the plane frame
    Eigen::Vector2d lo, hi;
  };
  std::vector<std::vector<FaceRef>> by_plane(planes.size());
  for (int c = 0; c < num_cells; ++c)
    for (const auto& f : cells[c].faces) {
      const PlaneFrame frame(planes[f.plane]);
      FaceRef ref{c, &f, {}, Eigen::Vector2d::Constant(1e300), Eigen::Vector2d::Constant(-1e300)};
      for (const auto& x : f.polygon) {
        const Eigen::Vector2d p = frame.project(x);
        ref.polygon.push_back({p, x});
        ref.lo = ref.lo.cwiseMin(p);
        ref.hi = ref.hi.cwiseMax(p);
      }
      if (f.sign < 0) std::reverse(ref.polygon.begin(), ref.polygon.end());
      by_plane[f.plane].push_back(std::move(ref));
    }
  std::vector<Adjacency> adjacencies;
  std::vector<double> box_area(num_cells, 0.0);
  for (int plane = 0; plane < static_cast<int>(planes.size()); ++plane) {
    auto& refs = by_plane[plane];
    if (plane >= num_primitives) {
      for (const auto& r : refs) box_area[r.cell] += polygonArea3d(r.face->polygon);
      continue;
    }
    std::vector<const FaceRef*> up, down;
    for (const auto& r : refs) (r.face->sign > 0 ? up : down).push_back(&r);
    std::sort(down.begin(), down.end(), [](const FaceRef* x, const FaceRef* y) { return x->lo.x() < y->lo.x(); });
    for (const FaceRef* a : up) {
      for (const FaceRef* b : down) {
        if (b->lo.x() > a->hi.x()) break;
        if (b->hi.x() < a->lo.x() || b->lo.y() > a->hi.y() || b->hi.y() < a->lo.y() || a->cell == b->cell) continue;
        std::vector<Vertex2> overlap = clipConvex(a->polygon, b->polygon);
        if (overlap.size() < 3) continue;
        std::vector<Eigen::Vector2d> pts;
        for (const auto& v : overlap) pts.push_back(v.p);
        const double area = polygonArea2d(pts);
        if (area < kMinArea) continue;
        Adjacency adjacency{a->cell, b->cell, area, {}, plane};
        for (const auto& v : overlap) adjacency.polygon.push_back(v.x);
        adjacencies.push_back(std::move(adjacency));
      }
    }
  }
  outcome.num_candidate_faces = adjacencies.size();
  if (secondsSince(start) > options.seconds) {
    outcome.status = AssemblyStatus::TimeLimit;
    outcome.message = "the cell adjacency did not finish within the time limit";
    return outcome;
  }

  // s-t min-cut: source = inside, sink = outside. Cutting s->i labels i outside, paying its inside
  // votes; cutting i->t labels i inside, paying its outside votes and the box area it would expose.
  using namespace boost;
  using Traits = adjacency_list_traits<vecS, vecS, directedS>;
  using Graph = adjacency_list<
      vecS, vecS, directedS,
      property<vertex_index_t, long,
               property<vertex_color_t, default_color_type,
                        property<vertex_distance_t, long, property<vertex_predecessor_t, Traits::edge_descriptor>>>>,
      property<edge_capacity_t, double,
               property<edge_residual_capacity_t, double, property<edge_reverse_t, Traits::edge_descriptor>>>>;
  auto label = [&](double beta, std::vector<bool>& inside) {
    Graph graph(static_cast<std::size_t>(num_cells) + 2);
    const auto source = static_cast<Traits::vertex_descriptor>(num_cells);
    const auto sink = static_cast<Traits::vertex_descriptor>(num_cells + 1);
    auto capacity = get(edge_capacity, graph);
    auto reverse = get(edge_reverse, graph);
    auto addEdge = [&](Traits::vertex_descriptor u, Traits::vertex_descriptor v, double forward, double backward) {
      const auto e = add_edge(u, v, graph).first;
      const auto r = add_edge(v, u, graph).first;
      capacity[e] = forward;
      capacity[r] = backward;
      reverse[e] = r;
      reverse[r] = e;
    };
    for (int c = 0; c < num_cells; ++c) {
      addEdge(source, static_cast<Traits::vertex_descriptor>(c), cost_outside[c], 0.0);
      addEdge(static_cast<Traits::vertex_descriptor>(c), sink, cost_inside[c] + beta * box_area[c], 0.0);
    }
    for (const auto& adjacency : adjacencies)
      addEdge(static_cast<Traits::vertex_descriptor>(adjacency.a), static_cast<Traits::vertex_descriptor>(adjacency.b),
              beta * adjacency.area, beta * adjacency.area);
    boykov_kolmogorov_max_flow(graph, source, sink);
    auto color = get(vertex_color, graph);
    inside.assign(num_cells, false);
    for (int c = 0; c < num_cells; ++c) inside[c] = get(color, static_cast<Traits::vertex_descriptor>(c)) == black_color;
    if (!options.resolve_crossings) return;
    std::vector<std::vector<std::pair<int, double>>> neighbours(num_cells);
    for (const auto& adjacency : adjacencies) {
      neighbours[adjacency.a].push_back({adjacency.b, beta * adjacency.area});
      neighbours[adjacency.b].push_back({adjacency.a, beta * adjacency.area});
    }
    std::vector<double> label_cost_inside(num_cells), label_cost_outside(num_cells);
    for (int c = 0; c < num_cells; ++c) {
      label_cost_inside[c] = cost_inside[c] + beta * box_area[c];
      label_cost_outside[c] = cost_outside[c];
    }
    // How much the min-cut energy rises when cell c changes label (under the current labels).
    auto flip_cost = [&](int c) {
      double delta = inside[c] ? label_cost_outside[c] - label_cost_inside[c] : label_cost_inside[c] - label_cost_outside[c];
      for (const auto& [n, w] : neighbours[c]) delta += inside[n] == inside[c] ? w : -w;
      return delta;
    };
    outcome.crossings_resolved = resolveEdgeCrossings(cells, neighbours, flip_cost, inside);
    outcome.crossings_resolved += repairByRelabelling(cells, adjacencies, num_primitives, flip_cost,
                                                     [&] { return secondsSince(start) > options.seconds; }, inside);
  };
  auto none = [](const std::vector<bool>& inside) { return std::find(inside.begin(), inside.end(), true) == inside.end(); };

  std::vector<bool> inside;
  outcome.smoothness_used = options.smoothness;
  label(options.smoothness, inside);
  // Points that cover little of each face (a scanner's patches, points stopping short of the
  // edges) vote with little area against the whole surface's area term, and the cut can then
  // prefer no solid at all. Weaker smoothing is tried before giving up, but a solid that reaches
  // the box's walls is not kept: it is the outside of inward-facing normals, not a part.
  for (int halvings = 1; none(inside) && halvings <= kSmoothnessHalvings; ++halvings) {
    const double beta = options.smoothness * std::ldexp(1.0, -halvings);
    std::vector<bool> attempt;
    label(beta, attempt);
    if (none(attempt)) continue;
    bool reaches_box = false;
    for (int c = 0; c < num_cells; ++c) reaches_box = reaches_box || (attempt[c] && box_area[c] > 0.0);
    if (reaches_box) break;
    inside = std::move(attempt);
    outcome.smoothness_used = beta;
  }
  if (none(inside)) {
    outcome.status = AssemblyStatus::EmptySolution;
    outcome.message = "the min-cut labelled every cell outside: the points' normals do not describe a solid";
    return outcome;
  }

  dropSmallInsideGroups(cells, adjacencies, inside);
  mesh = extractBoundary(cells, adjacencies, inside, num_primitives);
  outcome.seconds_solve = secondsSince(start) - outcome.seconds_partition;
  return outcome;
}

}  // namespace paco::detail
