#pragma once
// The completion and observed-fusion steps of paco_reconstruct and paco_complete, timed and
// reported alike.
#include "app_support.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/common/normalization.h>
#include <paco/common/orientation.h>
#include <paco/common/point_types.h>
#include <paco/completion/hidden_extent.h>
#include <paco/completion/observed_fusion.h>
#include <paco/completion/parametric_completer.h>
#include <paco/completion/turn_ensemble.h>
#include <paco/io/cloud_io.h>

#include <Eigen/Geometry>
#include <boost/algorithm/string.hpp>
#include <boost/program_options.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace paco::app {

/// The fusion flags with the library's defaults (paco::ObservedFusionOptions).
inline FusionFlags libraryFusionFlags() {
  const ObservedFusionOptions defaults;
  return FusionFlags(defaults.align_unseen_degrees, defaults.clip_margin, defaults.tilt_margin, defaults.fill_spacing,
                     defaults.unseen_point_fraction, defaults.contradiction_radius, defaults.join_distance);
}

/// "complete: N primitives with confidence > T", how many turns voted, and how far the scan was
/// turned for the network (models with input orientation "seen-planes"), so that a user sees
/// what the model was given.
inline void reportCompletion(std::size_t primitives, double threshold, int turns, const Normalization& frame) {
  const double degrees = paco::radiansToDegrees(Eigen::AngleAxisd(frame.rotation).angle());
  std::printf("complete: %zu primitives with confidence > %.2f", primitives, threshold);
  if (turns > 1) std::printf(" (voted over %d turns of the scan)", turns);
  if (degrees > 0.05) std::printf(" (the scan turned by %.1f deg onto its seen faces for the network)", degrees);
  std::printf("\n");
}

/// Stages 2-3: encodes and completes the scan, the network run on `turns` turns of it and the
/// planes voted on (paco::completeWithTurns), timed as "complete" (encoder and network).
inline std::vector<PlanarPrimitive> completeScan(const CompletionModel::ConstPtr& model,
                                                 const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                                                 const PlanarSegmentation& segmentation, double threshold, int turns,
                                                 int points, StageTimer& timer) {
  TurnEnsembleOptions options;
  options.turns = turns;
  options.threshold = threshold;
  options.num_points = points;
  Normalization frame;
  timer.start("complete");
  std::vector<PlanarPrimitive> primitives = completeWithTurns(model, cloud, segmentation, options, &frame);
  timer.stop();
  reportCompletion(primitives.size(), threshold, turns, frame);
  return primitives;
}

/// The --turns option of the tools that complete (TurnEnsembleOptions::turns).
inline void addTurnsOption(boost::program_options::options_description& options, int& turns) {
  options.add_options()("turns", boost::program_options::value(&turns)->default_value(turns),
                        "run the network on this many 90-degree turns of the scan and keep the planes most turns "
                        "predict (1 to 24; 1: once)");
}

/// Throws UsageError unless 1 <= turns <= kMaxEnsembleTurns.
inline void checkTurns(int turns) {
  if (turns < 1 || turns > kMaxEnsembleTurns)
    throw UsageError("--turns must be 1 to " + std::to_string(kMaxEnsembleTurns) + ", got " + std::to_string(turns));
}

/// Comma-separated finite numbers of `option`, exactly `count` of them ("X,Y,Z"); UsageError
/// otherwise, saying what `option` takes (`form`).
inline std::vector<double> parseNumbers(const std::string& option, const std::string& form, const std::string& text,
                                        std::size_t count) {
  std::vector<std::string> items;
  boost::algorithm::split(items, text, boost::is_any_of(","));
  std::vector<double> values;
  for (const std::string& item : items) {
    std::size_t used = 0;
    double value = std::nan("");
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(value))
      throw UsageError(option + " takes " + form + "; '" + item + "' in '" + text + "' is not a finite number");
    values.push_back(value);
  }
  if (values.size() != count)
    throw UsageError(option + " takes " + form + " (" + std::to_string(count) + " numbers), got " +
                     std::to_string(values.size()));
  return values;
}

/// The points of --known-extent: the cloud in the file `text` names when it exists, else the
/// point "X,Y,Z" or the corners of the box "X0,Y0,Z0,X1,Y1,Z1"; none for empty text. Throws
/// UsageError unless the text is three or six finite numbers (a box with X0 <= X1, Y0 <= Y1 and
/// Z0 <= Z1), and IoError for a cloud file that cannot be read.
inline std::vector<Eigen::Vector3d> parseKnownExtent(const std::string& text) {
  if (text.empty()) return {};
  if (std::filesystem::is_directory(text))
    throw UsageError("--known-extent '" + text + "' is a folder; give a cloud file, a point X,Y,Z or a box");
  if (std::filesystem::is_regular_file(text)) {
    io::LabelledCloud cloud;
    try {
      cloud = io::loadCloud(text);  // finite: checked
    } catch (const IoError& e) {
      throw IoError(std::string("--known-extent: ") + e.what());
    }
    std::vector<Eigen::Vector3d> points = positionsOf(cloud.points);
    if (points.empty()) throw IoError("--known-extent: '" + text + "' has no points");
    for (Eigen::Vector3d& p : points) p += cloud.coordinate_offset;  // the file's coordinates
    return points;
  }
  const std::string form = "X,Y,Z (a point), X0,Y0,Z0,X1,Y1,Z1 (a box) or an existing cloud file";
  // Without a comma it cannot be a point or a box: most likely a file name with a typo.
  if (text.find(',') == std::string::npos)
    throw UsageError("--known-extent takes " + form + "; there is no file '" + text + "'");
  // One point is enough where the scan stops short on one side only: the ground under an
  // airborne scan's roof.
  if (std::count(text.begin(), text.end(), ',') == 2) {
    const std::vector<double> p = parseNumbers("--known-extent", form, text, 3);
    return {Eigen::Vector3d(p[0], p[1], p[2])};
  }
  const std::vector<double> values = parseNumbers("--known-extent", form, text, 6);
  const Eigen::AlignedBox3d box(Eigen::Vector3d(values[0], values[1], values[2]),
                                Eigen::Vector3d(values[3], values[4], values[5]));
  if ((box.min().array() > box.max().array()).any())
    throw UsageError("--known-extent: X0,Y0,Z0 must not exceed X1,Y1,Z1 (got '" + text + "')");
  std::vector<Eigen::Vector3d> corners;
  for (int i = 0; i < 8; ++i) corners.push_back(box.corner(static_cast<Eigen::AlignedBox3d::CornerType>(i)));
  return corners;
}

/// What a user may know about a scan besides its points, for the fusion step: where the object
/// reaches (ObservedFusionOptions::known_extent_points) and where the scanner was
/// (scanner_direction / scanner_position / scanner_cell).
struct ScanKnowledge {
  std::vector<Eigen::Vector3d> known_extent;
  /// --known-extent was X0,Y0,Z0,X1,Y1,Z1: a box on the input's axes, not a point or a file of points.
  bool known_extent_is_box = false;
  /// --extent-head: a hidden-extent head whose guess becomes `known_extent` (guessHiddenExtent).
  std::string extent_head;
  Eigen::Vector3d scanner_direction = Eigen::Vector3d::Zero();
  std::optional<Eigen::Vector3d> scanner_position;
  double scanner_cell = ObservedFusionOptions().scanner_cell;

  bool empty() const {
    return known_extent.empty() && extent_head.empty() && scanner_direction.squaredNorm() == 0.0 && !scanner_position;
  }

  /// The same knowledge in the working frame of a scan read with io::LabelledCloud::coordinate_offset
  /// `offset`: positions move by -offset, the direction and the cell stay.
  ScanKnowledge inWorkingFrame(const Eigen::Vector3d& offset) const {
    ScanKnowledge moved = *this;
    for (Eigen::Vector3d& p : moved.known_extent) p -= offset;
    if (moved.scanner_position) *moved.scanner_position -= offset;
    return moved;
  }
};

/// --known-extent, --seen-from, --seen-from-point and --scanner-cell of the tools that fuse.
struct ScanKnowledgeFlags {
  std::string known_extent, extent_head, seen_from, seen_from_point;
  double scanner_cell = ObservedFusionOptions().scanner_cell;

  void addTo(boost::program_options::options_description& options) {
    namespace po = boost::program_options;
    options.add_options()
        ("known-extent", po::value(&known_extent),
         "X,Y,Z (a point, e.g. one on the ground under an airborne scan's roof), X0,Y0,Z0,X1,Y1,Z1 (a box), or a "
         "cloud file of points (e.g. a footprint's corners at ground and roof height): where the object is known to "
         "reach, in the input's units and frame; the hidden side is closed there instead of at the scan's box (with "
         "fusion)")
        ("extent-head", po::value(&extent_head),
         "a hidden-extent head trained for the model (paco_train --extent-head-for), e.g. models/extent/mfcad_cube.pt for "
         "parts cut from a cube, models/extent/mfcad_stretched.pt for other box-like objects: the hidden side is "
         "closed where it guesses the object ends (with fusion; doc/evaluation.md, models/README.md)")
        ("seen-from", po::value(&seen_from),
         "X,Y,Z: the direction towards a distant scanner (e.g. 0,0,1 for airborne LiDAR with Z up); completed "
         "points it would have seen (off the scan's silhouette, or in front of what it saw) are dropped, and the box "
         "that closes the hidden side has its walls along the lines of sight (with fusion)")
        ("seen-from-point", po::value(&seen_from_point),
         "X,Y,Z: the scanner's position (e.g. 0,0,0 for a depth camera's own frame), for the same test along lines "
         "of sight through it (with fusion)")
        ("scanner-cell", po::value(&scanner_cell)->default_value(scanner_cell, shortNumber(scanner_cell)),
         "width of a line of sight for --seen-from and --seen-from-point, a fraction of the scan's diagonal (at least "
         "twice the scan's point spacing); gaps in the scan up to twice this wide do not count as seen empty");
  }

  /// Throws UsageError on malformed values, and IoError for a --known-extent file that cannot be read.
  ScanKnowledge parse() const {
    ScanKnowledge knowledge;
    knowledge.known_extent = parseKnownExtent(known_extent);
    knowledge.known_extent_is_box = knowledge.known_extent.size() > 1 && !std::filesystem::is_regular_file(known_extent);
    if (!extent_head.empty() && !known_extent.empty())
      throw UsageError("--extent-head guesses the extent that --known-extent gives: choose one");
    knowledge.extent_head = extent_head;
    if (!seen_from.empty() && !seen_from_point.empty())
      throw UsageError("give --seen-from (a direction) or --seen-from-point (a position), not both");
    if (!seen_from.empty()) {
      const std::vector<double> d = parseNumbers("--seen-from", "X,Y,Z (a direction)", seen_from, 3);
      knowledge.scanner_direction = Eigen::Vector3d(d[0], d[1], d[2]);
      if (knowledge.scanner_direction.norm() == 0.0)
        throw UsageError("--seen-from takes a direction towards the scanner; 0,0,0 is none");
    }
    if (!seen_from_point.empty()) {
      const std::vector<double> p = parseNumbers("--seen-from-point", "X,Y,Z (a position)", seen_from_point, 3);
      knowledge.scanner_position = Eigen::Vector3d(p[0], p[1], p[2]);
    }
    if (!(scanner_cell > 0.0 && scanner_cell < 1.0))
      throw UsageError("--scanner-cell must be in (0, 1) (a fraction of the diagonal), got " + shortNumber(scanner_cell));
    knowledge.scanner_cell = scanner_cell;
    return knowledge;
  }
};

/// The completion options of paco_reconstruct and paco_complete: which predictions are kept, and
/// how they meet the scan (fusion, and what is known of the object and the scanner).
struct CompletionFlags {
  double threshold = ParametricCompleter().getConfidenceThreshold();
  int turns = TurnEnsembleOptions().turns;
  bool no_fusion = false;
  ScanKnowledgeFlags knowledge;
  FusionFlags fusion = libraryFusionFlags();

  /// `no_fusion_help` says what the tool does without fusion.
  void addTo(boost::program_options::options_description& options, const std::string& no_fusion_help) {
    namespace po = boost::program_options;
    options.add_options()
        ("threshold", po::value(&threshold)->default_value(threshold, shortNumber(threshold)),
         "keep completed primitives with confidence above this, in [0, 1]")
        ("no-fusion", po::bool_switch(&no_fusion), no_fusion_help.c_str());
    addTurnsOption(options, turns);
    knowledge.addTo(options);
    fusion.addTo(options);
  }

  /// Throws UsageError naming the option that is out of range or malformed, and IoError for a
  /// --known-extent file that cannot be read; returns what is known of the object and scanner.
  ScanKnowledge validate() const {
    if (!(threshold >= 0.0 && threshold <= 1.0))
      throw UsageError("--threshold must be in [0, 1], got " + shortNumber(threshold));
    checkTurns(turns);
    fusion.validate();
    const ScanKnowledge parsed = knowledge.parse();
    if (!parsed.empty() && no_fusion)
      throw UsageError("--known-extent, --extent-head, --seen-from and --seen-from-point work through the fusion "
                       "step: drop --no-fusion");
    return parsed;
  }
};

/// The head of --extent-head, checked against the model before any slow work; null without one.
inline HiddenExtentModel::ConstPtr loadExtentHead(const ScanKnowledge& knowledge, const CompletionModel& model) {
  if (knowledge.extent_head.empty()) return nullptr;
  auto head = HiddenExtentModel::load(knowledge.extent_head);
  head->checkMatches(model);
  return head;
}

/// --extent-head: the head's guess of how far the object reaches beyond the scan, averaged over
/// the same `turns` as the network's planes, becomes the known extent of the box fill. Timed as
/// "extent".
inline void guessHiddenExtent(const CompletionModel::ConstPtr& model, const HiddenExtentModel& head,
                              const pcl::PointCloud<pcl::PointNormal>::ConstPtr& cloud,
                              const PlanarSegmentation& segmentation, int turns, ScanKnowledge& knowledge,
                              StageTimer& timer) {
  timer.start("extent");
  const HiddenExtent extent = estimateHiddenExtent(model, head, cloud, segmentation, turns, knowledge.scanner_direction);
  timer.stop();
  knowledge.known_extent = extent.corners();
  const auto closed = std::count(extent.closed_by_seen_face.begin(), extent.closed_by_seen_face.end(), true);
  std::printf("hidden extent (%s): the object reaches up to %.4g beyond the scan's box (%.1f %% of its diagonal); "
              "%d of its 6 sides end at a seen face\n",
              head.path().c_str(), extent.largestInUserUnits(),
              100.0 * *std::max_element(extent.beyond.begin(), extent.beyond.end()), static_cast<int>(closed));
}

/// Replaces `primitives` (the completion) by their fusion with the seen faces of `cloud`; the box
/// fill reaches the known extent, and the scanner's view bounds the completion, when given.
/// Returns the axes of the box the fill closes (ObservedFusionReport::box_axes).
inline Eigen::Matrix3d fuseWithSeenFaces(std::vector<PlanarPrimitive>& primitives,
                                         const pcl::PointCloud<pcl::PointNormal>& cloud,
                                         const PlanarSegmentation& segmentation, const FusionFlags& flags,
                                         const ScanKnowledge& knowledge, StageTimer& timer) {
  if (!knowledge.known_extent.empty()) {
    // The object reaches the known extent and holds the scan: far apart, the two are most likely
    // in different units or frames (the fill would then close a box around both).
    Eigen::AlignedBox3d scan_box, known_box;
    for (const auto& p : cloud) scan_box.extend(Eigen::Vector3d(p.x, p.y, p.z));
    for (const auto& p : knowledge.known_extent) known_box.extend(p);
    const double gap = (known_box.min() - scan_box.max()).cwiseMax(scan_box.min() - known_box.max()).cwiseMax(0.0).norm();
    const double diagonal = scan_box.diagonal().norm();
    if (gap > diagonal)
      std::fprintf(stderr,
                   "warning: --known-extent lies %.4g away from the scan, more than the scan's diagonal (%.4g): is it "
                   "in the input's units and frame?\n",
                   gap, diagonal);
  }
  timer.start("fuse");
  ObservedFusionReport report;
  ObservedFusionOptions options;
  options.align_unseen_degrees = flags.align_unseen_degrees;
  options.clip_margin = flags.clipMargin();
  options.tilt_margin = flags.tiltMargin();
  options.fill_spacing = flags.fill_box_spacing;
  options.unseen_point_fraction = flags.unseen_point_fraction;
  options.contradiction_radius = flags.contradiction_radius;
  options.join_distance = flags.join_distance;
  options.known_extent_points = knowledge.known_extent;
  options.scanner_direction = knowledge.scanner_direction;
  options.scanner_position = knowledge.scanner_position;
  options.scanner_cell = knowledge.scanner_cell;
  primitives = fuseWithObserved(std::move(primitives), makePrimitives(cloud, segmentation), options, &report);
  timer.stop();
  std::printf("fuse with the seen faces%s: %s\n",
              knowledge.known_extent.empty()   ? ""
              : knowledge.extent_head.empty() ? " (box fill to the known extent)"
                                              : " (box fill to the guessed extent)",
              describe(report).c_str());
  if ((report.box_on_one_plane || report.box_on_mirror_pair) && report.filled_points > 0 && !knowledge.scanner_position)
    // Without a known extent the level box of a roof's slopes ends at the lowest seen point: the
    // roof closes at its eaves.
    std::printf("  note: no two seen planes are perpendicular, so the box that closes the hidden side %s; if the "
                "scanner looked from one direction (airborne LiDAR with Z up: --seen-from 0,0,1), say so, and the "
                "box's walls follow its lines of sight%s\n",
                report.box_on_one_plane ? "is turned onto the largest seen plane"
                                        : "lies on the bisectors of mirror-image seen planes (a roof's slopes)",
                report.box_on_mirror_pair && knowledge.known_extent.empty()
                    ? "; the box ends at the lowest seen point: a point on the ground (--known-extent X,Y,Z) "
                      "takes the walls down to it"
                    : "");
  if (report.no_seen_plane_along_sight && report.filled_points > 0 && knowledge.known_extent.empty())
    // The scanner's direction levels the box, but with no wall seen nothing says how far down the
    // object goes: AHN3_02373 closes at its eaves, 2.6 m thick, and the cell complex drops a low
    // wing whose solid is then a sliver.
    std::printf("  note: no seen plane runs along the scanner's lines of sight (no wall seen), so the box that closes "
                "the hidden side ends at the seen point farthest from the scanner; a point on the ground "
                "(--known-extent X,Y,Z) takes the walls down to it\n");
  if (knowledge.known_extent_is_box) {
    // The fill's box lies on the seen axes: turned from the input's, it encloses the corners of the
    // given box with a larger one (AHN3_02373 seen from above: 48.9 x 41.5 m for a 37.7 x 23.1 m
    // footprint), and the hidden side is closed beyond what the user said.
    const double degrees =
        radiansToDegrees(Eigen::AngleAxisd(rotationOntoAxesClosestToIdentity(report.box_axes)).angle());
    if (degrees > 1.0)
      std::printf("  note: the box that closes the hidden side lies on the seen faces' axes, %.1f deg from the "
                  "input's, so it encloses the --known-extent box's corners with a larger box; give the extent "
                  "as points in a cloud file instead (e.g. a footprint's corners, or one point on the ground)\n",
                  degrees);
  }
  return report.box_axes;
}

}  // namespace paco::app
