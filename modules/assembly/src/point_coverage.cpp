#include "point_coverage.h"

#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/AABB_triangle_primitive.h>
#include <CGAL/Simple_cartesian.h>

namespace paco::detail {
namespace {

// Distances only: no predicate needs exactness here.
using Kernel = CGAL::Simple_cartesian<double>;
using Triangle3 = Kernel::Triangle_3;
using TriangleIterator = std::vector<Triangle3>::const_iterator;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, CGAL::AABB_triangle_primitive<Kernel, TriangleIterator>>>;

}  // namespace

double shareOfPointsFartherThan(const SurfaceMesh& mesh, const std::vector<PlanarPrimitive>& primitives,
                                double distance) {
  std::size_t total = 0;
  for (const auto& primitive : primitives) total += primitive.points.size();
  if (total == 0) return 0.0;
  const SurfaceMesh triangles = triangulated(mesh);
  std::vector<Triangle3> soup;
  soup.reserve(triangles.faces.size());
  auto corner = [&](std::uint32_t v) {
    const Eigen::Vector3d& x = triangles.vertices[v];
    return Kernel::Point_3(x.x(), x.y(), x.z());
  };
  for (const auto& f : triangles.faces) {
    Triangle3 t(corner(f[0]), corner(f[1]), corner(f[2]));
    if (!t.is_degenerate()) soup.push_back(t);
  }
  if (soup.empty()) return 1.0;
  Tree tree(soup.begin(), soup.end());
  tree.accelerate_distance_queries();
  const double squared = distance * distance;
  std::size_t far = 0;
  for (const auto& primitive : primitives)
    for (const auto& p : primitive.points)
      if (tree.squared_distance(Kernel::Point_3(p.x, p.y, p.z)) > squared) ++far;
  return static_cast<double>(far) / static_cast<double>(total);
}

}  // namespace paco::detail
