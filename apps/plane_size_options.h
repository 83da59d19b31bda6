#pragma once
// The segmenter's smallest-plane options, shared by the tools that segment a scan
// (paco_reconstruct, paco_complete, paco_eval), so that they read and are checked alike.
#include "app_support.h"

#include <paco/common/scan_shares.h>

#include <boost/program_options.hpp>

#include <string>

namespace paco::app {

inline void addMinPointsOption(boost::program_options::options_description& options, int& min_points) {
  options.add_options()("min-points", boost::program_options::value(&min_points)->default_value(min_points),
                        ("segmenter: fewest points of a plane, >= 3 (0: " + percentText(kScanMinPlaneFraction) +
                         " of the points segmented, after thinning, " + percentText(kExactScanMinPlaneFraction) +
                         " on an exact scan without noise; at least 3)")
                            .c_str());
}

inline void validateMinPoints(int min_points) {
  if (min_points != 0 && min_points < 3)
    throw UsageError("--min-points must be 0 (" + percentText(kScanMinPlaneFraction) + " of the points) or at least 3, got " +
                     std::to_string(min_points));
}

inline void addMinParallelPointsOption(boost::program_options::options_description& options, int& min_points) {
  options.add_options()(
      "min-parallel-points", boost::program_options::value(&min_points)->default_value(min_points),
      ("segmenter: fewest points of a plane parallel to a larger one, >= 3 (0: " +
       percentText(kScanMinParallelPlaneFraction) + " of the points segmented, after thinning, " +
       percentText(kNoisyScanMinParallelPlaneFraction) + " on a noisy scan; -1: none)")
          .c_str());
}

inline void validateMinParallelPoints(int min_points) {
  if (min_points != -1 && min_points != 0 && min_points < 3)
    throw UsageError("--min-parallel-points must be -1 (none), 0 (" + percentText(kScanMinParallelPlaneFraction) +
                     " of the points) or at least 3, got " +
                     std::to_string(min_points));
}

}  // namespace paco::app
