// The poisson-qem baseline (the paper's Table 3): CGAL Poisson surface reconstruction of the
// partial points, then CGAL Garland–Heckbert simplification. The only file that includes CGAL.
#include <paco/evaluation/methods.h>

#include <paco/common/error.h>

// Eigen, instantiated by CGAL's Garland–Heckbert quadrics, trips -Wmaybe-uninitialized in
// its own storage copy; the warning is not about our code.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/Count_stop_predicate.h>
#include <CGAL/Surface_mesh_simplification/Policies/Edge_collapse/GarlandHeckbert_plane_policies.h>
#include <CGAL/Surface_mesh_simplification/edge_collapse.h>
#include <CGAL/compute_average_spacing.h>
#include <CGAL/mst_orient_normals.h>
#include <CGAL/pca_estimate_normals.h>
#include <CGAL/poisson_surface_reconstruction.h>
#include <CGAL/property_map.h>

#include <chrono>
#include <utility>
#include <vector>

namespace paco::evaluation {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using PointWithNormal = std::pair<Point, Vector>;
using Mesh = CGAL::Surface_mesh<Point>;
namespace SMS = CGAL::Surface_mesh_simplification;
constexpr int kNormalNeighbours = 18;
}  // namespace

SurfaceMesh reconstructPoissonQem(const pcl::PointCloud<pcl::PointNormal>& cloud, std::size_t target_faces,
                                  std::map<std::string, double>* seconds) {
  std::vector<PointWithNormal> points;
  points.reserve(cloud.size());
  for (const auto& p : cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) points.emplace_back(Point(p.x, p.y, p.z), Vector(0, 0, 0));
  if (points.size() < 10)
    throw InvalidInputError("reconstructPoissonQem: needs at least 10 finite points, got " + std::to_string(points.size()));
  if (target_faces < 4) throw InvalidInputError("reconstructPoissonQem: the target face count must be at least 4");

  const auto start = std::chrono::steady_clock::now();
  const auto point_map = CGAL::First_of_pair_property_map<PointWithNormal>();
  const auto normal_map = CGAL::Second_of_pair_property_map<PointWithNormal>();
  CGAL::pca_estimate_normals<CGAL::Sequential_tag>(points, kNormalNeighbours,
                                                   CGAL::parameters::point_map(point_map).normal_map(normal_map));
  // Points whose normal could not be oriented are dropped, as CGAL's own examples do.
  const auto unoriented = CGAL::mst_orient_normals(points, kNormalNeighbours,
                                                   CGAL::parameters::point_map(point_map).normal_map(normal_map));
  points.erase(unoriented, points.end());
  SurfaceMesh result;
  if (points.size() < 10) return result;
  const double spacing = CGAL::compute_average_spacing<CGAL::Sequential_tag>(points, 6, CGAL::parameters::point_map(point_map));
  Mesh mesh;
  const bool ok = CGAL::poisson_surface_reconstruction_delaunay(points.begin(), points.end(), point_map, normal_map,
                                                                mesh, spacing);
  const auto reconstructed = std::chrono::steady_clock::now();
  if (seconds) (*seconds)["reconstruct"] = std::chrono::duration<double>(reconstructed - start).count();
  if (!ok || mesh.number_of_faces() == 0) return result;

  // Closed triangle meshes have 3F/2 edges; the stop predicate counts edges.
  if (mesh.number_of_faces() > target_faces && CGAL::is_triangle_mesh(mesh)) {
    SMS::Count_stop_predicate<Mesh> stop(3 * target_faces / 2);
    SMS::GarlandHeckbert_plane_policies<Mesh, Kernel> policies(mesh);
    SMS::edge_collapse(mesh, stop,
                       CGAL::parameters::get_cost(policies.get_cost()).get_placement(policies.get_placement()));
    mesh.collect_garbage();
  }
  if (seconds)
    (*seconds)["simplify"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - reconstructed).count();

  std::vector<std::uint32_t> index(mesh.number_of_vertices() + mesh.number_of_removed_vertices(), 0);
  for (auto v : mesh.vertices()) {
    index[v.idx()] = static_cast<std::uint32_t>(result.vertices.size());
    const Point& p = mesh.point(v);
    result.vertices.emplace_back(p.x(), p.y(), p.z());
  }
  for (auto f : mesh.faces()) {
    std::vector<std::uint32_t> face;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(f), mesh)) face.push_back(index[v.idx()]);
    result.faces.push_back(std::move(face));
  }
  return result;
}

}  // namespace paco::evaluation
