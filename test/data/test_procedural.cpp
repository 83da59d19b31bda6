#include <paco/data/ground_truth.h>
#include <paco/data/procedural.h>

#include <gtest/gtest.h>

#include <set>

namespace {

using namespace paco::data;

TEST(Procedural, EveryFamilyGivesClosedOutwardPlaneOnlyParts) {
  const PartKind kinds[] = {PartKind::FeaturedBox, PartKind::Prism,      PartKind::LExtrusion,
                            PartKind::TExtrusion,  PartKind::UExtrusion, PartKind::BoxUnion};
  for (PartKind kind : kinds) {
    for (std::uint64_t seed : {1u, 2u}) {
      const paco::SurfaceMesh mesh = generatePart(seed, kind);
      const paco::MeshTopology topology = paco::analyseTopology(mesh);
      EXPECT_TRUE(topology.isClosedManifold()) << toString(kind) << " seed " << seed << ": " << topology.describe();
      EXPECT_EQ(topology.components, 1u);
      EXPECT_GT(paco::signedVolume(mesh), 0.0);
      const GroundTruth gt = extractGroundTruth(mesh);  // throws if not plane-only
      EXPECT_GE(gt.faces.size(), kind == PartKind::Prism ? 5u : 6u) << toString(kind);
      Eigen::Vector3d lo, hi;
      paco::boundingBox(mesh, lo, hi);
      EXPECT_LE(hi.cwiseAbs().maxCoeff(), 2.5);
      EXPECT_LE(lo.cwiseAbs().maxCoeff(), 2.5);
    }
  }
}

TEST(Procedural, LSectionHasItsKnownPlanes) {
  // An L extrusion has 8 planes, 9 with the optional chamfer of its outer corner.
  for (std::uint64_t seed = 0; seed < 3; ++seed) {
    const std::size_t planes = extractGroundTruth(generatePart(seed, PartKind::LExtrusion)).faces.size();
    EXPECT_TRUE(planes == 8 || planes == 9) << planes;
  }
}

TEST(Procedural, SameSeedSameMesh) {
  const paco::SurfaceMesh a = generatePart(17), b = generatePart(17), c = generatePart(18);
  EXPECT_EQ(a.vertices, b.vertices);
  EXPECT_EQ(a.faces, b.faces);
  EXPECT_FALSE(a.vertices == c.vertices && a.faces == c.faces);
  EXPECT_EQ(partKindOf(17), partKindOf(17));
  std::set<PartKind> kinds;
  for (std::uint64_t s = 0; s < 60; ++s) kinds.insert(partKindOf(s));
  EXPECT_EQ(kinds.size(), 6u);
  EXPECT_EQ(proceduralPartName(42), "proc-000042");
}

}  // namespace
