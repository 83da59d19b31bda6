#include <paco/common/error.h>
#include <paco/data/builder.h>
#include <paco/data/dataset.h>
#include <paco/data/procedural.h>

#include "shapes.h"
#include "test_support.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

namespace {

using namespace paco::data;

/// Small sizes keep the tests fast; the format does not depend on them.
BuildOptions smallOptions() {
  BuildOptions options;
  options.info.levels = {0, 2};
  options.info.views = 3;
  options.info.input_points = 256;
  options.info.gt_points = 512;
  options.info.dense_points = 2048;
  options.info.seed = 4;
  return options;
}

TEST(DatasetSplit, FnvHashAndSplitRule) {
  EXPECT_EQ(fnv1a64(""), 14695981039346656037ull);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  int counts[3] = {0, 0, 0};
  for (int i = 0; i < 10000; ++i) {
    const std::string name = "part-" + std::to_string(i);
    const Split split = splitOf(name);
    EXPECT_EQ(split, splitOf(name));
    const std::uint64_t bucket = fnv1a64(name) % 100;
    EXPECT_EQ(split, bucket < 80 ? Split::Train : bucket < 90 ? Split::Val : Split::Test);
    ++counts[static_cast<int>(split)];
  }
  EXPECT_NEAR(counts[0] / 10000.0, 0.8, 0.02);
  EXPECT_NEAR(counts[1] / 10000.0, 0.1, 0.02);
  EXPECT_EQ(splitFromString(toString(Split::Val)), Split::Val);
  EXPECT_THROW(splitFromString("training"), paco::InvalidInputError);
}

TEST(DatasetBuild, SameSeedSameBytesOtherSeedOtherBytes) {
  BuildOptions options = smallOptions();
  options.info.augment_scale_min = 0.5;
  options.info.augment_scale_max = 2.0;
  options.info.augment_rotate = true;
  options.info.noise_percent = 1.0;
  const paco::SurfaceMesh mesh = generatePart(3);
  const std::string a = encodePartFile(buildPart("p", mesh, options));
  const std::string b = encodePartFile(buildPart("p", mesh, options));
  EXPECT_EQ(a, b);
  options.info.seed = 5;
  EXPECT_NE(a, encodePartFile(buildPart("p", mesh, options)));
}

TEST(DatasetBuild, AugmentationKeepsPlanesAndNormalisesTheAugmentedShape) {
  BuildOptions plain = smallOptions(), augmented = smallOptions();
  augmented.info.augment_scale_min = 0.5;
  augmented.info.augment_scale_max = 2.0;
  augmented.info.augment_rotate = true;
  const paco::SurfaceMesh mesh = paco::test::makeChamferedCube(0.25);
  const PartSamples a = buildPart("cube", mesh, plain), b = buildPart("cube", mesh, augmented);
  EXPECT_EQ(a.ground_truth.faces.size(), 7u);
  EXPECT_EQ(b.ground_truth.faces.size(), 7u);
  EXPECT_TRUE(a.augmentation.isIdentity());
  EXPECT_GT(b.augmentation.determinant(), 0.0);
  // Different parts get different augmentations; the same part the same.
  EXPECT_FALSE(augmentationFor("cube", augmented.info).isApprox(augmentationFor("other", augmented.info)));
  EXPECT_TRUE(augmentationFor("cube", augmented.info).isApprox(b.augmentation));
  for (const PartSamples* part : {&a, &b}) {
    Eigen::Vector3d lo, hi;
    paco::boundingBox(part->ground_truth.mesh, lo, hi);
    EXPECT_NEAR((hi - lo).norm(), 1.0, 1e-12);
    EXPECT_LT((hi + lo).norm(), 1e-12);
  }
  // The stored normalisation maps the augmented source into the sample frame.
  const Eigen::Vector3d v = b.augmentation * mesh.vertices[0];
  const Eigen::Vector3d w = b.normalization.apply(v);
  double nearest = 1e9;
  for (const auto& x : b.ground_truth.mesh.vertices) nearest = std::min(nearest, (x - w).norm());
  EXPECT_LT(nearest, 1e-12);
}

TEST(DatasetBuild, SegmentOptionLabelsWithPlanarSegmenterOrSaysItCannot) {
  BuildOptions options = smallOptions();
  options.info.levels = {0};
  options.info.input_points = 1024;
  options.segment = true;
  const paco::SurfaceMesh box = paco::test::makeBox({0, 0, 0}, {2, 1.5, 1});
  if (!segmentationAvailable()) {
    EXPECT_THROW(buildPart("box", box, options), paco::InvalidInputError);
    return;
  }
  const PartSamples part = buildPart("box", box, options);
  EXPECT_TRUE(part.labels_from_segmenter);
  for (const PartialSample& sample : part.samples) {
    // A box seen from a corner with 25 % missing shows at least three faces, which GoCoPP finds.
    std::set<int> segments(sample.labels.begin(), sample.labels.end());
    segments.erase(-1);
    EXPECT_GE(segments.size(), 3u);
  }
}

/// Points per segment label (label -1 left out).
std::map<int, int> segmentSizes(const std::vector<int>& labels) {
  std::map<int, int> sizes;
  for (int label : labels)
    if (label >= 0) ++sizes[label];
  return sizes;
}

TEST(DatasetBuild, SegmentMinimumsAreTheSmallestSegmentsAndZeroMeansTheToolsShare) {
  if (!segmentationAvailable()) GTEST_SKIP() << "built without the segmentation module";
  BuildOptions options = smallOptions();
  options.info.levels = {0};
  options.info.input_points = 1024;
  options.segment = true;
  // A procedural part: faces of many sizes, some far below 300 of the 1024 points.
  const paco::SurfaceMesh part = generatePart(7);

  options.info.segment_min_points = 300;
  const PartSamples coarse = buildPart("p", part, options);
  // The tools' rule: 1 % of 1024 points (10), and 0.25 % (3) on an exact sample like this one.
  options.info.segment_min_points = 0;
  const PartSamples fine = buildPart("p", part, options);
  ASSERT_EQ(coarse.samples.size(), fine.samples.size());
  std::size_t coarse_segments = 0, fine_segments = 0;
  int smallest_fine = std::numeric_limits<int>::max();
  for (std::size_t i = 0; i < fine.samples.size(); ++i) {
    const auto coarse_sizes = segmentSizes(coarse.samples[i].labels);
    const auto fine_sizes = segmentSizes(fine.samples[i].labels);
    for (const auto& [label, size] : coarse_sizes) EXPECT_GE(size, 300) << "segment " << label;
    for (const auto& [label, size] : fine_sizes) {
      EXPECT_GE(size, 3) << "segment " << label;
      smallest_fine = std::min(smallest_fine, size);
    }
    coarse_segments += coarse_sizes.size();
    fine_segments += fine_sizes.size();
  }
  EXPECT_GT(fine_segments, coarse_segments);
  EXPECT_LT(smallest_fine, 10) << "the exact-sample share, below 1 %";

  options.info.segment_min_points = -1;
  EXPECT_THROW(buildPart("p", part, options), paco::InvalidInputError);

  // Small planes parallel to a larger one are added as the tools add them: more segments than
  // with the 300-point rule alone, none below the parallel minimum.
  options.info.segment_min_points = 300;
  options.info.segment_min_parallel_points = 15;
  const PartSamples with_parallel = buildPart("p", part, options);
  std::size_t parallel_segments = 0;
  for (const auto& sample : with_parallel.samples) {
    const auto sizes = segmentSizes(sample.labels);
    for (const auto& [label, size] : sizes) EXPECT_GE(size, 15) << "segment " << label;
    parallel_segments += sizes.size();
  }
  EXPECT_GT(parallel_segments, coarse_segments);
}

TEST(DatasetInfo, SegmentMinimumsAreRecordedAndOldInfoFilesMeanFiftyWithoutParallelPlanes) {
  DatasetInfo info;
  info.input_labels_from_segmenter = true;
  info.segment_min_points = 0;
  EXPECT_EQ(DatasetInfo::parse(info.serialize(), "here").segment_min_points, 0);
  EXPECT_NE(info.describe().find("the tools' rule (1 %"), std::string::npos);
  info.segment_min_points = 31;
  EXPECT_EQ(DatasetInfo::parse(info.serialize(), "here").segment_min_points, 31);
  EXPECT_NE(info.describe().find("at least 31 points"), std::string::npos);
  // Written before the key existed: segmented with PlanarSegmenter's default, 50 points.
  const DatasetInfo old = DatasetInfo::parse("format_version\t1\ninput_labels_from_segmenter\t1\n", "old");
  EXPECT_EQ(old.segment_min_points, 50);
  EXPECT_EQ(old.segment_min_parallel_points, -1);  // and without small parallel planes
  info.segment_min_parallel_points = 0;
  EXPECT_EQ(DatasetInfo::parse(info.serialize(), "here").segment_min_parallel_points, 0);
  EXPECT_NE(info.describe().find("parallel to a larger one of at least the tools' share of the input's points (0.15 %"), std::string::npos);
  info.segment_min_parallel_points = 12;
  EXPECT_EQ(DatasetInfo::parse(info.serialize(), "here").segment_min_parallel_points, 12);
  // Without parallel planes the info file is the one written before the key existed, so such
  // datasets keep their identity and resume.
  info.segment_min_parallel_points = -1;
  EXPECT_EQ(info.serialize().find("segment_min_parallel_points"), std::string::npos);
  // Unsegmented datasets do not record it, so it never tells them apart.
  DatasetInfo plain;
  plain.segment_min_points = 0;
  EXPECT_EQ(plain.serialize(), DatasetInfo().serialize());
}

TEST(DatasetInfo, SingleScannerAndViewpointDistanceAreRecordedOnlyWhenNotTheDefault) {
  DatasetInfo info;
  info.mode = "visibility";
  const std::string stations = info.serialize();
  info.single_scanner = true;
  info.viewpoint_distance = 1.5;
  const DatasetInfo back = DatasetInfo::parse(info.serialize(), "here");
  EXPECT_TRUE(back.single_scanner);
  EXPECT_EQ(back.viewpoint_distance, 1.5);
  EXPECT_NE(info.describe().find("one scanner"), std::string::npos) << info.describe();
  // The defaults write the info file of before, so that such datasets keep their identity.
  info.single_scanner = false;
  info.viewpoint_distance = 1.0;
  EXPECT_EQ(info.serialize(), stations);
  EXPECT_EQ(stations.find("single_scanner"), std::string::npos);
  EXPECT_EQ(stations.find("viewpoint_distance"), std::string::npos);
  const DatasetInfo old = DatasetInfo::parse("format_version\t1\nmode\tvisibility\n", "old");
  EXPECT_FALSE(old.single_scanner);
  EXPECT_EQ(old.viewpoint_distance, 1.0);
}

TEST(DatasetIo, ReaderReadsBackWhatWasWritten) {
  paco::test::TempDir dir;
  const BuildOptions options = smallOptions();
  std::vector<PartSamples> parts;
  {
    DatasetWriter writer(dir.path().string(), options.info);
    for (int i = 0; i < 6; ++i) {
      parts.push_back(buildPart(proceduralPartName(i), generatePart(100 + i), options));
      writer.write(parts.back());
    }
    writer.fail("broken", "mesh is not closed: 3 boundary edges");
    EXPECT_TRUE(writer.isDone("proc-000002"));
    EXPECT_TRUE(writer.isDone("broken"));
  }
  const Dataset dataset(dir.path().string());
  EXPECT_EQ(dataset.parts().size(), 6u);
  std::size_t total = 0;
  for (Split split : {Split::Train, Split::Val, Split::Test}) total += dataset.size(split);
  EXPECT_EQ(total, 6u * 2 * 3);
  EXPECT_NE(dataset.description().find("nearest"), std::string::npos);
  EXPECT_NE(dataset.description().find("not PlanarSegmenter"), std::string::npos);

  for (Split split : {Split::Train, Split::Val, Split::Test}) {
    for (std::size_t i = 0; i < dataset.size(split); ++i) {
      const Sample s = dataset.load(split, i);
      EXPECT_EQ(splitOf(s.part), split);
      const PartSamples& part = parts.at(std::stoi(s.part.substr(5)));
      const int level_slot = s.level == MissingLevel::Simple ? 0 : 1;
      ASSERT_NE(s.level, MissingLevel::Moderate);
      const PartialSample& written = part.samples.at(level_slot * 3 + s.view);
      ASSERT_EQ(s.input.size(), 256u);
      ASSERT_EQ(s.gt_points.size(), 512u);
      for (std::size_t j = 0; j < s.input.size(); ++j) {
        EXPECT_EQ(s.input[j].x, static_cast<float>(written.points[j].x()));
        EXPECT_EQ(s.input[j].normal_z, static_cast<float>(written.normals[j].z()));
        EXPECT_EQ(s.input_labels[j], written.labels[j]);
      }
      EXPECT_EQ(s.gt_labels[7], part.gt.labels[7]);
      EXPECT_EQ(s.gt_points[9].y, static_cast<float>(part.gt.points[9].y()));
      ASSERT_EQ(s.gt_planes.size(), part.ground_truth.faces.size());
      EXPECT_EQ(s.gt_planes[0].offset, part.ground_truth.faces[0].plane.offset);
      EXPECT_EQ(s.gt_plane_areas[0], part.ground_truth.faces[0].area);
      EXPECT_EQ(s.normalization.scale, part.normalization.scale);
      EXPECT_NEAR(s.missing_ratio, written.missing_ratio, 1e-6);
      EXPECT_FALSE(s.input_labels_from_segmenter);
    }
  }
  // Ordered by part, level, view; select() filters.
  const std::size_t train = dataset.size(Split::Train);
  ASSERT_GT(train, 0u);
  const Sample first = dataset.load(Split::Train, 0), second = dataset.load(Split::Train, 1);
  EXPECT_EQ(first.part, second.part);
  EXPECT_EQ(first.view, 0);
  EXPECT_EQ(second.view, 1);
  const auto hard_view2 = dataset.select(Split::Train, MissingLevel::Hard, 2);
  EXPECT_EQ(hard_view2.size(), train / 6);
  for (std::size_t i : hard_view2) {
    const Sample s = dataset.load(Split::Train, i);
    EXPECT_EQ(s.level, MissingLevel::Hard);
    EXPECT_EQ(s.view, 2);
  }
  EXPECT_TRUE(dataset.select(Split::Train, MissingLevel::Moderate, std::nullopt).empty());
  const paco::SurfaceMesh gt_mesh = dataset.loadGtMesh(first);
  EXPECT_TRUE(paco::analyseTopology(gt_mesh).isClosedManifold());
  EXPECT_THROW(dataset.load(Split::Train, train), paco::InvalidInputError);
}

TEST(DatasetIo, WriterRefusesOtherOptionsAndReaderReportsDamage) {
  paco::test::TempDir dir;
  BuildOptions options = smallOptions();
  {
    DatasetWriter writer(dir.path().string(), options.info);
    writer.write(buildPart("a", paco::test::makeBox({0, 0, 0}, {1, 2, 3}), options));
  }
  EXPECT_EQ(DatasetWriter(dir.path().string(), options.info).numFinished(), 1u);  // resumes
  BuildOptions other = options;
  other.info.noise_percent = 3.0;
  EXPECT_THROW(DatasetWriter(dir.path().string(), other.info), paco::IoError);
  {
    // Segmented with another smallest plane is another dataset too.
    paco::test::TempDir segmented;
    other = options;
    other.info.input_labels_from_segmenter = true;
    other.info.segment_min_points = 0;
    DatasetWriter first(segmented.path().string(), other.info);
    other.info.segment_min_points = 50;
    EXPECT_THROW(DatasetWriter(segmented.path().string(), other.info), paco::IoError);
  }

  const Dataset intact(dir.path().string());
  const Split split = splitOf("a");
  ASSERT_EQ(intact.size(split), 6u);
  const std::string file = dir.file("parts/a.bin");
  const std::string bytes = paco::test::readBytes(file);
  paco::test::writeBytes(file, bytes.substr(0, bytes.size() - 100));
  EXPECT_NO_THROW(intact.load(split, 0));
  EXPECT_THROW(intact.load(split, 5), paco::IoError);
  paco::test::writeBytes(file, "garbage");
  EXPECT_THROW(intact.load(split, 0), paco::IoError);
  EXPECT_THROW(Dataset(dir.file("nothing-here")), paco::IoError);
}

TEST(DatasetIo, InterruptedIndexAppendIsDropped) {
  paco::test::TempDir dir;
  const BuildOptions options = smallOptions();
  {
    DatasetWriter writer(dir.path().string(), options.info);
    writer.write(buildPart("a", paco::test::makeBox({0, 0, 0}, {1, 1, 1}), options));
  }
  // A crash in the middle of an append leaves an unfinished line.
  const std::string index = paco::test::readBytes(dir.file("index.tsv"));
  paco::test::writeBytes(dir.file("index.tsv"), index + "b\ttrain\tparts/b.b");
  EXPECT_EQ(Dataset(dir.path().string()).parts().size(), 1u);
  DatasetWriter writer(dir.path().string(), options.info);
  EXPECT_FALSE(writer.isDone("b"));
  EXPECT_EQ(paco::test::readBytes(dir.file("index.tsv")), index);
}

}  // namespace
