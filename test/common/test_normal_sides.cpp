// Which way a scan's normals face as a whole: a room scanned from inside faces its middle and is
// turned; an object scanned from outside faces away and is left alone; ground under a building
// faces the middle too, but one way only, and is left alone.
#include "shapes.h"

#include <paco/common/normal_sides.h>

#include <gtest/gtest.h>

#include <random>

namespace {

using paco::NormalSides;

pcl::PointNormal pointWithNormal(const Eigen::Vector3f& x, const Eigen::Vector3f& n) {
  pcl::PointNormal p;
  p.getVector3fMap() = x;
  p.getNormalVector3fMap() = n;
  return p;
}

TEST(NormalSides, ARoomScannedFromInsideFacesInwardsAndIsTurned) {
  const auto room = paco::test::scanLShapedRoomFromInside(6000, 3);
  const NormalSides read = paco::normalSides(*room);
  EXPECT_GT(read.inwardShare(), 0.99);
  // Floor, ceiling and walls face the middle from every side: their mean normal is short.
  EXPECT_LT(read.inward_agreement, 0.5);
  EXPECT_TRUE(read.faceInwards());
  EXPECT_FALSE(read.turned);

  pcl::PointCloud<pcl::PointNormal> turned = *room;
  const NormalSides result = paco::turnInwardNormalsOutward(turned);
  EXPECT_TRUE(result.turned);
  EXPECT_EQ(result.inwards, read.inwards);
  ASSERT_EQ(turned.size(), room->size());
  for (std::size_t i = 0; i < turned.size(); ++i) {
    EXPECT_EQ(turned[i].getVector3fMap(), (*room)[i].getVector3fMap()) << i;
    EXPECT_EQ(turned[i].getNormalVector3fMap(), -(*room)[i].getNormalVector3fMap()) << i;
  }
  EXPECT_LT(paco::normalSides(turned).inwardShare(), 0.01);
  EXPECT_FALSE(paco::turnInwardNormalsOutward(turned).turned);  // once is enough
}

TEST(NormalSides, AnObjectScannedFromOutsideIsLeftAsItIs) {
  // An L bracket, a boss on a slab, a chamfered cube and the L-shaped room as a solid seen from
  // outside: outward normals, whatever concave edges they have.
  for (const auto& [name, mesh] : {std::pair{"bracket", paco::test::makeLBracket()},
                                   std::pair{"L-shaped room", paco::test::makeLShapedRoom()},
                                   std::pair{"boss on slab", paco::test::makeBossOnSlab()},
                                   std::pair{"chamfered cube", paco::test::makeChamferedCube()}}) {
    SCOPED_TRACE(name);
    const auto scan = paco::test::scanByFace(mesh, 4000, 5);
    pcl::PointCloud<pcl::PointNormal> cloud = *scan.cloud;
    const NormalSides sides = paco::turnInwardNormalsOutward(cloud);
    EXPECT_LT(sides.inwardShare(), 0.5);
    EXPECT_GT(sides.outwards, 0u);
    EXPECT_FALSE(sides.turned);
    for (std::size_t i = 0; i < cloud.size(); ++i)
      ASSERT_EQ(cloud[i].getNormalVector3fMap(), (*scan.cloud)[i].getNormalVector3fMap()) << i;
  }
}

TEST(NormalSides, GroundUnderABuildingFacesOneWayAndIsLeftAlone) {
  // 20 x 20 of ground around a 2 x 2 x 6 building (roof and walls facing out): the ground lies
  // below the box centre and faces up, towards it, and it is most of the scan.
  pcl::PointCloud<pcl::PointNormal> cloud;
  std::mt19937 random(11);
  std::uniform_real_distribution<float> across(0.0f, 20.0f), along(0.0f, 2.0f), up(0.0f, 6.0f);
  for (int i = 0; i < 4000; ++i) {
    const Eigen::Vector3f x(across(random), across(random), 0.0f);
    if (x.x() > 9 && x.x() < 11 && x.y() > 9 && x.y() < 11) continue;  // under the building
    cloud.push_back(pointWithNormal(x, Eigen::Vector3f::UnitZ()));
  }
  for (int i = 0; i < 200; ++i) {
    cloud.push_back(pointWithNormal({9 + along(random), 9 + along(random), 6.0f}, Eigen::Vector3f::UnitZ()));
    cloud.push_back(pointWithNormal({9.0f, 9 + along(random), up(random)}, -Eigen::Vector3f::UnitX()));
    cloud.push_back(pointWithNormal({11.0f, 9 + along(random), up(random)}, Eigen::Vector3f::UnitX()));
  }
  const NormalSides sides = paco::normalSides(cloud);
  EXPECT_GT(sides.inwardShare(), paco::kInwardNormalShare);
  EXPECT_GT(sides.inward_agreement, 0.99);
  EXPECT_FALSE(sides.faceInwards());
  EXPECT_FALSE(paco::turnInwardNormalsOutward(cloud).turned);
}

TEST(NormalSides, MissingNormalsAndAFlatScanTellNothing) {
  pcl::PointCloud<pcl::PointNormal> no_normals, flat;
  std::mt19937 random(2);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int i = 0; i < 500; ++i) {
    const Eigen::Vector3f x(u(random), u(random), u(random));
    no_normals.push_back(pointWithNormal(x, Eigen::Vector3f::Zero()));  // a file without normals
    flat.push_back(pointWithNormal({x.x(), x.y(), 0.0f}, -Eigen::Vector3f::UnitZ()));
  }
  no_normals.push_back(pointWithNormal({0.9f, 0.9f, 0.9f}, Eigen::Vector3f::Constant(std::nanf(""))));
  for (const auto* cloud : {&no_normals, &flat}) {
    const NormalSides sides = paco::normalSides(*cloud);
    EXPECT_EQ(sides.inwards + sides.outwards, 0u);
    EXPECT_EQ(sides.inwardShare(), 0.0);
    EXPECT_FALSE(sides.faceInwards());
  }
  EXPECT_EQ(paco::normalSides(pcl::PointCloud<pcl::PointNormal>()).inwardShare(), 0.0);
}

}  // namespace
