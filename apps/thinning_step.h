#pragma once
// The working cloud of paco_reconstruct and paco_complete (repeated and stray points left out,
// dense scans thinned, normals facing inwards turned), and the options of that step and of the
// segmenter, which both tools share; paco_segment turns inward normals the same way.
#include "app_support.h"
#include "plane_size_options.h"

#include <paco/common/normal_sides.h>
#include <paco/segmentation/planar_segmenter.h>
#include <paco/segmentation/thinning.h>

#include <boost/program_options.hpp>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

#include <cstdio>
#include <memory>
#include <string>

namespace paco::app {

inline void addMaxPointsOption(boost::program_options::options_description& options, std::size_t& max_points) {
  options.add_options()("max-points", boost::program_options::value(&max_points)->default_value(max_points),
                        "thin denser inputs to about this many evenly spread points before segmenting (0: keep all)");
}

inline void validateMaxPoints(std::size_t max_points) {
  if (max_points != 0 && max_points < kMinPointBudget)
    throw UsageError("--max-points must be 0 (keep all) or at least " + std::to_string(kMinPointBudget));
}

/// --keep-stray-points of the tools that prepare a scan (paco::findStrayPoints).
inline void addKeepStrayPointsOption(boost::program_options::options_description& options, bool& keep) {
  options.add_options()("keep-stray-points", boost::program_options::bool_switch(&keep),
                        "keep small groups of points far from the rest of the scan (at most 0.5 % of the points, "
                        "farther from the rest than the object is wide), which are left out by default");
}

/// --keep-inward-normals of the tools that prepare a scan (paco::turnInwardNormalsOutward).
inline void addKeepInwardNormalsOption(boost::program_options::options_description& options, bool& keep) {
  options.add_options()("keep-inward-normals", boost::program_options::bool_switch(&keep),
                        "keep given normals that face the middle of the scan as a whole (a room scanned from inside, "
                        "or normals turned towards a viewpoint inside the object); by default they are turned "
                        "outwards, so that the object is the solid they enclose (a room's volume)");
}

/// Unless `keep_inward_normals`, turns the given normals of `cloud` outwards when they face its
/// middle as a whole (paco::turnInwardNormalsOutward); returns how they faced.
inline NormalSides turnInwardNormals(pcl::PointCloud<pcl::PointNormal>& cloud, bool keep_inward_normals) {
  return keep_inward_normals ? normalSides(cloud) : turnInwardNormalsOutward(cloud);
}

/// A line when the normals faced inwards as a whole: turned, or kept so.
inline void reportNormalSides(const NormalSides& sides) {
  if (sides.turned)
    std::printf("normals: %.0f %% face the middle of the scan, as in a room scanned from inside or when turned "
                "towards a point inside the object; turned outwards, so that the faces built on them face out of "
                "the solid they enclose (--keep-inward-normals keeps them)\n",
                100.0 * sides.inwardShare());
  else if (sides.faceInwards())
    std::printf("normals: %.0f %% face the middle of the scan, kept so (--keep-inward-normals): the assemblers take "
                "the space they face as outside\n",
                100.0 * sides.inwardShare());
}

/// Fewest points of a scan the tools work on (after repeated and stray points are left out).
constexpr std::size_t kMinScanPoints = 10;

/// The cloud the pipeline works on (paco::prepareScanPoints: repeated points and, unless
/// `keep_strays`, stray points left out, then thinned to `max_points`; then, unless
/// `keep_inward_normals`, paco::turnInwardNormalsOutward), with a line for each step that changed
/// anything. Throws InvalidInputError when fewer than kMinScanPoints remain.
inline std::shared_ptr<pcl::PointCloud<pcl::PointNormal>> workingCloud(const pcl::PointCloud<pcl::PointNormal>& scan,
                                                                        std::size_t max_points, bool keep_strays,
                                                                        bool keep_inward_normals, StageTimer& timer) {
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  timer.start("prepare");
  const ScanPreparationReport report = prepareScanPoints(scan, max_points, *cloud, !keep_strays);
  const NormalSides sides = turnInwardNormals(*cloud, keep_inward_normals);
  timer.stop();
  if (report.repeats_removed > 0)
    std::printf("left out %zu of %zu points that repeat another point's coordinates\n", report.repeats_removed,
                scan.size());
  if (report.strays_removed > 0)
    std::printf("left out %zu stray %s far from the rest of the scan (--keep-stray-points keeps them)\n",
                report.strays_removed, report.strays_removed == 1 ? "point" : "points");
  if (report.thinning.thinned())
    std::printf("thin: %zu of %zu points kept, one per %.3g-unit voxel (--max-points %zu)\n",
                report.thinning.output_points, report.thinning.input_points, report.thinning.voxel_size, max_points);
  reportNormalSides(sides);
  // Any three points lie on a plane: a handful of points shows no plane, and the completion
  // would make up a whole solid around them (three points came back as a closed box).
  if (cloud->size() < kMinScanPoints)
    throw InvalidInputError("the scan has " + std::to_string(cloud->size()) + " distinct point" +
                            (cloud->size() == 1 ? "" : "s") + (cloud->size() < scan.size() ? " left" : "") +
                            "; it takes at least " + std::to_string(kMinScanPoints) +
                            " to show a plane: give a denser scan");
  return cloud;
}

/// The working cloud's and the segmenter's options of paco_reconstruct and paco_complete, added
/// and checked alike.
struct ScanSegmentationFlags {
  std::size_t max_points = kDefaultScanPointBudget;
  bool keep_stray_points = false;
  bool keep_inward_normals = false;
  int min_points = 0;           // 0: scanMinPointsPerPlane's share of the points
  int min_parallel_points = 0;  // 0: scanMinPointsPerParallelPlane's share; -1: none
  double noise_adaptation = kScanNoiseMultiple;

  void addTo(boost::program_options::options_description& options) {
    addMaxPointsOption(options, max_points);
    addKeepStrayPointsOption(options, keep_stray_points);
    addKeepInwardNormalsOption(options, keep_inward_normals);
    addMinPointsOption(options, min_points);
    addMinParallelPointsOption(options, min_parallel_points);
    addNoiseAdaptationOption(options, noise_adaptation);
  }

  /// Throws UsageError naming the option that is out of range.
  void validate() const {
    validateMaxPoints(max_points);
    validateMinPoints(min_points);
    validateMinParallelPoints(min_parallel_points);
    validateNoiseAdaptation(noise_adaptation);
  }

  /// The working cloud of `scan` (workingCloud) with these options.
  std::shared_ptr<pcl::PointCloud<pcl::PointNormal>> workingCloudOf(const pcl::PointCloud<pcl::PointNormal>& scan,
                                                                    StageTimer& timer) const {
    return workingCloud(scan, max_points, keep_stray_points, keep_inward_normals, timer);
  }

  /// Sets the tools' scan defaults on `segmenter` for a working cloud of `points` points.
  void configure(PlanarSegmenter<pcl::PointNormal>& segmenter, std::size_t points) const {
    setScanDefaults(segmenter, points, min_points, min_parallel_points, noise_adaptation);
  }
};

}  // namespace paco::app
