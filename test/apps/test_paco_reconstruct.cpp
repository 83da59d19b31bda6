// paco_reconstruct end to end on the shipped sample scan: a closed mesh in the input's own frame
// plus the primitives as .vg and PCD; bad input and a missing model give a clear error, a
// non-zero exit, and no output file at all.
#include "shapes.h"
#include "test_support.h"

#ifdef PACO_TEST_WITH_COMPLETION
#include <torch/torch.h>  // before PCL-using headers (see doc/training.md)

#include <paco/common/angles.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/hidden_extent.h>
#include <paco/completion/turn_ensemble.h>

#include "tiny_model_config.h"
#endif

#include <paco/common/surface_mesh.h>
#include <paco/io/cloud_io.h>
#include <paco/io/mesh_io.h>
#include <paco/io/vertex_groups_io.h>
#include <paco/segmentation/planar_segmenter.h>

#include <Eigen/Geometry>

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <regex>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using paco::test::TempDir;

using paco::test::quoted;
std::string samplePath() { return std::string(PACO_SOURCE_DIR) + "/data/sample_partial.pcd"; }
std::string tool() { return quoted(paco::test::toolPath("paco_reconstruct")); }

std::size_t filesIn(const fs::path& dir) {
  std::size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir)) ++n;
  return n;
}

// The sample in a different frame and unit (x 250, shifted): outputs must follow it.
std::string writeMovedSample(const TempDir& dir) {
  paco::io::LabelledCloud cloud = paco::io::loadCloud(samplePath());
  for (auto& p : cloud.points) {
    p.x = 250.0f * p.x + 1000.0f;
    p.y = 250.0f * p.y - 40.0f;
    p.z = 250.0f * p.z + 7.0f;
  }
  const std::string path = dir.file("moved.ply");
  paco::io::saveCloud(path, cloud);
  return path;
}

TEST(PacoReconstruct, DirectBaselineGivesClosedMeshInTheInputFrame) {
  TempDir dir;
  const std::string input = writeMovedSample(dir);
  const std::string mesh_path = dir.file("part.obj");
  std::string log;
  const int rc = paco::test::runCommand(tool() + " " + quoted(input) + " -o " + quoted(mesh_path) +
                                            " --no-completion --assembler cell-complex",
                                        &log);
  ASSERT_EQ(rc, 0) << log;
  // By default the smallest plane is a share of the points (the sample has no repeated points),
  // and a smaller share for planes parallel to a larger one; the sample's noise (0.5 % of the
  // diagonal) widens the inlier distance, and with it the parallel planes' share.
  const paco::io::LabelledCloud cloud = paco::io::loadCloud(input);
  const std::string min_points = std::to_string(paco::scanMinPointsPerPlane(cloud.points.size()));
  const std::string min_parallel_points =
      std::to_string(paco::noisyScanMinPointsPerParallelPlane(cloud.points.size(), 0));
  EXPECT_NE(log.find("segment (gocopp, planes of >= " + min_points + " points, parallel to a larger one >= " +
                     min_parallel_points + ", inlier distance raised to"),
            std::string::npos)
      << log;
  EXPECT_NE(log.find("timing:"), std::string::npos) << log;

  const paco::SurfaceMesh mesh = paco::io::loadMesh(mesh_path);
  const paco::MeshTopology topology = paco::analyseTopology(mesh);
  EXPECT_TRUE(topology.isClosedManifold()) << topology.describe();
  EXPECT_GT(paco::signedVolume(mesh), 0.0);

  // Same frame as the input: the two bounding boxes overlap almost entirely.
  Eigen::Vector3d cmin = Eigen::Vector3d::Constant(1e300), cmax = -cmin;
  for (const auto& p : cloud.points) {
    cmin = cmin.cwiseMin(Eigen::Vector3d(p.x, p.y, p.z));
    cmax = cmax.cwiseMax(Eigen::Vector3d(p.x, p.y, p.z));
  }
  Eigen::Vector3d mmin, mmax;
  paco::boundingBox(mesh, mmin, mmax);
  const double diagonal = (cmax - cmin).norm();
  EXPECT_LT((mmin - cmin).norm(), 0.2 * diagonal);
  EXPECT_LT((mmax - cmax).norm(), 0.2 * diagonal);

  const auto groups = paco::io::loadVertexGroups(dir.file("part.vg"));
  EXPECT_GE(groups.segmentation.size(), 4u);
  const auto coloured = paco::io::loadCloud(dir.file("part_primitives.pcd"));
  EXPECT_EQ(coloured.points.size(), groups.points.size());
  EXPECT_EQ(filesIn(dir.path()), 4u);  // input + mesh + .vg + .pcd, nothing partial
}

// One stray return 25 diagonals away is left out, so the mesh stays the part's size.
TEST(PacoReconstruct, LeavesOutAStrayPointFarFromTheScan) {
  TempDir dir;
  paco::io::LabelledCloud cloud = paco::io::loadCloud(samplePath());
  Eigen::AlignedBox3d seen;
  for (const auto& p : cloud.points) seen.extend(p.getVector3fMap().cast<double>());
  pcl::PointNormal stray = cloud.points[0];
  stray.getVector3fMap() = (seen.max() + 25.0 * seen.diagonal()).cast<float>();
  cloud.points.push_back(stray);
  paco::io::saveCloud(dir.file("scan.pcd"), cloud);
  const std::string base = tool() + " " + quoted(dir.file("scan.pcd")) + " --no-completion --assembler cell-complex -o ";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("part.obj")), &log), 0) << log;
  EXPECT_NE(log.find("left out 1 stray point far from the rest of the scan"), std::string::npos) << log;
  // The part's 15 planes are found, as without the stray point.
  EXPECT_NE(log.find(": 15 planes, coverage"), std::string::npos) << log;
  Eigen::Vector3d lo, hi;
  paco::boundingBox(paco::io::loadMesh(dir.file("part.obj")), lo, hi);
  EXPECT_LT((hi - lo).norm(), 1.5 * seen.diagonal().norm());
  // Kept, the stray point stretches the scan's box 25 times, and the segmenter, working in
  // fractions of that box, merges the part's faces.
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("kept.obj")) + " --keep-stray-points", &log), 0) << log;
  EXPECT_EQ(log.find("stray point"), std::string::npos) << log;
  EXPECT_EQ(log.find(": 15 planes, coverage"), std::string::npos) << log;
}

// A scan denser than --max-points is thinned before segmentation, and the tool says so.
TEST(PacoReconstruct, ThinsAScanDenserThanMaxPoints) {
  TempDir dir;
  std::string log;
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("part.obj")) +
                                       " --no-completion --assembler cell-complex --max-points 1000",
                                   &log),
            0)
      << log;
  EXPECT_NE(log.find("of 4096 points kept"), std::string::npos) << log;
  const auto groups = paco::io::loadVertexGroups(dir.file("part.vg"));
  EXPECT_LE(groups.points.size(), 1000u);
  EXPECT_GE(groups.points.size(), 300u);
  EXPECT_TRUE(paco::analyseTopology(paco::io::loadMesh(dir.file("part.obj"))).isClosedManifold());
  // The sample is within the default budget: nothing is thinned.
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("all.obj")) +
                                       " --no-completion --assembler cell-complex",
                                   &log),
            0)
      << log;
  EXPECT_EQ(log.find("thin:"), std::string::npos) << log;
}

// A scan merged with itself gives the same primitives as the scan: the repeats are left out.
TEST(PacoReconstruct, LeavesOutRepeatedPoints) {
  TempDir dir;
  paco::io::LabelledCloud cloud = paco::io::loadCloud(samplePath());
  const std::size_t n = cloud.points.size();
  const pcl::PointCloud<pcl::PointNormal> copy = cloud.points;  // += of itself would insert from itself
  cloud.points += copy;
  paco::io::saveCloud(dir.file("twice.pcd"), cloud);
  const std::string options = " --no-completion --assembler cell-complex";
  std::string log;
  const std::string twice_command =
      tool() + " " + quoted(dir.file("twice.pcd")) + " -o " + quoted(dir.file("twice.obj")) + options;
  ASSERT_EQ(paco::test::runCommand(twice_command, &log), 0) << log;
  const std::string said = "left out " + std::to_string(n) + " of " + std::to_string(2 * n) + " points";
  EXPECT_NE(log.find(said), std::string::npos) << log;
  const std::string once_command =
      tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("once.obj")) + options;
  ASSERT_EQ(paco::test::runCommand(once_command, &log), 0) << log;
  const auto twice = paco::io::loadVertexGroups(dir.file("twice.vg"));
  const auto once = paco::io::loadVertexGroups(dir.file("once.vg"));
  EXPECT_EQ(twice.points.size(), once.points.size());
  EXPECT_EQ(twice.segmentation.size(), once.segmentation.size());
}

#ifdef PACO_TEST_WITH_COMPLETION
// An untrained model with --threshold 1 keeps no completed primitive. With fusion (the default)
// the seen faces still reach the assembler and the mesh closes; without it nothing is left to
// assemble, which must be a clear failure that writes nothing.
TEST(PacoReconstruct, FusionKeepsTheSeenFacesWhenTheNetworkKeepsNothing) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  const std::string base = tool() + " " + quoted(samplePath()) + " --model " + quoted(dir.file("tiny.pt")) +
                           " --threshold 1 --assembler cell-complex -o ";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("fused.obj")), &log), 0) << log;
  EXPECT_NE(log.find("complete: 0 primitives"), std::string::npos) << log;
  EXPECT_NE(log.find("fuse with the seen faces: 0 primitives took a seen plane"), std::string::npos) << log;
  // By default the box of the seen points fills what nothing covers; --fill-box 0 turns it off.
  EXPECT_NE(log.find("points filled on the seen box"), std::string::npos) << log;
  // The seen faces and the fill stay within the scan's box: no note that the mesh reaches past it.
  EXPECT_EQ(log.find("beyond the scan's bounding box"), std::string::npos) << log;
  const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("fused.obj"));
  EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("unfilled.obj")) + " --fill-box 0", &log), 0) << log;
  EXPECT_EQ(log.find("points filled"), std::string::npos) << log;
  EXPECT_TRUE(paco::analyseTopology(paco::io::loadMesh(dir.file("unfilled.obj"))).isClosedManifold());

  const fs::path out_dir = dir.file("nofusion");
  fs::create_directories(out_dir);
  EXPECT_NE(paco::test::runCommand(base + quoted((out_dir / "part.obj").string()) + " --no-fusion", &log), 0);
  EXPECT_NE(log.find("nothing to assemble: no completed primitive has confidence above --threshold 1; lower "
                     "--threshold, or drop --no-fusion"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("setInputPrimitives"), std::string::npos) << log;
  EXPECT_EQ(filesIn(out_dir), 0u);
}

// A scan of the box [0,2] x [0,1] x [0,1] that stopped at x = 1 (points and normals), turned by
// `turn`, written to `path`.
namespace {
void writeHalfBoxScan(const std::string& path, const Eigen::Matrix3d& turn) {
  const paco::SurfaceSample surface = paco::sampleSurface(paco::test::makeBox({0, 0, 0}, {2, 1, 1}), 8000, 3);
  paco::io::LabelledCloud scan;
  scan.has_normals = true;
  for (std::size_t i = 0; i < surface.points.size(); ++i) {
    if (surface.points[i].x() > 1.0) continue;
    const Eigen::Vector3d q = turn * surface.points[i], n = turn * surface.normals[i];
    pcl::PointNormal p;
    p.x = float(q.x()), p.y = float(q.y()), p.z = float(q.z());
    p.normal_x = float(n.x()), p.normal_y = float(n.y()), p.normal_z = float(n.z());
    scan.points.push_back(p);
  }
  paco::io::saveCloud(path, scan);
}

// Runs paco_reconstruct on `input` with `assembler` and a tiny untrained model whose primitives
// are all left out (--threshold 1): the seen faces and the box fill alone. Returns the tool's log;
// `mesh` receives the mesh, or stays empty when the tool failed (a test failure).
std::string reconstructWithoutTheNetwork(const TempDir& dir, const std::string& input, const std::string& assembler,
                                         paco::SurfaceMesh& mesh, const std::string& more_options = "") {
  const std::string model = dir.file("tiny.pt");
  if (!std::filesystem::exists(model)) {
    paco::PacoNetwork network(paco::test::tinyModelConfig());
    paco::saveCheckpoint(model, network);
  }
  const std::string mesh_path = dir.file(std::filesystem::path(input).stem().string() + "_" + assembler + ".obj");
  std::string log;
  const int status = paco::test::runCommand(tool() + " " + quoted(input) + " --model " + quoted(model) +
                                                " --threshold 1 --assembler " + assembler + " -o " + quoted(mesh_path) +
                                                more_options,
                                            &log);
  EXPECT_EQ(status, 0) << log;
  mesh = status == 0 ? paco::io::loadMesh(mesh_path) : paco::SurfaceMesh{};
  return log;
}

// Expects `mesh` to be one closed solid spanning the box from the origin to `far_corner` (within
// 0.03) with `volume` (within 1 %); `log` is the tool's, printed on failure.
void expectOneSolid(const paco::SurfaceMesh& mesh, const Eigen::Vector3d& far_corner, double volume,
                    const std::string& log) {
  const paco::MeshTopology topology = paco::analyseTopology(mesh);
  EXPECT_TRUE(topology.isClosedManifold()) << log;
  EXPECT_EQ(topology.components, 1u) << log;
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  EXPECT_LT(lo.norm(), 0.03) << lo.transpose();
  EXPECT_LT((hi - far_corner).norm(), 0.03) << hi.transpose() << "\n" << log;
  EXPECT_NEAR(paco::signedVolume(mesh), volume, 0.01 * volume) << log;
}

}  // namespace

// A plate 1 x 1 x 0.04 scanned on its two sides only: the network adds nothing (--threshold 1), so
// the rims come from the box fill. They are narrower than twice the fill's empty radius (0.05 of
// the diagonal), and before the fill capped that radius on narrow faces the sides' points covered
// them: no rim, no solid ("all planes are parallel to one direction").
TEST(PacoReconstruct, AThinPlateScannedOnItsTwoSidesClosesAtItsThickness) {
  TempDir dir;
  const paco::SurfaceSample surface = paco::sampleSurface(paco::test::makeBox({0, 0, 0}, {1, 1, 0.04}), 6000, 5);
  paco::io::LabelledCloud scan;
  scan.has_normals = true;
  for (std::size_t i = 0; i < surface.points.size(); ++i) {
    if (std::abs(surface.normals[i].z()) < 0.5) continue;
    pcl::PointNormal p;
    p.getVector3fMap() = surface.points[i].cast<float>();
    p.getNormalVector3fMap() = surface.normals[i].cast<float>();
    scan.points.push_back(p);
  }
  paco::io::saveCloud(dir.file("plate.pcd"), scan);
  for (const std::string assembler : {"polyfit", "cell-complex"}) {
    paco::SurfaceMesh mesh;
    const std::string log = reconstructWithoutTheNetwork(dir, dir.file("plate.pcd"), assembler, mesh);
    EXPECT_NE(log.find("(4 new box faces)"), std::string::npos) << log;
    EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold()) << assembler;
    Eigen::Vector3d lo, hi;
    paco::boundingBox(mesh, lo, hi);
    EXPECT_NEAR(hi.z() - lo.z(), 0.04, 0.002) << assembler;
    EXPECT_NEAR(paco::signedVolume(mesh), 0.04, 0.004) << assembler << "\n" << log;
  }
}

// Profiles of sheet metal 0.05 thick, 8,000 points without normals: their end faces are a few
// point spacings wide, too thin for the segmenter's 1 % (80 points, the rule of a scan with
// noise), so every plane found is parallel to the profile's axis. The ends are closed over the
// profile, and the solid has the profile's volume. These samples are exact, and the tools'
// defaults keep planes of 0.25 %, the ends' too: the solid closes as well.
// In the U channel no shared edge ties the inner faces to the outer ones; before rays oriented
// them, they faced the box centre, into the metal, and the cell complex filled the channel (5.7
// times the volume).
TEST(PacoReconstruct, ThinSheetMetalProfilesCloseAtTheirEnds) {
  TempDir dir;
  const double t = 0.05;
  const std::vector<std::pair<std::string, paco::SurfaceMesh>> profiles = {
      {"bracket", paco::test::makePrism({{0, 0}, {1, 0}, {1, t}, {t, t}, {t, 0.8}, {0, 0.8}}, 1.0)},
      {"channel", paco::test::makeUChannel(1.0, 0.6, t, 1.0)},
  };
  for (const auto& [name, profile] : profiles) {
    const paco::SurfaceSample surface = paco::sampleSurface(profile, 8000, 7);
    paco::io::LabelledCloud scan;
    for (const Eigen::Vector3d& x : surface.points) {
      pcl::PointNormal p;
      p.getVector3fMap() = x.cast<float>();
      scan.points.push_back(p);
    }
    paco::io::saveCloud(dir.file(name + ".xyz"), scan);
    Eigen::Vector3d true_lo, true_hi;
    paco::boundingBox(profile, true_lo, true_hi);
    for (const std::string assembler : {"polyfit", "cell-complex"}) {
      SCOPED_TRACE(name + ", " + assembler);
      paco::SurfaceMesh mesh;
      const std::string log =
          reconstructWithoutTheNetwork(dir, dir.file(name + ".xyz"), assembler, mesh, " --min-points 80");
      EXPECT_NE(log.find("close the two ends of a profile"), std::string::npos) << log;
      EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
      Eigen::Vector3d lo, hi;
      paco::boundingBox(mesh, lo, hi);
      for (int axis = 0; axis < 3; ++axis) EXPECT_NEAR(hi[axis] - lo[axis], true_hi[axis] - true_lo[axis], 0.03) << axis;
      EXPECT_NEAR(paco::signedVolume(mesh), paco::signedVolume(profile), 0.05 * paco::signedVolume(profile)) << log;

      paco::SurfaceMesh with_ends;
      const std::string defaults_log = reconstructWithoutTheNetwork(dir, dir.file(name + ".xyz"), assembler, with_ends);
      EXPECT_NE(defaults_log.find("planes of >= 20 points (80 on a scan with noise)"), std::string::npos)
          << defaults_log;
      EXPECT_TRUE(paco::analyseTopology(with_ends).isClosedManifold()) << defaults_log;
      EXPECT_NEAR(paco::signedVolume(with_ends), paco::signedVolume(profile), 0.05 * paco::signedVolume(profile))
          << defaults_log;
    }
  }
}

// An L-shaped room scanned from inside: its normals face into the room, and the assemblers
// read the space a face's normal points into as outside. Before the tools turned such normals
// outwards, the cell complex kept the space beyond the walls as solid (three components, 7.2 x
// 10.3 x 6.8 for a room 6 x 7 x 2.6). Now both assemblers give the room's volume, its unseen wall
// and ceiling closed by the box fill.
TEST(PacoReconstruct, ARoomScannedFromInsideIsTheRoomsVolume) {
  TempDir dir;
  paco::io::LabelledCloud scan;
  scan.has_normals = true;
  scan.points = *paco::test::scanLShapedRoomFromInside(8000, 7);
  paco::io::saveCloud(dir.file("room.pcd"), scan);
  for (const std::string assembler : {"polyfit", "cell-complex"}) {
    SCOPED_TRACE(assembler);
    paco::SurfaceMesh mesh;
    const std::string log = reconstructWithoutTheNetwork(dir, dir.file("room.pcd"), assembler, mesh);
    EXPECT_NE(log.find("normals: 100 % face the middle of the scan"), std::string::npos) << log;
    EXPECT_NE(log.find("turned outwards"), std::string::npos) << log;
    expectOneSolid(mesh, {6, 7, 2.6}, paco::test::kLShapedRoomVolume, log);
  }
  // Kept as they are, the tool says what it expects of them.
  paco::SurfaceMesh kept;
  const std::string kept_log =
      reconstructWithoutTheNetwork(dir, dir.file("room.pcd"), "polyfit", kept, " --keep-inward-normals");
  EXPECT_NE(kept_log.find("kept so (--keep-inward-normals)"), std::string::npos) << kept_log;
  EXPECT_EQ(kept_log.find("turned outwards"), std::string::npos) << kept_log;
}

// A furnished room scanned from inside: 6 x 5 x 2.7 with a table (1.2 x 0.8 x 0.75, on the floor)
// and a cabinet (0.6 x 2 x 2, against the wall x = 0), a door opening 0.9 x 2.1 in the wall y = 0;
// the floor under the furniture and the wall behind the cabinet unseen. Normals face into the room
// and out of the furniture, as a scanner inside gives them. Turned outwards, they make both
// assemblers give one solid: the room's air, less the furniture, the door closed over. Kept as
// given, the cell complex gave five components 6.8 x 5.8 x 3.5.
TEST(PacoReconstruct, AFurnishedRoomScannedFromInsideIsItsAir) {
  TempDir dir;
  paco::io::LabelledCloud scan;
  scan.has_normals = true;
  const double w = 6.0, d = 5.0, h = 2.7;
  // Each solid sampled by area at about 80 points per square unit (paco::test::scanByFace), less
  // what the scanner did not see.
  const auto add = [&](const paco::SurfaceMesh& solid, double area, std::uint64_t seed, float facing,
                       const std::function<bool(const Eigen::Vector3d&)>& seen) {
    const auto part = paco::test::scanByFace(solid, static_cast<std::size_t>(80.0 * area), seed, seen);
    for (auto p : *part.cloud) {
      p.getNormalVector3fMap() *= facing;
      scan.points.push_back(p);
    }
  };
  const auto under_table = [](const Eigen::Vector3d& x) {
    return x.x() > 2.4 && x.x() < 3.6 && x.y() > 2.1 && x.y() < 2.9;
  };
  const auto behind_cabinet = [](const Eigen::Vector3d& x) { return x.x() < 0.6 && x.y() > 1.5 && x.y() < 3.5; };
  const auto door = [](const Eigen::Vector3d& x) { return x.y() < 1e-6 && x.x() > 4.0 && x.x() < 4.9 && x.z() < 2.1; };
  const auto on_floor = [](const Eigen::Vector3d& x) { return x.z() < 1e-6; };
  // The room from inside: its normals face into it.
  add(paco::test::makeBox({0, 0, 0}, {w, d, h}), 2 * (w * d + w * h + d * h), 2, -1.0f, [&](const Eigen::Vector3d& x) {
    const bool floor_under_furniture = on_floor(x) && (under_table(x) || behind_cabinet(x));
    const bool wall_behind_cabinet = x.x() < 1e-6 && behind_cabinet(x) && x.z() < 2.0;
    return !floor_under_furniture && !wall_behind_cabinet && !door(x);
  });
  // The table (top and four sides) and the cabinet (top, front and two sides) from outside.
  add(paco::test::makeBox({2.4, 2.1, 0}, {3.6, 2.9, 0.75}), 2 * (0.96 + 0.9 + 0.6), 3, 1.0f,
      [&](const Eigen::Vector3d& x) { return !on_floor(x); });
  add(paco::test::makeBox({0, 1.5, 0}, {0.6, 3.5, 2.0}), 2 * (1.2 + 1.2 + 4.0), 4, 1.0f,
      [&](const Eigen::Vector3d& x) { return !on_floor(x) && x.x() > 1e-6; });
  paco::io::saveCloud(dir.file("furnished.pcd"), scan);
  const double air = w * d * h - 1.2 * 0.8 * 0.75 - 0.6 * 2.0 * 2.0;
  for (const std::string assembler : {"polyfit", "cell-complex"}) {
    SCOPED_TRACE(assembler);
    paco::SurfaceMesh mesh;
    const std::string log = reconstructWithoutTheNetwork(dir, dir.file("furnished.pcd"), assembler, mesh);
    EXPECT_NE(log.find("turned outwards"), std::string::npos) << log;
    expectOneSolid(mesh, {w, d, h}, air, log);
  }
}

// A scan of the box [0,2] x [0,1] x [0,1] that stopped at x = 1 ends there; told that the object
// reaches x = 2, the box fill closes the hidden side there, and the mesh reaches it.
TEST(PacoReconstruct, AKnownExtentClosesTheHiddenSideThere) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  writeHalfBoxScan(dir.file("half_box.pcd"), Eigen::Matrix3d::Identity());
  const std::string base = tool() + " " + quoted(dir.file("half_box.pcd")) + " --model " + quoted(dir.file("tiny.pt")) +
                           " --threshold 1 --assembler cell-complex -o ";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("known.obj")) + " --known-extent 0,0,0,2,1,1", &log), 0)
      << log;
  EXPECT_NE(log.find("box fill to the known extent"), std::string::npos) << log;
  const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("known.obj"));
  EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  EXPECT_NEAR(hi.x(), 2.0, 0.01) << log;
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 0.05) << log;
  // The same extent as a cloud of the points the object reaches.
  paco::test::writeBytes(dir.file("reach.xyz"), "0 0 0\n2 1 1\n");
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("from_file.obj")) + " --known-extent " +
                                       quoted(dir.file("reach.xyz")),
                                   &log),
            0)
      << log;
  paco::boundingBox(paco::io::loadMesh(dir.file("from_file.obj")), lo, hi);
  EXPECT_NEAR(hi.x(), 2.0, 0.01) << log;
  // A known extent far from the scan is most likely in other units or another frame: a warning.
  EXPECT_EQ(log.find("warning: --known-extent lies"), std::string::npos) << log;
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("far.obj")) + " --known-extent 100,100,100,101,101,101", &log),
            0)
      << log;
  EXPECT_NE(log.find("warning: --known-extent lies 171."),
            std::string::npos)
      << log;
  // Without it the mesh ends with the scan.
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("seen.obj")), &log), 0) << log;
  paco::boundingBox(paco::io::loadMesh(dir.file("seen.obj")), lo, hi);
  EXPECT_NEAR(hi.x(), 1.0, 0.01) << log;
}

// The same half box with a hidden-extent head trained on other scans of it, which all go on by
// the scan's length along +x: the box fill closes the hidden side at x = 2 (the head's guesses
// under the tool's four turns mapped back to the scan's sides). A head of
// another network, or one together with --known-extent or --no-fusion, is refused.
TEST(PacoReconstruct, AnExtentHeadClosesTheHiddenSideWhereItGuesses) {
  TempDir dir;
  torch::manual_seed(4);
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  const auto model = paco::CompletionModel::load(dir.file("tiny.pt"));
  // Scans of the half box sampled with other seeds, their faces as segments, under the four
  // turns the tool averages over, each with how far the whole box goes on: a head learns from
  // them what this scan's features say.
  std::vector<paco::ExtentExample> examples;
  const paco::SurfaceMesh box = paco::test::makeBox({0, 0, 0}, {2, 1, 1});
  const std::vector<Eigen::Vector3d> whole = {{0, 0, 0}, {2, 1, 1}};
  for (std::uint64_t seed = 10; seed < 34; ++seed) {
    const paco::test::FaceLabelledScan scan =
        paco::test::scanByFace(box, 8000, seed, [](const Eigen::Vector3d& p) { return p.x() <= 1.0; });
    for (const Eigen::Matrix3d& turn : paco::ensembleTurns(4)) {
      const paco::ExtentObservation observation = paco::observeExtent(model, scan.cloud, scan.segmentation, turn);
      examples.push_back({observation.features, paco::extentBeyond(observation, whole)});
    }
  }
  paco::ExtentTrainingOptions training;
  training.epochs = 1000;
  training.batch = 16;
  paco::trainHiddenExtentModel(paco::networkFingerprint(*model), examples, training)->save(dir.file("head.pt"));
  writeHalfBoxScan(dir.file("half_box.pcd"), Eigen::Matrix3d::Identity());
  const std::string base = tool() + " " + quoted(dir.file("half_box.pcd")) + " --model " + quoted(dir.file("tiny.pt")) +
                           " --threshold 1 --assembler cell-complex --extent-head " + quoted(dir.file("head.pt")) + " -o ";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("guessed.obj")), &log), 0) << log;
  EXPECT_NE(log.find("box fill to the guessed extent"), std::string::npos) << log;
  EXPECT_NE(log.find("hidden extent ("), std::string::npos) << log;
  // All but the cut side (+x) are seen faces of the box: the head must not grow them.
  EXPECT_NE(log.find("5 of its 6 sides end at a seen face"), std::string::npos) << log;
  const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("guessed.obj"));
  EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  // Without the head the mesh would end at x = 1 with the scan.
  EXPECT_NEAR(hi.x(), 2.0, 0.1) << log;
  EXPECT_NEAR(lo.x(), 0.0, 0.05) << log;
  EXPECT_NEAR(hi.y(), 1.0, 0.05) << log;
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 0.1) << log;
  // The mesh reaches 1 past the scan's box (58 % of its diagonal), as the user asked by giving the
  // head: no note asking to bound the completion.
  EXPECT_EQ(log.find("beyond the scan's bounding box"), std::string::npos) << log;

  EXPECT_NE(paco::test::runCommand(base + quoted(dir.file("both.obj")) + " --known-extent 0,0,0,2,1,1", &log), 0);
  EXPECT_NE(log.find("choose one"), std::string::npos) << log;
  EXPECT_NE(paco::test::runCommand(base + quoted(dir.file("nofuse.obj")) + " --no-fusion", &log), 0);
  EXPECT_NE(log.find("drop --no-fusion"), std::string::npos) << log;
  paco::PacoNetwork other(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("other.pt"), other);
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("half_box.pcd")) + " --model " +
                                       quoted(dir.file("other.pt")) + " --extent-head " + quoted(dir.file("head.pt")) +
                                       " -o " + quoted(dir.file("other.obj")),
                                   &log),
            1);
  EXPECT_NE(log.find("trained on another completion network"), std::string::npos) << log;
  for (const char* name : {"both.obj", "nofuse.obj", "other.obj"}) EXPECT_FALSE(std::filesystem::exists(dir.file(name))) << name;
}

// The same half box in UTM coordinates (northing 5.4e6, where float32 steps by 0.5 m, half the
// box): read relative to a coordinate offset, the scan keeps its shape, the known extent given in
// the file's coordinates applies, and every output is back in the file's coordinates.
TEST(PacoReconstruct, NationalGridCoordinatesKeepTheirPrecision) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  writeHalfBoxScan(dir.file("half_box.pcd"), Eigen::Matrix3d::Identity());
  paco::io::LabelledCloud scan = paco::io::loadCloud(dir.file("half_box.pcd"));
  const Eigen::Vector3d corner(500000.25, 5412345.5, 100.125);
  scan.coordinate_offset = corner;  // the points, 0..1, become corner + 0..1 in the file
  paco::io::saveCloud(dir.file("utm.xyz"), scan);
  std::string log;
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("utm.xyz")) + " --model " + quoted(dir.file("tiny.pt")) +
                                       " --threshold 1 --assembler cell-complex --known-extent 500000.25,5412345.5,"
                                       "100.125,500002.25,5412346.5,101.125 -o " + quoted(dir.file("utm.obj")),
                                   &log),
            0)
      << log;
  EXPECT_NE(log.find("working relative to (500000, 5412350, 100)"), std::string::npos) << log;
  const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("utm.obj"));
  EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  EXPECT_LT((lo - corner).cwiseAbs().maxCoeff(), 0.01) << log;
  EXPECT_LT((hi - corner - Eigen::Vector3d(2, 1, 1)).cwiseAbs().maxCoeff(), 0.01) << log;
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 0.05) << log;
  // The primitives: .vg in double precision, the coloured PCD in float32 for PCL (0.5 steps).
  const paco::io::VertexGroups groups = paco::io::loadVertexGroups(dir.file("utm.vg"));
  EXPECT_EQ(groups.coordinate_offset, Eigen::Vector3d(500000, 5412350, 100));
  const Eigen::Vector3d first = groups.points[0].getVector3fMap().cast<double>() + groups.coordinate_offset - corner;
  EXPECT_TRUE((first.array() > -0.01).all() && (first.array() < Eigen::Array3d(2.01, 1.01, 1.01)).all()) << first;
  const paco::io::LabelledCloud coloured = paco::io::loadCloud(dir.file("utm_primitives.pcd"));
  const Eigen::Vector3d near = coloured.points[0].getVector3fMap().cast<double>() + coloured.coordinate_offset - corner;
  EXPECT_TRUE((near.array() > -0.3).all() && (near.array() < Eigen::Array3d(2.3, 1.3, 1.3)).all()) << near;
}

// A building-like case: the box and its scan turned by 30 degrees about z, the extent given as
// the turned box's corners (a footprint at ground and roof height). The fill's box lies on the
// seen walls' axes, so it encloses those corners tightly: the full box, volume 2.
TEST(PacoReconstruct, AKnownFootprintInOtherAxesClosesTheTurnedBox) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  const Eigen::Matrix3d turn =
      Eigen::AngleAxisd(paco::degreesToRadians(30.0), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  writeHalfBoxScan(dir.file("turned_half_box.pcd"), turn);
  std::string footprint;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d corner = turn * Eigen::Vector3d((i & 1) ? 2 : 0, (i & 2) ? 1 : 0, (i & 4) ? 1 : 0);
    footprint += std::to_string(corner.x()) + " " + std::to_string(corner.y()) + " " + std::to_string(corner.z()) + "\n";
  }
  paco::test::writeBytes(dir.file("footprint.xyz"), footprint);
  std::string log;
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("turned_half_box.pcd")) + " --model " +
                                       quoted(dir.file("tiny.pt")) + " --threshold 1 --assembler cell-complex -o " +
                                       quoted(dir.file("turned.obj")) + " --known-extent " +
                                       quoted(dir.file("footprint.xyz")),
                                   &log),
            0)
      << log;
  const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("turned.obj"));
  EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
  EXPECT_NEAR(paco::signedVolume(mesh), 2.0, 0.05) << log;
}

TEST(PacoReconstruct, AKnownExtentMustBeABoxOrACloud) {
  TempDir dir;
  std::string log;
  // Anything but three finite numbers or six with X0 <= X1 is a usage error, and so is a known
  // extent without the fusion that uses it.
  const std::string bad = tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("bad.obj")) + " --known-extent ";
  EXPECT_EQ(paco::test::runCommand(bad + "1,2,3,4", &log), 2) << log;
  EXPECT_NE(log.find("(6 numbers), got 4"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(bad + "1,2,nan", &log), 2) << log;
  EXPECT_NE(log.find("'nan' in '1,2,nan' is not a finite number"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(bad + "0,0,0,1,1,x", &log), 2) << log;
  EXPECT_NE(log.find("'x' in '0,0,0,1,1,x' is not a finite number"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(bad + quoted(dir.file("no_such_footprint.xyz")), &log), 2) << log;
  EXPECT_NE(log.find("or an existing cloud file; there is no file"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(bad + "2,0,0,1,1,1", &log), 2) << log;
  EXPECT_NE(log.find("must not exceed"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(bad + "0,0,0,1,1,1 --no-fusion", &log), 2) << log;
  EXPECT_NE(log.find("drop --no-fusion"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(bad + "0,0,0,1,1,1 --no-completion", &log), 2) << log;
  EXPECT_FALSE(fs::exists(dir.file("bad.obj")));
}

// The scanner's direction or position: malformed values, both at once, a zero direction, a cell
// out of range and either without fusion are usage errors that leave no output.
TEST(PacoReconstruct, ScannerOptionsAreChecked) {
  TempDir dir;
  std::string log;
  const std::string base = tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("bad.obj"));
  const std::vector<std::pair<std::string, std::string>> cases = {
      {" --seen-from 0,0", "--seen-from takes X,Y,Z (a direction) (3 numbers), got 2"},
      {" --seen-from 0,0,z", "'z' in '0,0,z' is not a finite number"},
      {" --seen-from 0,0,0", "0,0,0 is none"},
      {" --seen-from-point 1,2", "--seen-from-point takes X,Y,Z"},
      {" --seen-from 0,0,1 --seen-from-point 0,0,5", "not both"},
      {" --seen-from 0,0,1 --scanner-cell 0", "--scanner-cell must be in (0, 1)"},
      {" --seen-from 0,0,1 --no-fusion", "drop --no-fusion"},
      {" --seen-from-point 0,0,5 --no-completion", "drop --no-completion"}};
  for (const auto& [options, message] : cases) {
    EXPECT_EQ(paco::test::runCommand(base + options, &log), 2) << options << "\n" << log;
    EXPECT_NE(log.find(message), std::string::npos) << options << "\n" << log;
  }
  EXPECT_FALSE(fs::exists(dir.file("bad.obj")));
}

// With a tiny candidate-face budget PolyFit must leave out the predicted primitives (the untrained
// model's, confidence < 1) and keep the seen faces, and the tool must say so.
TEST(PacoReconstruct, ReportsPrimitivesLeftOutForTheCandidateFaceBudget) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  std::string log;
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " --model " + quoted(dir.file("tiny.pt")) +
                                       " --threshold 0 --max-candidate-faces 10 -o " + quoted(dir.file("part.obj")),
                                   &log),
            0)
      << log;
  EXPECT_NE(log.find("least confident left out for --max-candidate-faces 10"), std::string::npos) << log;
  EXPECT_EQ(log.find(" 0 least confident left out"), std::string::npos) << log;
  EXPECT_TRUE(paco::analyseTopology(paco::io::loadMesh(dir.file("part.obj"))).isClosedManifold());
}

// A gable roof seen from above, and nothing else: two slopes at 25 degrees, 10 x 6 m, the ridge at
// height 5 along x turned by `heading_degrees` about z, written to `path` with normals.
void writeGableRoof(const std::string& path, double heading_degrees) {
  const Eigen::Matrix3f heading =
      Eigen::AngleAxisf(static_cast<float>(paco::degreesToRadians(heading_degrees)), Eigen::Vector3f::UnitZ())
          .toRotationMatrix();
  paco::io::LabelledCloud roof;
  roof.has_normals = true;
  const double slope = paco::degreesToRadians(25.0);
  for (const double side : {-1.0, 1.0})
    for (int i = 0; i < 40; ++i)
      for (int j = 0; j < 20; ++j) {
        const double across = side * 3.0 * (j + 0.5) / 20.0;  // from the ridge (y = 0) to an eave
        pcl::PointNormal p;
        p.getVector3fMap() = heading * Eigen::Vector3f(static_cast<float>(10.0 * (i + 0.5) / 40.0),
                                                       static_cast<float>(across),
                                                       static_cast<float>(5.0 - std::abs(across) * std::tan(slope)));
        p.getNormalVector3fMap() = heading * Eigen::Vector3f(0.0f, static_cast<float>(side * std::sin(slope)),
                                                             static_cast<float>(std::cos(slope)));
        roof.points.push_back(p);
      }
  paco::io::saveCloud(path, roof);
}

// No two seen planes of the roof are perpendicular, so the box fill's box is a guess (on the
// slopes' bisectors), and the tool says that --seen-from would set its walls along the lines of
// sight, and, unless --known-extent is given, that a point on the ground takes the walls down to it.
// With --seen-from 0,0,1, that note is gone, but no wall is seen, so the ground hint stays.
TEST(PacoReconstruct, AScanWithoutPerpendicularPlanesSuggestsTheScannersDirection) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  writeGableRoof(dir.file("roof.ply"), 0.0);
  const std::string base = tool() + " " + quoted(dir.file("roof.ply")) + " --model " + quoted(dir.file("tiny.pt")) +
                           " --assembler cell-complex -o " + quoted(dir.file("roof.obj"));
  const std::string note = "no two seen planes are perpendicular, so the box that closes the hidden side";
  std::string log;
  ASSERT_EQ(paco::test::runCommand(base, &log), 0) << log;
  EXPECT_NE(log.find(note), std::string::npos) << log;
  EXPECT_NE(log.find("--seen-from 0,0,1), say so"), std::string::npos) << log;
  const std::string ground = "a point on the ground (--known-extent X,Y,Z) takes the walls down to it";
  EXPECT_NE(log.find(ground), std::string::npos) << log;
  ASSERT_EQ(paco::test::runCommand(base + " --known-extent 5,0,-1", &log), 0) << log;  // given: no hint
  EXPECT_NE(log.find(note), std::string::npos) << log;
  EXPECT_EQ(log.find(ground), std::string::npos) << log;
  ASSERT_EQ(paco::test::runCommand(base + " --seen-from 0,0,1", &log), 0) << log;
  EXPECT_EQ(log.find(note), std::string::npos) << log;
  EXPECT_EQ(log.find("no two seen planes are perpendicular"), std::string::npos) << log;
  // Seen from above, no wall is seen either: the ground hint stays, unless the ground is given.
  const std::string no_wall = "no seen plane runs along the scanner's lines of sight (no wall seen)";
  EXPECT_NE(log.find(no_wall), std::string::npos) << log;
  EXPECT_NE(log.find(ground), std::string::npos) << log;
  ASSERT_EQ(paco::test::runCommand(base + " --seen-from 0,0,1 --known-extent 5,0,-1", &log), 0) << log;
  EXPECT_EQ(log.find(no_wall), std::string::npos) << log;
  EXPECT_EQ(log.find(ground), std::string::npos) << log;
  // Seen along the ridge, both slopes run along the lines of sight: they bound the depth, no note.
  ASSERT_EQ(paco::test::runCommand(base + " --seen-from 1,0,0", &log), 0) << log;
  EXPECT_EQ(log.find(no_wall), std::string::npos) << log;
}

// A --known-extent box lies on the input's axes and the fill's box on the seen faces': when they
// differ (the roof turned by 30 degrees), the fill encloses the given box with a larger one, and
// the tool says so and suggests points. A box on the seen axes, or points, draw no note.
TEST(PacoReconstruct, AKnownExtentBoxOffTheSeenAxesIsNoted) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  paco::io::LabelledCloud ground;
  ground.points.push_back(pcl::PointNormal());  // the origin: under the roof's first eave corner
  paco::io::saveCloud(dir.file("ground.xyz"), ground);
  const std::string note = "so it encloses the --known-extent box's corners with a larger box";
  std::string log;
  for (const double heading : {0.0, 30.0}) {
    SCOPED_TRACE(heading);
    writeGableRoof(dir.file("roof.ply"), heading);
    const std::string base = tool() + " " + quoted(dir.file("roof.ply")) + " --model " + quoted(dir.file("tiny.pt")) +
                             " --assembler cell-complex --seen-from 0,0,1 -o " + quoted(dir.file("roof.obj"));
    ASSERT_EQ(paco::test::runCommand(base + " --known-extent -4,-4,0,11,11,5", &log), 0) << log;
    EXPECT_EQ(log.find(note) != std::string::npos, heading > 0.0) << log;
    if (heading > 0.0) {
      EXPECT_NE(log.find("30.0 deg from the input's"), std::string::npos) << log;
    }
    ASSERT_EQ(paco::test::runCommand(base + " --known-extent " + quoted(dir.file("ground.xyz")), &log), 0) << log;
    EXPECT_EQ(log.find(note), std::string::npos) << log;
    ASSERT_EQ(paco::test::runCommand(base + " --known-extent 0,0,0", &log), 0) << log;
    EXPECT_EQ(log.find(note), std::string::npos) << log;
  }
}

// One point on the ground, given as X,Y,Z: the roof seen from above closes down to it instead of
// at its eaves (3.6 m). The network's guesses are left out (--threshold 1) so that the mesh is the
// seen slopes and the fill alone.
TEST(PacoReconstruct, AKnownPointOnTheGroundClosesARoofDownToIt) {
  TempDir dir;
  writeGableRoof(dir.file("roof.ply"), 30.0);
  const std::string base = tool() + " " + quoted(dir.file("roof.ply")) + " --threshold 1 --seen-from 0,0,1 -o ";
  std::string log;
  for (const std::string& ground : {std::string(), std::string(" --known-extent 2,1,0.5")}) {
    SCOPED_TRACE(ground);
    ASSERT_EQ(paco::test::runCommand(base + quoted(dir.file("roof.obj")) + ground, &log), 0) << log;
    const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("roof.obj"));
    EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold()) << log;
    Eigen::Vector3d lo, hi;
    paco::boundingBox(mesh, lo, hi);
    EXPECT_NEAR(lo.z(), ground.empty() ? 5.0 - 3.0 * std::tan(paco::degreesToRadians(25.0)) : 0.5, 0.05) << log;
    EXPECT_NEAR(hi.z(), 5.0, 0.05) << log;
  }
}
#endif

TEST(PacoReconstruct, TruncatedInputFailsWithoutOutputs) {
  TempDir dir;
  const std::string bytes = paco::test::readBytes(samplePath());
  paco::test::writeBytes(dir.file("cut.pcd"), bytes.substr(0, bytes.size() / 2));
  std::string log;
  const int rc = paco::test::runCommand(tool() + " " + quoted(dir.file("cut.pcd")) + " -o " +
                                            quoted(dir.file("part.obj")) + " --no-completion",
                                        &log);
  EXPECT_EQ(rc, 1) << log;
  EXPECT_NE(log.find("cut.pcd"), std::string::npos) << log;
  EXPECT_NE(log.find("truncated"), std::string::npos) << log;
  EXPECT_EQ(filesIn(dir.path()), 1u);
}

// Three points lie on a plane whatever they are: the completion made a closed box around them.
// Fewer than ten distinct points are refused, repeated points not counted; ten make a mesh.
TEST(PacoReconstruct, AHandfulOfPointsIsRefused) {
  TempDir dir;
  paco::test::writeBytes(dir.file("three.xyz"), "0 0 0\n1 0 0\n0 1 0\n");
  paco::test::writeBytes(dir.file("repeated.xyz"), "0 0 0\n1 0 0\n0 1 0\n0 0 0\n1 0 0\n0 1 0\n0 0 0\n1 0 0\n"
                                                   "0 1 0\n0 0 0\n1 0 0\n0 1 0\n");
  std::string log;
  for (const char* scan : {"three.xyz", "repeated.xyz"}) {
    SCOPED_TRACE(scan);
    EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file(scan)) + " -o " + quoted(dir.file("m.obj")), &log),
              1)
        << log;
    EXPECT_NE(log.find("the scan has 3 distinct points"), std::string::npos) << log;
    EXPECT_NE(log.find("it takes at least 10 to show a plane"), std::string::npos) << log;
    EXPECT_FALSE(fs::exists(dir.file("m.obj")));
  }
}

// A flat object's scan is one plane: no volume to close. The error says so and what to try.
TEST(PacoReconstruct, AFlatScanSaysWhyNoVolumeCloses) {
  TempDir dir;
  std::string grid;
  for (int i = 0; i < 30; ++i)
    for (int j = 0; j < 30; ++j) grid += std::to_string(i / 29.0) + " " + std::to_string(j / 29.0) + " 0\n";
  paco::test::writeBytes(dir.file("flat.xyz"), grid);
  std::string log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("flat.xyz")) + " -o " + quoted(dir.file("m.obj")) +
                                       " --no-completion",
                                   &log),
            1)
      << log;
  EXPECT_NE(log.find("too-few-planes"), std::string::npos) << log;
  EXPECT_NE(log.find("scan more of the object's sides"), std::string::npos) << log;
  EXPECT_EQ(filesIn(dir.path()), 1u);
}

TEST(PacoReconstruct, MissingModelIsAClearError) {
  TempDir dir;
  std::string log;
  const int rc = paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("part.obj")) +
                                            " --model " + quoted(dir.file("no_such_model.pt")),
                                        &log);
  EXPECT_EQ(rc, 1) << log;
  EXPECT_NE(log.find("no_such_model.pt"), std::string::npos) << log;
  EXPECT_EQ(filesIn(dir.path()), 0u);
}

// The number of planes in the "segment (...): N planes" line of a log.
std::size_t segmentedPlanes(const std::string& log) {
  std::smatch m;
  if (!std::regex_search(log, m, std::regex(R"(segment \(.*\): (\d+) planes)"))) return 0;
  return std::stoul(m[1].str());
}

// The sample scan has noise of 0.5 % of its diagonal, more than the segmenter's inlier distance
// (0.4 % of it): the tool widens the distance to the noise, and the part's faces are not broken
// into many planes as with --noise-adaptation 0. A clean scan keeps the distance.
TEST(PacoReconstruct, ANoisyScanWidensTheInlierDistance) {
  TempDir dir;
  std::string log;
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("adapted.obj")) +
                                       " --no-completion --assembler cell-complex",
                                   &log),
            0)
      << log;
  EXPECT_NE(log.find("inlier distance raised to"), std::string::npos) << log;
  const std::size_t adapted_planes = segmentedPlanes(log);
  EXPECT_TRUE(paco::analyseTopology(paco::io::loadMesh(dir.file("adapted.obj"))).isClosedManifold());

  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("fixed.obj")) +
                                       " --no-completion --assembler cell-complex --noise-adaptation 0",
                                   &log),
            0)
      << log;
  EXPECT_EQ(log.find("inlier distance raised"), std::string::npos) << log;
  const std::size_t fixed_planes = segmentedPlanes(log);
  // The part has 21 faces, about 15 of them seen.
  EXPECT_GE(adapted_planes, 10u);
  EXPECT_LE(adapted_planes, 21u);
  EXPECT_GT(fixed_planes, adapted_planes + 5) << "adapted " << adapted_planes;

  const std::string clean = dir.file("clean.pcd");
  writeHalfBoxScan(clean, Eigen::Matrix3d::Identity());
  ASSERT_EQ(paco::test::runCommand(tool() + " " + quoted(clean) + " -o " + quoted(dir.file("clean.obj")) +
                                       " --no-completion --assembler cell-complex",
                                   &log),
            0)
      << log;
  EXPECT_EQ(log.find("inlier distance raised"), std::string::npos) << log;
  EXPECT_EQ(segmentedPlanes(log), 5u) << log;
}

TEST(PacoReconstruct, BadOptionsAreUsageErrors) {
  std::string log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()), &log), 2) << log;
  EXPECT_NE(log.find("-o MESH"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --threshold 2", &log), 2) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --clip-margin near", &log), 2) << log;
  EXPECT_NE(log.find("--clip-margin must be a number >= 0 or 'off', got 'near'"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --fill-box -0.1", &log), 2) << log;
  EXPECT_NE(log.find("--fill-box must be 0 (off) or in [0.001, 1)"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --unseen-points 0", &log), 2) << log;
  EXPECT_NE(log.find("--unseen-points must be in (0, 1]"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --contradiction-radius 1", &log), 2)
      << log;
  EXPECT_NE(log.find("--contradiction-radius must be 0 (off) or in (0, 1)"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --max-points 100", &log), 2) << log;
  EXPECT_NE(log.find("--max-points must be 0 (keep all) or at least 256"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --min-points 2", &log), 2) << log;
  EXPECT_NE(log.find("--min-points must be 0 (1 % of the points) or at least 3, got 2"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --min-parallel-points 2", &log), 2)
      << log;
  EXPECT_NE(log.find("--min-parallel-points must be -1 (none), 0 (0.15 % of the points) or at least 3, got 2"),
            std::string::npos)
      << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o x.obj --noise-adaptation -1", &log), 2)
      << log;
  EXPECT_NE(log.find("--noise-adaptation must be 0 (off) or a positive number, got -1"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " --help", &log), 0) << log;
  EXPECT_NE(log.find("--no-completion"), std::string::npos);
  EXPECT_NE(log.find("--fill-box"), std::string::npos);
  EXPECT_NE(log.find("--unseen-points"), std::string::npos);
  EXPECT_NE(log.find("--contradiction-radius"), std::string::npos);
}

TEST(PacoReconstruct, UnknownBackendNamesAreRejectedBeforeAnyWork) {
  TempDir dir;
  std::string log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("m.obj")) +
                                       " --no-completion --segmenter nope",
                                   &log),
            1)
      << log;
  EXPECT_NE(log.find("nope"), std::string::npos) << log;
  EXPECT_EQ(filesIn(dir.path()), 0u);
}

// Output paths are checked before the input is read: a missing folder, a folder given as the
// mesh, or a wrong extension is a usage error naming the option, and nothing is written.
TEST(PacoReconstruct, OutputPathsAreCheckedBeforeAnyWork) {
  TempDir dir;
  const std::string run = tool() + " " + quoted(samplePath()) + " --no-completion -o ";
  std::string log;
  EXPECT_EQ(paco::test::runCommand(run + quoted(dir.file("missing/m.obj")), &log), 2) << log;
  EXPECT_NE(log.find("-o '" + dir.file("missing/m.obj") + "': the folder '" + dir.file("missing") +
                     "' does not exist; create it first"),
            std::string::npos)
      << log;
  EXPECT_EQ(log.find("read '"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(run + quoted(dir.file("m.obj")) + " --pcd " + quoted(dir.file("missing/p.pcd")), &log),
            2)
      << log;
  EXPECT_NE(log.find("--pcd '"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(run + quoted(dir.file("m.txt")), &log), 2) << log;
  EXPECT_NE(log.find("-o must name a .obj, .off, .ply or .stl file"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(run + quoted(dir.file("m.obj")) + " --vg " + quoted(dir.file("m.txt")), &log), 2)
      << log;
  EXPECT_NE(log.find("--vg must name a .vg or .bvg file"), std::string::npos) << log;
  std::filesystem::create_directory(dir.file("folder.obj"));
  EXPECT_EQ(paco::test::runCommand(run + quoted(dir.file("folder.obj")), &log), 2) << log;
  EXPECT_NE(log.find("is a folder; give a file name"), std::string::npos) << log;
  EXPECT_EQ(filesIn(dir.path()), 1u);  // the folder made above, nothing else
}

// Many scans in one run, the model loaded once: each good scan gets its three outputs, named after
// it in --output-dir; a truncated one is reported and skipped, and the run exits 1 naming it.
#ifdef PACO_TEST_WITH_COMPLETION
TEST(PacoReconstruct, AFolderOfScansIsReconstructedWithOneModelLoad) {
  TempDir dir;
  paco::PacoNetwork network(paco::test::tinyModelConfig());
  paco::saveCheckpoint(dir.file("tiny.pt"), network);
  const std::string moved = writeMovedSample(dir);
  const std::string bytes = paco::test::readBytes(samplePath());
  paco::test::writeBytes(dir.file("cut.pcd"), bytes.substr(0, bytes.size() / 2));
  const std::string out = dir.file("meshes");  // made by the run
  std::string log;
  const int rc = paco::test::runCommand(tool() + " " + quoted(samplePath()) + " " + quoted(dir.file("cut.pcd")) + " " +
                                            quoted(moved) + " --output-dir " + quoted(out) + " --format off --model " +
                                            quoted(dir.file("tiny.pt")) + " --threshold 1 --assembler cell-complex",
                                        &log);
  EXPECT_EQ(rc, 1) << log;
  EXPECT_NE(log.find("[1/3] '" + samplePath() + "'"), std::string::npos) << log;
  // The third scan's line says how long a scan takes and how long the rest will.
  const std::size_t third = log.find("[3/3, ");
  ASSERT_NE(third, std::string::npos) << log;
  const std::string third_line = log.substr(third, log.find('\n', third) - third);
  EXPECT_TRUE(std::regex_match(third_line, std::regex(R"(\[3/3, [0-9.]+ s per scan, about [0-9.]+ s left\] '.*')")))
      << third_line;
  EXPECT_NE(third_line.find("'" + moved + "'"), std::string::npos) << third_line;
  EXPECT_NE(log.find("cut.pcd': truncated"), std::string::npos) << log;
  EXPECT_NE(log.find("reconstructed 2 of 3 scans into '" + out + "'"), std::string::npos) << log;
  EXPECT_NE(log.find("1 of 3 scans failed (their messages are above): '" + dir.file("cut.pcd") + "'"),
            std::string::npos)
      << log;
  const std::size_t load = log.find("load model");  // in the timing totals, and only there
  EXPECT_NE(load, std::string::npos) << log;
  EXPECT_EQ(log.find("load model", load + 1), std::string::npos) << log;

  EXPECT_EQ(filesIn(out), 6u);  // two scans' mesh, .vg and .pcd; nothing of the truncated one, nothing partial
  for (const char* stem : {"sample_partial", "moved"}) {
    SCOPED_TRACE(stem);
    const paco::SurfaceMesh mesh = paco::io::loadMesh(out + "/" + stem + ".off");
    EXPECT_TRUE(paco::analyseTopology(mesh).isClosedManifold());
    EXPECT_GE(paco::io::loadVertexGroups(out + "/" + stem + ".vg").segmentation.size(), 4u);
    EXPECT_TRUE(fs::exists(out + "/" + stem + "_primitives.pcd"));
  }
  // Each mesh is in its own input's frame: the moved sample's is 250 times the sample's.
  Eigen::Vector3d min_a, max_a, min_b, max_b;
  paco::boundingBox(paco::io::loadMesh(out + "/sample_partial.off"), min_a, max_a);
  paco::boundingBox(paco::io::loadMesh(out + "/moved.off"), min_b, max_b);
  EXPECT_NEAR((max_b - min_b).norm() / (max_a - min_a).norm(), 250.0, 2.5);

  // A run where every scan fails leaves no folder behind it made.
  const std::string none = dir.file("none");
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(dir.file("cut.pcd")) + " --output-dir " + quoted(none) +
                                       " --no-completion",
                                   &log),
            1)
      << log;
  EXPECT_NE(log.find("reconstructed 0 of 1 scans"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(none)) << log;
}
#endif

TEST(PacoReconstruct, ManyInputsNeedAnOutputFolder) {
  TempDir dir;
  const std::string two = tool() + " " + quoted(samplePath()) + " " + quoted(dir.file("b.pcd")) + " --no-completion";
  fs::copy_file(samplePath(), dir.file("b.pcd"));
  std::string log;
  EXPECT_EQ(paco::test::runCommand(two + " -o " + quoted(dir.file("m.obj")), &log), 2) << log;
  EXPECT_NE(log.find("-o names one mesh, but 2 INPUTs were given: use --output-dir DIR"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(two, &log), 2) << log;
  EXPECT_NE(log.find("expected --output-dir DIR for 2 INPUTs"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(two + " -o " + quoted(dir.file("m.obj")) + " --output-dir " + quoted(dir.file("o")),
                                   &log),
            2)
      << log;
  EXPECT_NE(log.find("give -o MESH or --output-dir DIR, not both"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(two + " --output-dir " + quoted(dir.file("o")) + " --vg " + quoted(dir.file("p.vg")),
                                   &log),
            2)
      << log;
  EXPECT_NE(log.find("--vg and --pcd name one scan's outputs"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(two + " --output-dir " + quoted(dir.file("o")) + " --format xyz", &log), 2) << log;
  EXPECT_NE(log.find("--format must be obj, off, ply or stl, got 'xyz'"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " -o " + quoted(dir.file("m.obj")) +
                                       " --format ply --no-completion",
                                   &log),
            2)
      << log;
  EXPECT_NE(log.find("--format goes with --output-dir"), std::string::npos) << log;
  // Two inputs named alike would overwrite each other's mesh; one input twice is a slip.
  fs::create_directories(dir.file("other"));
  fs::copy_file(samplePath(), dir.file("other/b.pcd"));
  EXPECT_EQ(paco::test::runCommand(two + " " + quoted(dir.file("other/b.pcd")) + " --output-dir " + quoted(dir.file("o")),
                                   &log),
            2)
      << log;
  EXPECT_NE(log.find("would both be written as 'b.obj' in --output-dir"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(two + " " + quoted(dir.file("b.pcd")) + " --output-dir " + quoted(dir.file("o")), &log),
            2)
      << log;
  EXPECT_NE(log.find("INPUT '" + dir.file("b.pcd") + "' is given twice"), std::string::npos) << log;
  EXPECT_EQ(paco::test::runCommand(tool() + " " + quoted(samplePath()) + " " + quoted(dir.file("b.pcd")) +
                                       " --output-dir " + quoted(dir.file("o")) + " --known-extent 0,0,0",
                                   &log),
            2)
      << log;
  EXPECT_NE(log.find("--known-extent says where one object reaches"), std::string::npos) << log;
  paco::test::writeBytes(dir.file("file"), "x");
  EXPECT_EQ(paco::test::runCommand(two + " --output-dir " + quoted(dir.file("file")), &log), 2) << log;
  EXPECT_NE(log.find("--output-dir '" + dir.file("file") + "' is a file, not a folder"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(dir.file("o")));  // no usage error made the folder
  EXPECT_EQ(filesIn(dir.path()), 3u);       // b.pcd, other/, file
}

#ifdef PACO_CHAIN_STAGES_EXAMPLE
// The documentation's example chains the four classes by hand; it must keep working.
TEST(ChainStagesExample, RunsOnTheSampleScan) {
  TempDir dir;
  std::string log;
  const int rc = paco::test::runCommand(std::string("PACO_MODEL= ") + quoted(PACO_CHAIN_STAGES_EXAMPLE) + " " +
                                            quoted(samplePath()) + " " + quoted(dir.file("example.obj")),
                                        &log);
  ASSERT_EQ(rc, 0) << log;
  EXPECT_NE(log.find("segments:"), std::string::npos) << log;
  const paco::SurfaceMesh mesh = paco::io::loadMesh(dir.file("example.obj"));
  EXPECT_TRUE(paco::analyseTopology(mesh).isClosed());
}
#endif

}  // namespace
