#include "shapes.h"
#include "test_support.h"
#include "tiny_model_config.h"

#include <paco/common/error.h>
#include <paco/common/orientation.h>
#include <paco/completion/checkpoint.h>
#include <paco/completion/hidden_extent.h>
#include <paco/completion/turn_ensemble.h>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <random>

namespace paco {
namespace {

TEST(HiddenExtent, BeyondIsHowFarTheWholeObjectReachesPastEachSideOfTheSeenBox) {
  ExtentObservation observation;
  observation.frame.center = Eigen::Vector3d(10, 0, 0);
  observation.frame.scale = 0.5;  // user units -> frame units
  observation.seen_box = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  // In the frame: x from -1 to 1.6, y from -1.2 to 0.5, z from -1 to 1.
  const std::vector<Eigen::Vector3d> whole = {{8, 0, -2}, {13.2, -2.4, 2}, {10, 1, 0}};
  const auto beyond = extentBeyond(observation, whole);
  const std::array<float, kBoxSides> expected = {0.0f, 0.2f, 0.0f, 0.6f, 0.0f, 0.0f};
  for (int s = 0; s < kBoxSides; ++s) EXPECT_NEAR(beyond[s], expected[s], 1e-6) << "side " << s;
}

TEST(HiddenExtent, CornersAreTheGrownBoxInTheUsersFrame) {
  HiddenExtent extent;
  extent.frame.center = Eigen::Vector3d(1, 2, 3);
  extent.frame.scale = 2.0;
  extent.frame.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  extent.seen_box = Eigen::AlignedBox3d(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(0.5, 0.5, 0.5));
  extent.beyond = {0, 0, 0, 1.0, 0, 0};  // the frame's +x side, 1 frame unit = 0.5 user units
  const Eigen::AlignedBox3d grown = extent.grownBox();
  EXPECT_DOUBLE_EQ(grown.max().x(), 1.5);
  EXPECT_DOUBLE_EQ(extent.largestInUserUnits(), 0.5);
  Eigen::AlignedBox3d user;
  for (const auto& c : extent.corners()) user.extend(c);
  ASSERT_EQ(extent.corners().size(), 8u);
  // The frame's +x is the user's -y (rotation user -> frame is +90 deg about z): the box reaches
  // 0.25 + 0.5 below the centre along y, 0.25 elsewhere.
  EXPECT_NEAR(user.min().y(), 2 - 0.75, 1e-12);
  EXPECT_NEAR(user.max().y(), 2 + 0.25, 1e-12);
  EXPECT_NEAR(user.min().x(), 1 - 0.25, 1e-12);
  EXPECT_NEAR(user.max().x(), 1 + 0.25, 1e-12);
  EXPECT_NEAR(user.max().z(), 3 + 0.25, 1e-12);
}

// A guess of 0.1 on every side of the scan's box, in the scan's own frame, then closeSidesOnSeenFaces.
HiddenExtent guessedEverywhereThenClosed(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                         const PlanarSegmentation& segmentation, std::size_t min_points = 10) {
  HiddenExtent extent;
  extent.frame = Normalization::fromBoundingBox(cloud);
  for (const auto& p : cloud) extent.seen_box.extend(extent.frame.apply(p.getVector3fMap().cast<double>()));
  extent.beyond.fill(0.1);
  closeSidesOnSeenFaces(extent, cloud, segmentation, 0.02, min_points);
  return extent;
}

// A 4 x 2 x 1 box scanned up to x = 3: every side but +x is a seen face of it. The +x side of the
// scan's box is reached by the edges of the faces across it, which a cut leaves as well.
TEST(HiddenExtent, SidesOnWhichASeenFaceLiesFacingOutAreClosed) {
  const test::FaceLabelledScan scan = test::scanByFace(test::makeBox({0, 0, 0}, {4, 2, 1}), 4096, 5,
                                                       [](const Eigen::Vector3d& p) { return p.x() <= 3.0; });
  const auto guessed = [&](const PlanarSegmentation& segmentation, std::size_t min_points = 10) {
    return guessedEverywhereThenClosed(*scan.cloud, segmentation, min_points);
  };
  const HiddenExtent extent = guessed(scan.segmentation);
  EXPECT_EQ(extent.closed_by_seen_face, (std::array<bool, kBoxSides>{true, true, true, false, true, true}));
  EXPECT_EQ(extent.beyond, (std::array<double, kBoxSides>{0, 0, 0, 0.1, 0, 0}));

  // A top whose plane faces into the object, or with fewer points than a trusted face, does not
  // close its side.
  const std::vector<std::size_t> counts = scan.segmentation.pointsPerSegment();
  std::size_t top = counts.size();
  for (std::size_t i = 0; i < counts.size(); ++i)
    if (scan.segmentation.planes[i].normal.z() > 0.99) top = i;
  ASSERT_LT(top, counts.size());
  PlanarSegmentation inward = scan.segmentation;
  inward.planes[top].normal = -inward.planes[top].normal;
  inward.planes[top].offset = -inward.planes[top].offset;
  EXPECT_FALSE(guessed(inward).closed_by_seen_face[5]);
  EXPECT_NEAR(guessed(inward).beyond[5], 0.1, 1e-12);
  EXPECT_FALSE(guessed(scan.segmentation, counts[top] + 1).closed_by_seen_face[5]);

  // A face facing up inside the walls of a box whose top was cut away (a shelf at z = 0.5, 0.1 of
  // the diagonal below the walls' upper edges) does not close the top either: it is not the
  // object's end.
  test::FaceLabelledScan shelf = test::scanByFace(test::makeBox({0, 0, 0}, {4, 2, 1}), 4096, 5,
                                                  [](const Eigen::Vector3d& p) { return p.z() <= 0.95; });
  pcl::PointIndices shelf_points;
  for (int i = 0; i < 200; ++i) {
    pcl::PointNormal p;
    p.x = 1.0f + 0.01f * static_cast<float>(i), p.y = 1.0f, p.z = 0.5f;
    p.normal_x = 0.0f, p.normal_y = 0.0f, p.normal_z = 1.0f;
    shelf_points.indices.push_back(static_cast<int>(shelf.cloud->size()));
    shelf.cloud->push_back(p);
    shelf.segmentation.labels.push_back(static_cast<int>(shelf.segmentation.planes.size()));
  }
  shelf.segmentation.planes.push_back(Plane(Eigen::Vector3d::UnitZ(), -0.5));
  shelf.segmentation.segments.push_back(shelf_points);
  shelf.segmentation.validate(shelf.cloud->size());
  const HiddenExtent open_top = guessedEverywhereThenClosed(*shelf.cloud, shelf.segmentation);
  EXPECT_EQ(open_top.closed_by_seen_face, (std::array<bool, kBoxSides>{true, true, true, true, true, false}));
  EXPECT_NEAR(open_top.beyond[5], 0.1, 1e-12);
}

// Examples whose +x side reaches 0.3 beyond the seen box exactly when their first feature is
// positive: a head must read it off the features.
std::vector<ExtentExample> signExamples(int count, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> normal;
  std::vector<ExtentExample> examples(static_cast<std::size_t>(count));
  for (auto& e : examples) {
    for (int f = 0; f < 5; ++f) e.features.push_back(normal(rng));
    e.beyond[3] = e.features[0] > 0.0f ? 0.3f : 0.0f;
  }
  return examples;
}

TEST(HiddenExtentHead, LearnsFromItsFeaturesWhichSideGoesOnAndHowFar) {
  const auto train = signExamples(400, 1), held_out = signExamples(200, 2);
  ExtentTrainingOptions options;
  options.epochs = 300;
  options.hidden = 32;
  options.batch = 64;
  std::vector<double> losses;
  options.after_epoch = [&](int, double l1) {
    losses.push_back(l1);
    return true;
  };
  const auto head = trainHiddenExtentModel(42, train, options);
  ASSERT_EQ(losses.size(), 300u);
  EXPECT_LT(losses.back(), 0.5 * losses.front());
  const double zero = meanAbsoluteExtentError(nullptr, held_out);
  EXPECT_NEAR(zero, 0.3 * 0.5 / 6, 0.01);  // about half the examples are short by 0.3 on one of six sides
  // A guess blind to the features does no better than 0 on all sides.
  EXPECT_LT(meanAbsoluteExtentError(head.get(), held_out), 0.5 * zero);
  EXPECT_EQ(head->networkFingerprint(), 42u);
  EXPECT_EQ(head->featureWidth(), 5);
}

TEST(HiddenExtentHead, StopsWhenAskedAfterAnEpoch) {
  ExtentTrainingOptions options;
  options.epochs = 50;
  int epochs = 0;
  options.after_epoch = [&](int epoch, double) {
    epochs = epoch;
    return epoch < 3;
  };
  trainHiddenExtentModel(1, signExamples(20, 3), options);
  EXPECT_EQ(epochs, 3);
}

TEST(HiddenExtentHead, RejectsNoExampleAndUnequalFeatures) {
  EXPECT_THROW(trainHiddenExtentModel(1, {}, {}), InvalidInputError);
  auto examples = signExamples(3, 4);
  examples[1].features.pop_back();
  EXPECT_THROW(trainHiddenExtentModel(1, examples, {}), InvalidInputError);
}

TEST(HiddenExtentHead, SavedAndLoadedPredictsTheSame) {
  test::TempDir dir;
  ExtentTrainingOptions options;
  options.epochs = 5;
  const auto examples = signExamples(50, 5);
  const auto head = trainHiddenExtentModel(7, examples, options);
  head->save(dir.file("head.pt"));
  const auto loaded = HiddenExtentModel::load(dir.file("head.pt"));
  EXPECT_EQ(loaded->networkFingerprint(), 7u);
  EXPECT_EQ(loaded->featureWidth(), 5);
  for (int i = 0; i < 5; ++i) {
    const auto a = head->predict(examples[i].features), b = loaded->predict(examples[i].features);
    for (int s = 0; s < kBoxSides; ++s) EXPECT_FLOAT_EQ(a[s], b[s]);
  }
  EXPECT_THROW(loaded->predict({1.0f, 2.0f}), InvalidInputError);
  EXPECT_FALSE(std::filesystem::exists(dir.file("head.pt.partial")));
}

TEST(HiddenExtentHead, LoadSaysWhatIsWrongWithABadFile) {
  test::TempDir dir;
  auto expectModelError = [](const std::string& path, const std::string& words) {
    try {
      HiddenExtentModel::load(path);
      ADD_FAILURE() << "no error for " << path;
    } catch (const ModelError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  expectModelError(dir.file("missing.pt"), "does not exist");
  ExtentTrainingOptions options;
  options.epochs = 1;
  trainHiddenExtentModel(7, signExamples(10, 6), options)->save(dir.file("head.pt"));
  const auto size = std::filesystem::file_size(dir.file("head.pt"));
  std::filesystem::copy_file(dir.file("head.pt"), dir.file("cut.pt"));
  std::filesystem::resize_file(dir.file("cut.pt"), size / 2);
  expectModelError(dir.file("cut.pt"), "corrupt or truncated");
  // A completion model is not a head.
  PacoNetwork net(test::tinyModelConfig());
  saveCheckpoint(dir.file("network.pt"), net);
  expectModelError(dir.file("network.pt"), "not a hidden-extent head");
}

// A tiny untrained network, saved and loaded as a user's model file is.
CompletionModel::ConstPtr tinyModel(const test::TempDir& dir, int seed) {
  torch::manual_seed(seed);
  PacoNetwork net(test::tinyModelConfig());
  saveCheckpoint(dir.file("tiny.pt"), net);
  return CompletionModel::load(dir.file("tiny.pt"));
}

// A 4 x 2 x 1 box whose scan stops at x = 12: the part from 12 to 14 was never seen.
struct CutBoxScan {
  pcl::PointCloud<pcl::PointNormal>::Ptr cloud;
  PlanarSegmentation segmentation;
  std::vector<Eigen::Vector3d> whole = {{10, -5, 3}, {14, -3, 4}};
  CutBoxScan() {
    test::FaceLabelledScan scan = test::scanByFace(test::makeBox({10, -5, 3}, {14, -3, 4}), 4096, 7,
                                                   [](const Eigen::Vector3d& p) { return p.x() <= 12.0; });
    cloud = scan.cloud;
    segmentation = std::move(scan.segmentation);
  }
};

TEST(HiddenExtentWithModel, AHeadFitToAScanGrowsItsBoxBackToTheWholeObject) {
  test::TempDir dir;
  const auto model = tinyModel(dir, 2);
  const CutBoxScan scan;

  const ExtentObservation observation = observeExtent(model, scan.cloud, scan.segmentation);
  ASSERT_EQ(static_cast<int>(observation.features.size()), model->config().global_width + 3);
  EXPECT_NEAR(observation.seen_box.diagonal().norm(), 1.0, 1e-6);  // the frame has the scan at unit diagonal
  const auto target = extentBeyond(observation, scan.whole);
  // The box's faces lie on the axes, so the frame keeps them there: one side is short by
  // 2 / diagonal(2, 2, 1) = 2/3, the others not at all.
  float largest = 0.0f, others = 0.0f;
  for (float b : target) largest = std::max(largest, b);
  for (float b : target) others += b;
  EXPECT_NEAR(largest, 2.0 / 3.0, 0.01);
  EXPECT_NEAR(others - largest, 0.0, 0.01);

  // Overfit the scan under the four turns the estimate averages over, each with its own target:
  // the head then guesses this scan's hidden extent under every turn, and the turned guesses,
  // mapped back side by side, agree on the whole box.
  std::vector<ExtentExample> examples;
  for (const Eigen::Matrix3d& turn : ensembleTurns(4)) {
    const ExtentObservation turned = observeExtent(model, scan.cloud, scan.segmentation, turn);
    examples.push_back({turned.features, extentBeyond(turned, scan.whole)});
  }
  EXPECT_NE(examples[1].beyond, examples[0].beyond);  // a half turn moves the short side
  ExtentTrainingOptions options;
  options.epochs = 1500;
  options.hidden = 16;
  options.learning_rate = 0.01;
  double last_l1 = 0.0;
  options.after_epoch = [&](int, double l1) {
    last_l1 = l1;
    return true;
  };
  const auto head = trainHiddenExtentModel(networkFingerprint(*model), examples, options);
  EXPECT_LT(last_l1, 0.01);
  for (int turns : {1, 4}) {
    SCOPED_TRACE(turns);
    const HiddenExtent extent = estimateHiddenExtent(model, *head, scan.cloud, scan.segmentation, turns);
    Eigen::AlignedBox3d guessed;
    for (const auto& c : extent.corners()) guessed.extend(c);
    EXPECT_NEAR(guessed.min().x(), 10.0, 0.1);
    EXPECT_NEAR(guessed.max().x(), 14.0, 0.1);
    EXPECT_NEAR(guessed.min().y(), -5.0, 0.1);
    EXPECT_NEAR(guessed.max().y(), -3.0, 0.1);
    EXPECT_NEAR(guessed.min().z(), 3.0, 0.1);
    EXPECT_NEAR(guessed.max().z(), 4.0, 0.1);
  }
  EXPECT_THROW(estimateHiddenExtent(model, *head, scan.cloud, scan.segmentation, 0), InvalidInputError);

  // Another network's head is refused.
  torch::manual_seed(3);
  PacoNetwork other(test::tinyModelConfig());
  saveCheckpoint(dir.file("other.pt"), other);
  const auto other_model = CompletionModel::load(dir.file("other.pt"));
  EXPECT_NE(networkFingerprint(*other_model), networkFingerprint(*model));
  EXPECT_THROW(estimateHiddenExtent(other_model, *head, scan.cloud, scan.segmentation), ModelError);
}

// The roof of a gable house, 4 wide and 6 long, ridge 3 high and eaves 2 high, turned 30 degrees
// about the vertical: only its two slopes are seen, and no two seen planes are perpendicular.
test::FaceLabelledScan gableRoofScan() {
  SurfaceMesh house = test::makePrism({{0, 0}, {4, 0}, {4, 2}, {2, 3}, {0, 2}}, 6.0);
  Eigen::Matrix3d upright;
  upright << 1, 0, 0, 0, 0, -1, 0, 1, 0;  // x stays, the profile's y goes up, the ridge runs along -y
  const Eigen::Matrix3d placement = Eigen::AngleAxisd(M_PI / 6, Eigen::Vector3d::UnitZ()).toRotationMatrix() * upright;
  const Eigen::Vector3d offset(5, -2, 1);
  test::transformMesh(house, placement, offset);
  return test::scanByFace(house, 4096, 11, [&](const Eigen::Vector3d& p) {
    const Eigen::Vector3d q = placement.transpose() * (p - offset);
    return q.y() > 2.001 && q.z() > 0.001 && q.z() < 5.999;  // the slopes, not the gable ends
  });
}

// The head's box must be the box fill's: the fill takes the corners of the head's grown box as
// its known extent, and corners of a box in another frame widen the fill's box on every side. A
// gable roof's fill box lies on the bisectors of its slopes (or around the lines of sight when the
// scanner's direction is known); with nothing guessed beyond the scan, the head's corners must
// then lie on the fill's box of the scan.
TEST(HiddenExtentWithModel, TheHeadsBoxIsTheBoxFillsBox) {
  test::TempDir dir;
  const auto model = tinyModel(dir, 2);
  const test::FaceLabelledScan scan = gableRoofScan();
  std::vector<Eigen::Vector3d> normals;
  std::vector<double> sizes;
  const std::vector<std::size_t> counts = scan.segmentation.pointsPerSegment();
  for (std::size_t i = 0; i < counts.size(); ++i)
    if (counts[i] > 0) {
      normals.push_back(scan.segmentation.planes[i].normal);
      sizes.push_back(static_cast<double>(counts[i]));
    }
  ASSERT_EQ(normals.size(), 2u);

  for (const Eigen::Vector3d& scanner : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, 1)}) {
    SCOPED_TRACE(scanner.transpose());
    const ClosingBoxAxes fill = closingBoxAxes(normals, sizes, scanner);
    ASSERT_TRUE(fill.axes.has_value());
    EXPECT_EQ(fill.on_mirror_pair, scanner.squaredNorm() == 0.0);
    // The fill's box is level: the vertical is one of its axes.
    EXPECT_NEAR((fill.axes->transpose() * Eigen::Vector3d::UnitZ()).cwiseAbs().maxCoeff(), 1.0, 1e-6);

    const ExtentObservation observation =
        observeExtent(model, scan.cloud, scan.segmentation, Eigen::Matrix3d::Identity(), scanner);
    HiddenExtent nothing_beyond;
    nothing_beyond.frame = observation.frame;
    nothing_beyond.seen_box = observation.seen_box;
    Eigen::AlignedBox3d fill_box, corner_box;
    for (const auto& p : *scan.cloud) fill_box.extend(fill.axes->transpose() * p.getVector3fMap().cast<double>());
    for (const auto& c : nothing_beyond.corners()) corner_box.extend(fill.axes->transpose() * c);
    EXPECT_TRUE(corner_box.min().isApprox(fill_box.min(), 1e-5)) << corner_box.min().transpose() << " against "
                                                                  << fill_box.min().transpose();
    EXPECT_TRUE(corner_box.max().isApprox(fill_box.max(), 1e-5)) << corner_box.max().transpose() << " against "
                                                                  << fill_box.max().transpose();
  }
  // The dominant seen planes alone (the head's frame before) put the box on one slope: the
  // vertical is on none of its axes.
  const Eigen::Matrix3d on_a_slope = seenPlanesRotation(scan.segmentation);
  EXPECT_LT((on_a_slope * Eigen::Vector3d::UnitZ()).cwiseAbs().maxCoeff(), 0.99);
}

// Every head shipped in models/extent was trained for the shipped network: retraining the network
// without training its heads again would make the tools refuse them.
TEST(HiddenExtentHead, EveryShippedHeadFitsTheShippedModel) {
  const std::filesystem::path models = std::filesystem::path(PACO_SOURCE_DIR) / "models";
  if (!std::filesystem::exists(models / "paco_cpu.pt")) GTEST_SKIP() << "no shipped model in " << models;
  const auto model = CompletionModel::load((models / "paco_cpu.pt").string());
  std::vector<std::string> heads;
  for (const auto& entry : std::filesystem::directory_iterator(models / "extent"))
    if (entry.path().extension() == ".pt") heads.push_back(entry.path().filename().string());
  std::sort(heads.begin(), heads.end());
  EXPECT_EQ(heads, (std::vector<std::string>{"mfcad_cube.pt", "mfcad_stretched.pt"}));
  for (const std::string& name : heads) {
    SCOPED_TRACE(name);
    const auto head = HiddenExtentModel::load((models / "extent" / name).string());
    EXPECT_NO_THROW(head->checkMatches(*model));
    EXPECT_EQ(head->featureWidth(), model->config().global_width + 3);
  }
}

}  // namespace
}  // namespace paco
