// The baselines that need no other paco module: sanity, poisson-qem, the box prior, the registry.
#include <paco/common/error.h>
#include <paco/evaluation/methods.h>
#include <paco/evaluation/metrics.h>

#include <shapes.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace ev = paco::evaluation;

namespace {

pcl::PointCloud<pcl::PointNormal> sampleCloud(const paco::SurfaceMesh& mesh, std::size_t count, std::uint64_t seed) {
  const paco::SurfaceSample s = paco::sampleSurface(mesh, count, seed);
  pcl::PointCloud<pcl::PointNormal> cloud;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    pcl::PointNormal p;
    p.getVector3fMap() = s.points[i].cast<float>();
    p.getNormalVector3fMap() = s.normals[i].cast<float>();
    cloud.push_back(p);
  }
  return cloud;
}

bool has(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

}  // namespace

TEST(Methods, SanityFailsEveryCaseOnPurpose) {
  const ev::MethodOutput out = ev::runMethod("sanity", ev::MethodInput{}, ev::MethodOptions{});
  EXPECT_EQ(out.reason, ev::FailureReason::Sanity);
  EXPECT_FALSE(out.has_mesh);
  EXPECT_FALSE(ev::methodUsesAssembler("sanity"));
  EXPECT_FALSE(ev::methodUsesAssembler("poisson-qem"));
  EXPECT_TRUE(ev::methodUsesAssembler("direct"));
}

TEST(Methods, UnknownOrUnbuiltMethodSaysWhy) {
  try {
    ev::runMethod("paco", ev::MethodInput{}, ev::MethodOptions{});
    if (!has(ev::availableMethods(), "paco")) FAIL() << "expected an error";
  } catch (const paco::InvalidInputError& e) {
    EXPECT_NE(std::string(e.what()).find("paco::completion"), std::string::npos) << e.what();
  }
  EXPECT_THROW(ev::runMethod("nonsense", ev::MethodInput{}, ev::MethodOptions{}), paco::InvalidInputError);
}

TEST(Methods, RegisteredMethodRunsAndItsExceptionBecomesAFailure) {
  ev::registerMethod(
      "test-throws", [](const ev::MethodInput&, const ev::MethodOptions&) -> ev::MethodOutput {
        throw paco::InvalidInputError("broken on purpose");
      },
      false);
  EXPECT_TRUE(has(ev::availableMethods(), "test-throws"));
  const ev::MethodOutput out = ev::runMethod("test-throws", ev::MethodInput{}, ev::MethodOptions{});
  EXPECT_EQ(out.reason, ev::FailureReason::Threw);
  EXPECT_EQ(out.message, "broken on purpose");
  EXPECT_TRUE(out.seconds.count("total"));
}

TEST(Methods, RepeatedPointsAreLeftOutAndDenseInputsThinnedFirst) {
  if (!has(ev::availableMethods(), "direct")) GTEST_SKIP() << "built without paco::segmentation";
  // A method that reports how many input points and labels it was given.
  ev::registerMethod(
      "test-counts", [](const ev::MethodInput& in, const ev::MethodOptions&) {
        ev::MethodOutput out;
        out.message = std::to_string(in.input.size()) + " " + std::to_string(in.input_labels.size());
        return out;
      },
      false);
  ev::MethodInput in;
  in.input = sampleCloud(paco::test::makeBox({0, 0, 0}, {1, 1, 1}), 3000, 5);
  in.input_labels.assign(in.input.size(), 0);
  ev::MethodOptions options;
  EXPECT_EQ(options.max_input_points, 20000u);
  EXPECT_EQ(ev::runMethod("test-counts", in, options).message, "3000 3000");  // within the budget
  options.max_input_points = 1000;
  const std::string thinned = ev::runMethod("test-counts", in, options).message;
  const std::size_t kept = std::stoul(thinned.substr(0, thinned.find(' ')));
  EXPECT_LE(kept, 1000u);
  EXPECT_GE(kept, 850u);
  EXPECT_EQ(thinned.substr(thinned.find(' ')), " 0") << "labels of the full input no longer apply";
  options.use_dataset_labels = true;  // labels name input points: nothing is thinned
  EXPECT_EQ(ev::runMethod("test-counts", in, options).message, "3000 3000");
  // Repeated points are left out whatever the budget.
  options = ev::MethodOptions{};
  const pcl::PointCloud<pcl::PointNormal> copy = in.input;  // += of itself would insert from itself
  in.input += copy;
  EXPECT_EQ(ev::runMethod("test-counts", in, options).message, "3000 0");
}

TEST(PoissonQem, ReconstructsABoxWithTheTargetFaceCount) {
  if (!has(ev::availableMethods(), "poisson-qem")) GTEST_SKIP() << "built without CGAL";
  const paco::SurfaceMesh box = paco::test::makeBox({-0.3, -0.25, -0.2}, {0.3, 0.25, 0.2});
  ev::MethodInput in;
  in.input = sampleCloud(box, 2048, 3);
  ev::MethodOptions options;
  options.qem_target_faces = 40;
  const ev::MethodOutput out = ev::runMethod("poisson-qem", in, options);
  ASSERT_TRUE(out.has_mesh) << out.message;
  EXPECT_EQ(out.reason, ev::FailureReason::None);
  EXPECT_LE(out.mesh.faces.size(), 44u);
  EXPECT_GE(out.mesh.faces.size(), 12u);
  EXPECT_TRUE(out.seconds.count("reconstruct"));
  EXPECT_TRUE(out.seconds.count("simplify"));
  const ev::MeshMetrics m = ev::evaluateMesh(out.mesh, box);
  EXPECT_LT(m.chamfer, 6.0);  // a rounded box: well below the failure box of a non-box part
  EXPECT_GT(m.normal_consistency, 0.85);
  EXPECT_THROW(ev::reconstructPoissonQem(pcl::PointCloud<pcl::PointNormal>{}, 40), paco::InvalidInputError);
}

TEST(BoxPrior, FillsTheMissingFaceOfABox) {
  // A box seen without its top: the five visible faces as primitives; the prior must add points
  // on the top face (z = 0.2), and only there.
  const paco::SurfaceMesh box = paco::test::makeBox({-0.3, -0.25, -0.2}, {0.3, 0.25, 0.2});
  pcl::PointCloud<pcl::PointNormal> all = sampleCloud(box, 4000, 5), seen;
  for (const auto& p : all)
    if (p.z < 0.2f - 1e-6f) seen.push_back(p);
  std::vector<paco::PlanarPrimitive> visible;
  for (const Eigen::Vector3d& n : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(-1, 0, 0), Eigen::Vector3d(0, 1, 0),
                                   Eigen::Vector3d(0, -1, 0), Eigen::Vector3d(0, 0, -1)}) {
    paco::PlanarPrimitive prim;
    for (const auto& p : seen)
      if (p.getNormalVector3fMap().cast<double>().dot(n) > 0.99) prim.points.push_back(p);
    prim.plane = paco::Plane::fromPointAndNormal(prim.points[0].getVector3fMap().cast<double>(), n);
    visible.push_back(prim);
  }
  std::size_t before = 0;
  for (const auto& p : visible) before += p.points.size();
  const auto completed = ev::addBoundingBoxPrior(seen, visible);
  ASSERT_EQ(completed.size(), 6u);
  const paco::PlanarPrimitive& top = completed.back();
  EXPECT_GT(std::abs(top.plane.normal.z()), 0.99);
  EXPECT_GT(top.points.size(), 100u);
  for (const auto& p : top.points) EXPECT_NEAR(p.z, 0.2, 0.01);
  std::size_t after = 0;
  for (std::size_t i = 0; i < 5; ++i) after += completed[i].points.size();
  EXPECT_EQ(after, before);  // the observed faces had no empty parts
}

// An L bracket (a unit square with its 0.6 x 0.6 corner cut out, 0.6 high): six planes on the
// convex hull and the two walls of the notch, which are not.
TEST(OracleSeenHull, KeepsTheSeenFacesAndTheHullAndClosesOverAnUnseenNotch) {
  if (!has(ev::availableMethods(), "oracle-seen-hull")) GTEST_SKIP() << "built without paco::assembly";
  const double a = 1.0, b = 0.4, h = 0.6;
  const paco::SurfaceMesh bracket = paco::test::makeLBracket(a, b, h);
  const std::vector<paco::Plane> planes = {
      paco::Plane({-1, 0, 0}, 0), paco::Plane({0, -1, 0}, 0), paco::Plane({1, 0, 0}, -a), paco::Plane({0, 1, 0}, -a),
      paco::Plane({0, 0, -1}, 0), paco::Plane({0, 0, 1}, -h),
      paco::Plane({1, 0, 0}, -b), paco::Plane({0, 1, 0}, -b)};  // the notch's walls
  ev::MethodInput in;
  in.gt_points = sampleCloud(bracket, 8000, 7);
  in.gt_planes = planes;
  for (const auto& p : in.gt_points) {
    int label = -1;
    for (std::size_t k = 0; k < planes.size(); ++k)
      if (planes[k].normal.dot(p.getNormalVector3fMap().cast<double>()) > 0.99 &&
          std::abs(planes[k].signedDistance(p.getVector3fMap().cast<double>())) < 1e-5)
        label = static_cast<int>(k);
    ASSERT_GE(label, 0) << p;
    in.gt_labels.push_back(label);
  }
  // The scan: the GT points of the given planes, labelled with them.
  auto scanOf = [&](const std::vector<int>& seen_planes) {
    in.input.clear();
    in.input_labels.clear();
    for (std::size_t i = 0; i < in.gt_points.size(); ++i)
      if (std::count(seen_planes.begin(), seen_planes.end(), in.gt_labels[i])) {
        in.input.push_back(in.gt_points[i]);
        in.input_labels.push_back(in.gt_labels[i]);
      }
  };
  ev::MethodOptions options;
  options.assembler = "cell-complex";

  scanOf({0, 5});  // the x = 0 side and the top: the notch is not seen
  ev::MethodOutput out = ev::runMethod("oracle-seen-hull", in, options);
  ASSERT_TRUE(out.has_mesh) << out.message;
  ASSERT_EQ(out.planes.size(), 6u);
  for (const paco::Plane& p : out.planes)
    EXPECT_TRUE(std::abs(p.offset + b) > 1e-6 || std::abs(p.normal.z()) > 0.99) << "a notch wall was kept";
  EXPECT_NEAR(paco::signedVolume(out.mesh), a * a * h, 0.01 * a * a * h);  // the bounding box

  scanOf({0, 5, 6, 7});  // the notch seen too: every plane, the bracket itself
  out = ev::runMethod("oracle-seen-hull", in, options);
  ASSERT_TRUE(out.has_mesh) << out.message;
  EXPECT_EQ(out.planes.size(), 8u);
  EXPECT_NEAR(paco::signedVolume(out.mesh), h * (a * a - (a - b) * (a - b)), 0.01 * a * a * h);

  in.input_labels_from_segmenter = true;  // segment ids, not GT faces: the method refuses them
  out = ev::runMethod("oracle-seen-hull", in, options);
  EXPECT_EQ(out.reason, ev::FailureReason::Threw);
  EXPECT_NE(out.message.find("PlanarSegmenter"), std::string::npos) << out.message;

  in.input_labels_from_segmenter = false;
  in.input_labels.pop_back();  // a label short: the method says so, and the case fails
  out = ev::runMethod("oracle-seen-hull", in, options);
  EXPECT_EQ(out.reason, ev::FailureReason::Threw);
  EXPECT_NE(out.message.find("label"), std::string::npos) << out.message;
}
