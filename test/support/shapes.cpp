#include "shapes.h"

#include <paco/common/normal_sides.h>

namespace paco::test {

SurfaceMesh makePrism(const std::vector<Eigen::Vector2d>& polygon, double height) {
  SurfaceMesh m;
  const auto n = static_cast<std::uint32_t>(polygon.size());
  for (const auto& p : polygon) m.vertices.emplace_back(p.x(), p.y(), 0.0);
  for (const auto& p : polygon) m.vertices.emplace_back(p.x(), p.y(), height);
  std::vector<std::uint32_t> bottom, top;
  for (std::uint32_t i = 0; i < n; ++i) {
    bottom.push_back(n - 1 - i);  // reversed: faces -z
    top.push_back(n + i);
    const std::uint32_t j = (i + 1) % n;
    m.faces.push_back({i, j, n + j, n + i});
  }
  m.faces.push_back(bottom);
  m.faces.push_back(top);
  return m;
}

SurfaceMesh makeBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max) {
  const Eigen::Vector3d size = max - min;
  SurfaceMesh m = makePrism({{0, 0}, {size.x(), 0}, {size.x(), size.y()}, {0, size.y()}}, size.z());
  for (auto& v : m.vertices) v += min;
  return m;
}

SurfaceMesh makeLBracket(double a, double b, double h) {
  return makePrism({{0, 0}, {a, 0}, {a, b}, {b, b}, {b, a}, {0, a}}, h);
}

SurfaceMesh makeUChannel(double width, double height, double wall, double length) {
  const double w = width, h = height, t = wall;
  return makePrism({{0, 0}, {w, 0}, {w, h}, {w - t, h}, {w - t, t}, {t, t}, {t, h}, {0, h}}, length);
}

namespace {

// The extrusion from z = 0 to z = height of the ring between an outer and an inner quadrilateral
// (`corners`: outer 0-3, then inner 4-7, each counter-clockwise from above, corner k of one facing
// corner k of the other). Outer walls face out, inner walls into the hole. Each end is one quad
// per side, or two triangles when a quad would not be convex (an inner quad turned against the
// outer one).
SurfaceMesh extrudeRing(const std::vector<Eigen::Vector2d>& corners, double height, bool triangulated_ends) {
  SurfaceMesh m;
  for (const double z : {0.0, height})
    for (const auto& c : corners) m.vertices.emplace_back(c.x(), c.y(), z);
  for (std::uint32_t i = 0; i < 4; ++i) {
    const std::uint32_t j = (i + 1) % 4;
    m.faces.push_back({i, j, 8 + j, 8 + i});            // outer wall, facing out
    m.faces.push_back({4 + j, 4 + i, 12 + i, 12 + j});  // inner wall, facing the hole
    if (triangulated_ends) {
      m.faces.push_back({4 + i, j, i});  // bottom, facing -z
      m.faces.push_back({4 + i, 4 + j, j});
      m.faces.push_back({8 + i, 8 + j, 12 + i});  // top, facing +z
      m.faces.push_back({8 + j, 12 + j, 12 + i});
    } else {
      m.faces.push_back({4 + i, 4 + j, j, i});            // bottom frame, facing -z
      m.faces.push_back({8 + i, 8 + j, 12 + j, 12 + i});  // top frame, facing +z
    }
  }
  return m;
}

}  // namespace

SurfaceMesh makeSquareTube(double outer, double wall, double length) {
  const double a = outer, t = wall;
  return extrudeRing({{0, 0}, {a, 0}, {a, a}, {0, a}, {t, t}, {a - t, t}, {a - t, a - t}, {t, a - t}}, length, false);
}

SurfaceMesh makePlateWithDiamondHole(double hole, double thickness) {
  const double r = hole;
  // The hole's corners below, right of, above and left of the centre face the plate's edges.
  return extrudeRing({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0.5, 0.5 - r}, {0.5 + r, 0.5}, {0.5, 0.5 + r}, {0.5 - r, 0.5}},
                     thickness, true);
}

SurfaceMesh makeChamferedCube(double c) {
  // Profile in the xz-plane extruded along y: build it as a prism in xy, then swap axes.
  SurfaceMesh m = makePrism({{0, 0}, {1, 0}, {1, 1 - c}, {1 - c, 1}, {0, 1}}, 1.0);
  // (x, y, z) -> (x, z, y) mirrors; reverse faces to keep them outward.
  for (auto& v : m.vertices) std::swap(v.y(), v.z());
  flipFaces(m);
  return m;
}

SurfaceMesh makeBossOnSlab() {
  SurfaceMesh m;
  // Slab corners 0-7, boss bottom ring 8-11 (on z = 1), boss top 12-15 (z = 2).
  m.vertices = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}, {0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1},
                {0.5, 0.5, 1}, {1.5, 0.5, 1}, {1.5, 1.5, 1}, {0.5, 1.5, 1},
                {0.5, 0.5, 2}, {1.5, 0.5, 2}, {1.5, 1.5, 2}, {0.5, 1.5, 2}};
  m.faces = {{0, 3, 2, 1}, {0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7},
             // slab top: the ring between the outer square 4-7 and the boss square 8-11
             {4, 5, 9}, {4, 9, 8}, {5, 6, 10}, {5, 10, 9}, {6, 7, 11}, {6, 11, 10}, {7, 4, 8}, {7, 8, 11},
             // boss sides and top
             {8, 9, 13, 12}, {9, 10, 14, 13}, {10, 11, 15, 14}, {11, 8, 12, 15}, {12, 13, 14, 15}};
  return m;
}

void transformMesh(SurfaceMesh& mesh, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  for (auto& v : mesh.vertices) v = rotation * v + translation;
}

FaceLabelledScan scanByFace(const SurfaceMesh& mesh, std::size_t count, std::uint64_t seed,
                            const std::function<bool(const Eigen::Vector3d&)>& keep) {
  FaceLabelledScan scan;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    scan.segmentation.planes.push_back(Plane::fromPointAndNormal(mesh.vertices[mesh.faces[f][0]], faceNormal(mesh, f)));
  const SurfaceSample sample = sampleSurface(mesh, count, seed);
  for (std::size_t i = 0; i < sample.points.size(); ++i) {
    if (keep && !keep(sample.points[i])) continue;
    pcl::PointNormal p;
    p.x = float(sample.points[i].x()), p.y = float(sample.points[i].y()), p.z = float(sample.points[i].z());
    p.normal_x = float(sample.normals[i].x()), p.normal_y = float(sample.normals[i].y());
    p.normal_z = float(sample.normals[i].z());
    scan.cloud->push_back(p);
    scan.segmentation.labels.push_back(static_cast<int>(sample.faces[i]));
  }
  scan.segmentation.rebuildSegmentsFromLabels();
  return scan;
}

SurfaceMesh makeLShapedRoom() { return makePrism({{0, 0}, {6, 0}, {6, 4}, {3, 4}, {3, 7}, {0, 7}}, 2.6); }

bool seenFromInsideTheLShapedRoom(const Eigen::Vector3d& x) {
  const bool far_wall = x.y() > 7.0 - 1e-6;
  const bool ceiling_beyond_3 = x.z() > 2.6 - 1e-6 && x.y() > 3.0;
  return !far_wall && !ceiling_beyond_3;
}

pcl::PointCloud<pcl::PointNormal>::Ptr scanLShapedRoomFromInside(std::size_t count, std::uint64_t seed) {
  const FaceLabelledScan scan = scanByFace(makeLShapedRoom(), count, seed, seenFromInsideTheLShapedRoom);
  paco::flipNormals(*scan.cloud);
  return scan.cloud;
}

}  // namespace paco::test
