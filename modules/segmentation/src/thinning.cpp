#include <paco/common/error.h>
#include <paco/segmentation/thinning.h>

#include <pcl/common/common.h>
#include <pcl/filters/uniform_sampling.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <string>
#include <tuple>

namespace paco {

template <typename PointT>
ThinningReport thinToPointBudget(const pcl::PointCloud<PointT>& input, std::size_t max_points,
                                 pcl::PointCloud<PointT>& output) {
  if (max_points < kMinPointBudget)
    throw InvalidInputError("thinToPointBudget: a budget of " + std::to_string(max_points) +
                            " points is too small; use at least " + std::to_string(kMinPointBudget));
  if (&input == &output) throw InvalidInputError("thinToPointBudget: input and output must be different clouds");
  ThinningReport report;
  report.input_points = input.size();
  if (input.size() <= max_points) {
    output = input;
    report.output_points = output.size();
    return report;
  }

  auto finite = std::make_shared<pcl::PointCloud<PointT>>();
  finite->reserve(input.size());
  for (const auto& p : input.points)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) finite->push_back(p);
  if (finite->empty()) throw InvalidInputError("thinToPointBudget: the cloud has no finite point");
  finite->is_dense = true;

  PointT lo, hi;
  pcl::getMinMax3D(*finite, lo, hi);
  const Eigen::Vector3d extent(double(hi.x) - lo.x, double(hi.y) - lo.y, double(hi.z) - lo.z);
  const double diagonal = extent.norm();
  if (!(diagonal > 0.0)) {  // every point coincides: one represents them all
    output.clear();
    output.push_back(finite->front());
    report.output_points = 1;
    return report;
  }
  // PCL indexes voxels with 32-bit integers: keep their count below 2^30.
  const Eigen::Vector3d padded = extent.cwiseMax(1e-9 * diagonal);
  const double smallest_voxel = std::cbrt(padded.prod() / double(1 << 30)) * 1.01;

  pcl::UniformSampling<PointT> sampler;
  sampler.setInputCloud(finite);
  const auto countAt = [&](double voxel) {
    sampler.setRadiusSearch(voxel);
    sampler.filter(output);
    return output.size();
  };
  // A scanned surface of this diagonal fills about (diagonal / voxel)^2 voxels. Start there,
  // then bisect (geometrically) between a voxel that keeps too many points and one that fits.
  double voxel = std::max(smallest_voxel, diagonal / std::sqrt(double(max_points)));
  double too_small = 0.0, fits = 0.0;
  std::size_t kept = countAt(voxel);
  for (int pass = 0; pass < 12; ++pass) {
    if (kept <= max_points) {
      fits = voxel;
      if (kept >= max_points * 85 / 100 || voxel <= smallest_voxel) break;
    } else {
      too_small = voxel;
    }
    if (fits > 0.0 && too_small > 0.0)
      voxel = std::sqrt(fits * too_small);
    else  // no bracket yet: step by the square root of the overshoot (area scales as voxel^-2)
      voxel = std::max(smallest_voxel,
                       voxel * std::sqrt(double(kept) / double(max_points)) * (kept > max_points ? 1.02 : 0.98));
    kept = countAt(voxel);
  }
  if (fits == 0.0) {  // the passes ran out before any voxel fitted: grow it until one does
    while (kept > max_points) kept = countAt(voxel *= 1.25);
    fits = voxel;
  } else if (voxel != fits) {
    kept = countAt(fits);  // the last pass kept too many: go back to the best voxel that fitted
  }
  report.output_points = kept;
  report.voxel_size = fits;
  return report;
}

template <typename PointT>
std::vector<int> findRepeatedPoints(const pcl::PointCloud<PointT>& cloud) {
  std::vector<int> first_of(cloud.size(), -1);
  std::vector<std::size_t> order;
  order.reserve(cloud.size());
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (std::isfinite(cloud[i].x) && std::isfinite(cloud[i].y) && std::isfinite(cloud[i].z)) order.push_back(i);
  const auto position = [&](std::size_t i) { return std::make_tuple(cloud[i].x, cloud[i].y, cloud[i].z); };
  // Stable: within a run of equal positions the first input point comes first.
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return position(a) < position(b); });
  for (std::size_t k = 1; k < order.size(); ++k)
    if (position(order[k]) == position(order[k - 1]))
      first_of[order[k]] = first_of[order[k - 1]] >= 0 ? first_of[order[k - 1]] : static_cast<int>(order[k - 1]);
  return first_of;
}

template <typename PointT>
std::size_t removeRepeatedPoints(const pcl::PointCloud<PointT>& input, pcl::PointCloud<PointT>& output) {
  if (&input == &output) throw InvalidInputError("removeRepeatedPoints: input and output must be different clouds");
  const std::vector<int> first_of = findRepeatedPoints(input);
  output.clear();
  output.reserve(input.size());
  for (std::size_t i = 0; i < input.size(); ++i)
    if (first_of[i] < 0) output.push_back(input[i]);
  return input.size() - output.size();
}

template <typename PointT>
ScanPreparationReport prepareScanPoints(const pcl::PointCloud<PointT>& input, std::size_t max_points,
                                        pcl::PointCloud<PointT>& output) {
  ScanPreparationReport report;
  report.repeats_removed = removeRepeatedPoints(input, output);
  report.thinning.input_points = report.thinning.output_points = output.size();
  if (max_points > 0 && output.size() > max_points) {
    const pcl::PointCloud<PointT> distinct = std::move(output);
    report.thinning = thinToPointBudget(distinct, max_points, output);
  }
  return report;
}

template ScanPreparationReport prepareScanPoints<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&, std::size_t,
                                                                 pcl::PointCloud<pcl::PointXYZ>&);
template ScanPreparationReport prepareScanPoints<pcl::PointNormal>(const pcl::PointCloud<pcl::PointNormal>&,
                                                                    std::size_t, pcl::PointCloud<pcl::PointNormal>&);
template std::vector<int> findRepeatedPoints<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&);
template std::vector<int> findRepeatedPoints<pcl::PointNormal>(const pcl::PointCloud<pcl::PointNormal>&);
template std::size_t removeRepeatedPoints<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&,
                                                         pcl::PointCloud<pcl::PointXYZ>&);
template std::size_t removeRepeatedPoints<pcl::PointNormal>(const pcl::PointCloud<pcl::PointNormal>&,
                                                            pcl::PointCloud<pcl::PointNormal>&);
template ThinningReport thinToPointBudget<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&, std::size_t,
                                                          pcl::PointCloud<pcl::PointXYZ>&);
template ThinningReport thinToPointBudget<pcl::PointNormal>(const pcl::PointCloud<pcl::PointNormal>&, std::size_t,
                                                             pcl::PointCloud<pcl::PointNormal>&);

}  // namespace paco
