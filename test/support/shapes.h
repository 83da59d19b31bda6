#pragma once
// Small closed, outward-oriented polyhedra with known planes, areas and volumes, for tests.
// Richer CAD-like parts come from paco::data's procedural generator.
#include <paco/common/primitive.h>
#include <paco/common/surface_mesh.h>

#include <Eigen/Core>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdint>
#include <functional>
#include <vector>

namespace paco::test {

/// Axis-aligned box between `min` and `max`: 6 quad faces.
SurfaceMesh makeBox(const Eigen::Vector3d& min, const Eigen::Vector3d& max);
/// Extrusion of a simple counter-clockwise polygon in the xy-plane from z = 0 to z = height:
/// a bottom face, a top face and one quad per polygon edge.
SurfaceMesh makePrism(const std::vector<Eigen::Vector2d>& polygon, double height);
/// L-shaped extrusion: an a x a square with an (a-b) x (a-b) corner removed, height h. 8 planes,
/// volume h * (a^2 - (a-b)^2).
SurfaceMesh makeLBracket(double a = 1.0, double b = 0.4, double h = 0.6);
/// Unit cube with the edge at x = 1, z = 1 chamfered by `c`: 7 planes, volume 1 - c^2 / 2.
SurfaceMesh makeChamferedCube(double c = 0.3);
/// Union of a 2 x 2 x 1 slab and a 1 x 1 x 1 boss centred on its top: 11 planes (the slab top
/// is one ring face, triangulated), volume 5.
SurfaceMesh makeBossOnSlab();
/// A U channel along z: a web `width` wide along x and two legs `height` tall along y, all `wall`
/// thick, from z = 0 to z = length (10 planes).
SurfaceMesh makeUChannel(double width, double height, double wall, double length);
/// A square tube along z: an outer x outer square with a (outer - 2 wall)-wide square hole, from
/// z = 0 to z = length. 4 outer and 4 inner walls, each end a frame of 4 quads (8 planes); volume
/// length * (outer^2 - (outer - 2 wall)^2).
SurfaceMesh makeSquareTube(double outer, double wall, double length);
/// A unit square plate from z = 0 to z = thickness with a through hole turned by 45 degrees: a
/// square of half-diagonal `hole` centred on the plate, whose 4 walls (normals (+-1, +-1, 0) / sqrt 2)
/// are parallel to no other face. 10 planes; the top and bottom are rings of 8 triangles.
SurfaceMesh makePlateWithDiamondHole(double hole, double thickness);
/// Applies x -> R x + t to every vertex.
void transformMesh(SurfaceMesh& mesh, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation);

/// A scan of a mesh whose faces are each planar, segmented by face.
struct FaceLabelledScan {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud{new pcl::PointCloud<pcl::PointNormal>};
  PlanarSegmentation segmentation;  ///< one segment per face of the mesh (in face order)
};
/// `count` points sampled on the mesh (paco::sampleSurface with `seed`), with their face's normal
/// and labelled by their face; points for which `keep` (when given) is false are left out, the
/// part a scan missed (their faces keep their planes, with fewer or no points).
FaceLabelledScan scanByFace(const SurfaceMesh& mesh, std::size_t count, std::uint64_t seed,
                            const std::function<bool(const Eigen::Vector3d&)>& keep = nullptr);

/// An L-shaped room as a solid (makePrism): floor plan (0,0) (6,0) (6,4) (3,4) (3,7) (0,7), 2.6
/// high, of volume kLShapedRoomVolume.
SurfaceMesh makeLShapedRoom();
constexpr double kLShapedRoomVolume = (6.0 * 4.0 + 3.0 * 3.0) * 2.6;
/// What a scanner inside that room sees of its surface: all but the wall at y = 7 and the
/// ceiling beyond y = 3.
bool seenFromInsideTheLShapedRoom(const Eigen::Vector3d& x);
/// `count` points sampled over the room's surface (scanByFace), those seenFromInsideTheLShapedRoom,
/// every normal facing into the room, as a scanner inside gives them.
pcl::PointCloud<pcl::PointNormal>::Ptr scanLShapedRoomFromInside(std::size_t count, std::uint64_t seed);

}  // namespace paco::test
