// Where a partial scan stops short of its part, and whether the network's planes go further.
// Usage: paco_extent_check DATASET_DIR SPLIT CASES LEVEL [MODEL]
// Takes the first CASES view-0 samples of SPLIT (train|val|test) at LEVEL (0, 1, 2) of a
// paco_dataset folder. For each of the six sides of the boxes (axis-aligned in the GT's
// normalised frame), it compares the box of the input points (the seen box, where the fusion's
// box fill closes the part) with the box of the GT points:
//  - "short": the GT reaches more than 0.03 (of the GT's diagonal) beyond the seen box;
//  - "seen face": the scan shows a face at the seen box's side: at least 1 % of the input points
//    lie within 1 % of the seen box's diagonal of it, with normals within 25 degrees of its axis;
//  - the network's farthest plane on that side: among the completed primitives (the tools'
//    segmentation and four turns, MODEL or the shipped model, confidence above 0.7) whose normal
//    is within 15 degrees of the axis, the farthest one along it.
// It prints how many sides are short and by how much, how well "no seen face" tells a short side,
// and whether the network's planes reach beyond the seen box on the short sides
// (doc/results.md, "The hidden extent").
#include <paco/common/error.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/data/dataset.h>
#include <paco/encoding/completion_model.h>
#include <paco/segmentation/segmentation.h>

#include <pcl/console/print.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <string>

namespace {

constexpr double kShortGap = 0.03;           // GT diagonal is 1 in the normalised frame
constexpr double kFaceBand = 0.01;           // of the seen box's diagonal
constexpr double kFaceShare = 0.01;          // of the input points
constexpr double kFaceNormalCos = 0.906;     // cos 25 degrees
constexpr double kPlaneNormalCos = 0.966;    // cos 15 degrees

struct Tally {
  int sides = 0, short_sides = 0, unseen_face_sides = 0, unseen_face_short = 0;
  int short_without_face = 0, short_with_plane = 0, short_with_plane_beyond = 0;
  double short_gap_sum = 0.0, unseen_face_gap_sum = 0.0, short_plane_offset_sum = 0.0;
};

double mean(double sum, int n) { return n > 0 ? sum / n : std::numeric_limits<double>::quiet_NaN(); }

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5 || argc > 6) {
    std::fprintf(stderr, "usage: %s DATASET_DIR SPLIT CASES LEVEL [MODEL]\n", argv[0]);
    return 2;
  }
  try {
    const paco::data::Dataset dataset(argv[1]);
    const paco::data::Split split = paco::data::splitFromString(argv[2]);
    const std::size_t limit = std::stoul(argv[3]);
    const int level = std::stoi(argv[4]);
    if (level < 0 || level > 2) throw paco::InvalidInputError("LEVEL must be 0, 1 or 2, got " + std::string(argv[4]));
    const std::string model_path = argc == 6 ? argv[5] : paco::CompletionModel::findShippedModel();
    if (model_path.empty()) throw paco::ModelError("no shipped model in this tree: pass MODEL");
    paco::CompletionModel::setThreads(1);
    const paco::CompletionModel::ConstPtr model = paco::CompletionModel::load(model_path);
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);

    Tally t;
    std::size_t cases = 0;
    for (const std::size_t index : dataset.select(split, static_cast<paco::data::MissingLevel>(level), 0)) {
      if (cases == limit) break;
      ++cases;
      const paco::data::Sample sample = dataset.load(split, index);
      const auto cloud = sample.input.makeShared();
      auto segmenter = paco::makePlanarSegmenter<pcl::PointNormal>("gocopp");
      paco::setScanDefaults(*segmenter, cloud->size(), 0, 0);
      segmenter->setInputCloud(cloud);
      paco::PlanarSegmentation segmentation;
      segmenter->segment(segmentation);
      const std::vector<paco::PlanarPrimitive> completed =
          segmentation.empty() ? std::vector<paco::PlanarPrimitive>{}
                               : paco::completeWithTurns(model, cloud, segmentation, paco::TurnEnsembleOptions{});

      Eigen::AlignedBox3d seen_box, gt_box;
      for (const auto& p : *cloud) seen_box.extend(p.getVector3fMap().cast<double>());
      for (const auto& p : sample.gt_points) gt_box.extend(p.getVector3fMap().cast<double>());
      const double seen_diagonal = seen_box.diagonal().norm();
      for (int axis = 0; axis < 3; ++axis) {
        for (const double sign : {1.0, -1.0}) {
          // How far each box reaches along sign * axis.
          const double seen_end = sign > 0 ? seen_box.max()[axis] : -seen_box.min()[axis];
          const double gt_end = sign > 0 ? gt_box.max()[axis] : -gt_box.min()[axis];
          const double gap = gt_end - seen_end;
          std::size_t face_points = 0;
          for (const auto& p : *cloud) {
            const double along = sign * p.getVector3fMap().cast<double>()[axis];
            if (seen_end - along < kFaceBand * seen_diagonal &&
                std::abs(p.getNormalVector3fMap().cast<double>()[axis]) > kFaceNormalCos)
              ++face_points;
          }
          const bool seen_face = static_cast<double>(face_points) >= kFaceShare * static_cast<double>(cloud->size());
          double farthest = -std::numeric_limits<double>::infinity();
          for (const paco::PlanarPrimitive& primitive : completed) {
            const double c = sign * primitive.plane.normal[axis];
            if (std::abs(c) < kPlaneNormalCos) continue;
            farthest = std::max(farthest, -primitive.plane.offset / c);  // where the plane crosses the axis
          }
          const bool is_short = gap > kShortGap;
          ++t.sides;
          if (is_short) {
            ++t.short_sides;
            t.short_gap_sum += gap;
            if (!seen_face) ++t.short_without_face;
            if (std::isfinite(farthest)) {
              ++t.short_with_plane;
              t.short_plane_offset_sum += farthest - seen_end;
              if (farthest - seen_end > kFaceBand) ++t.short_with_plane_beyond;
            }
          }
          if (!seen_face) {
            ++t.unseen_face_sides;
            t.unseen_face_gap_sum += std::max(0.0, gap);
            if (is_short) ++t.unseen_face_short;
          }
        }
      }
    }
    std::printf("%zu cases, %d box sides; %d short of the GT by more than %.2f (mean gap %.3f of the GT's diagonal)\n",
                cases, t.sides, t.short_sides, kShortGap, mean(t.short_gap_sum, t.short_sides));
    std::printf("sides without a seen face: %d, of which short %d (mean gap over them %.3f); short sides without a "
                "seen face: %d of %d\n",
                t.unseen_face_sides, t.unseen_face_short, mean(t.unseen_face_gap_sum, t.unseen_face_sides),
                t.short_without_face, t.short_sides);
    std::printf("short sides with a completed plane along the axis: %d; its farthest one lies %.3f beyond the seen box "
                "on average, and more than %.2f beyond it on %d\n",
                t.short_with_plane, mean(t.short_plane_offset_sum, t.short_with_plane), kFaceBand,
                t.short_with_plane_beyond);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
