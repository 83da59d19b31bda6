#include <paco/common/error.h>
#include <paco/segmentation/thinning.h>

#include <pcl/common/common.h>
#include <pcl/common/point_tests.h>
#include <pcl/filters/uniform_sampling.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>
#include <pcl/segmentation/extract_clusters.h>

#include <Eigen/Geometry>

#include <omp.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <memory>
#include <numeric>
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

namespace {

/// The most points that may be stray among `points`: 0.5 % of them, at least 1.
std::size_t strayLimit(std::size_t points) { return std::max<std::size_t>(1, points / 200); }

/// One round of findStrayPoints over the points `source` of `cloud` (finite ones).
template <typename PointT>
std::vector<int> strayPointsAmong(const pcl::PointCloud<PointT>& cloud, const std::vector<int>& source) {
  auto finite = std::make_shared<pcl::PointCloud<PointT>>();
  Eigen::AlignedBox3f box;
  for (int i : source) {
    finite->push_back(cloud[static_cast<std::size_t>(i)]);
    box.extend(finite->back().getVector3fMap());
  }
  if (finite->size() < 2 || !(box.diagonal().norm() > 0.0f)) return {};
  const double link = 0.05 * box.diagonal().norm();

  // Clustering every point costs a radius search per point, and with a far stray point the whole
  // part lies within one link (0.9 s for 4,000 points). Clustering one representative per
  // half-link voxel bounds each search to a few dozen voxels; a point joins the group of its
  // nearest representative. That one lies within a voxel diagonal (0.87 link) of the point, so
  // representatives linked within (1 + sqrt 3) links join every pair of points within one link:
  // groups may only be merged, never split, by the shortcut.
  const double leaf = 0.5 * link;
  auto representatives = std::make_shared<pcl::PointCloud<PointT>>();
  pcl::VoxelGrid<PointT> voxels;
  voxels.setInputCloud(finite);
  voxels.setLeafSize(static_cast<float>(leaf), static_cast<float>(leaf), static_cast<float>(leaf));
  voxels.filter(*representatives);
  auto tree = std::make_shared<pcl::search::KdTree<PointT>>();
  tree->setInputCloud(representatives);
  pcl::EuclideanClusterExtraction<PointT> clustering;
  clustering.setInputCloud(representatives);
  clustering.setSearchMethod(tree);
  clustering.setClusterTolerance((1.0 + std::sqrt(3.0)) * link);
  clustering.setMinClusterSize(1);
  clustering.setMaxClusterSize(static_cast<pcl::uindex_t>(representatives->size()));
  std::vector<pcl::PointIndices> clusters;
  clustering.extract(clusters);
  if (clusters.size() < 2) return {};

  std::vector<int> cluster_of(representatives->size(), -1);
  for (std::size_t c = 0; c < clusters.size(); ++c)
    for (int r : clusters[c].indices) cluster_of[static_cast<std::size_t>(r)] = static_cast<int>(c);
  std::vector<int> group_of(finite->size(), -1);
  std::vector<std::vector<int>> members(clusters.size());  // indices into `finite`
  pcl::Indices nearest(1);
  std::vector<float> squared(1);
  for (std::size_t i = 0; i < finite->size(); ++i)
    if (tree->nearestKSearch((*finite)[i], 1, nearest, squared) == 1) {
      group_of[i] = cluster_of[static_cast<std::size_t>(nearest[0])];
      members[static_cast<std::size_t>(group_of[i])].push_back(static_cast<int>(i));
    }

  // A small group is stray when every other point is farther from it than the largest group is
  // wide. (A quarter of that width also caught real returns: three ground points 7 m below the
  // roof edge of a 17 m airborne-scanned building.) The largest group, not all other points: a
  // second stray would stretch those.
  const auto main = static_cast<std::size_t>(
      std::max_element(members.begin(), members.end(),
                       [](const std::vector<int>& a, const std::vector<int>& b) { return a.size() < b.size(); }) -
      members.begin());
  // Without a group that holds most of the points the cloud is sparse (points farther apart than
  // a link), not a scan with a few strays: ten points in a box would otherwise all be stray but one.
  if (2 * members[main].size() <= finite->size()) return {};
  Eigen::AlignedBox3f main_box;
  for (int i : members[main]) main_box.extend((*finite)[static_cast<std::size_t>(i)].getVector3fMap());
  const double reach = main_box.diagonal().norm();
  const std::size_t largest_stray = strayLimit(finite->size());
  pcl::KdTreeFLANN<PointT> all;
  all.setInputCloud(finite);
  std::vector<int> strays;
  for (std::size_t g = 0; g < members.size(); ++g) {
    if (g == main || members[g].empty() || members[g].size() > largest_stray) continue;
    double gap = std::numeric_limits<double>::infinity();
    const int k = static_cast<int>(members[g].size()) + 1;  // enough to reach a point outside the group
    for (int i : members[g]) {
      if (all.nearestKSearch((*finite)[static_cast<std::size_t>(i)], k, nearest, squared) <= 0) continue;
      for (std::size_t n = 0; n < nearest.size(); ++n)
        if (group_of[static_cast<std::size_t>(nearest[n])] != static_cast<int>(g)) {
          gap = std::min(gap, std::sqrt(static_cast<double>(squared[n])));
          break;
        }
    }
    if (gap > reach)
      for (int i : members[g]) strays.push_back(source[static_cast<std::size_t>(i)]);
  }
  return strays;
}

}  // namespace

template <typename PointT>
std::vector<int> findStrayPoints(const pcl::PointCloud<PointT>& cloud) {
  std::vector<int> kept;
  for (std::size_t i = 0; i < cloud.size(); ++i)
    if (pcl::isFinite(cloud[i])) kept.push_back(static_cast<int>(i));
  // A far stray stretches the box, and with it the link, so that a nearer stray group joins the
  // part; without the far one, the next round separates it. Rarely more than two rounds.
  // In all no more than one group may hold.
  const std::size_t budget = strayLimit(kept.size());
  std::vector<int> strays;
  for (int round = 0; round < 4; ++round) {
    std::vector<int> found = strayPointsAmong(cloud, kept);
    if (found.empty() || strays.size() + found.size() > budget) break;
    std::sort(found.begin(), found.end());
    std::vector<int> rest;
    std::set_difference(kept.begin(), kept.end(), found.begin(), found.end(), std::back_inserter(rest));
    kept = std::move(rest);
    strays.insert(strays.end(), found.begin(), found.end());
  }
  std::sort(strays.begin(), strays.end());
  return strays;
}

template <typename PointT>
ScanPreparationReport prepareScanPoints(const pcl::PointCloud<PointT>& input, std::size_t max_points,
                                        pcl::PointCloud<PointT>& output, bool remove_strays) {
  ScanPreparationReport report;
  report.repeats_removed = removeRepeatedPoints(input, output);
  if (remove_strays) {
    const std::vector<int> strays = findStrayPoints(output);
    if (!strays.empty()) {
      pcl::PointCloud<PointT> kept;
      std::size_t next = 0;
      for (std::size_t i = 0; i < output.size(); ++i) {
        if (next < strays.size() && strays[next] == static_cast<int>(i)) {
          ++next;
          continue;
        }
        kept.push_back(output[i]);
      }
      output = std::move(kept);
      report.strays_removed = strays.size();
    }
  }
  report.thinning.input_points = report.thinning.output_points = output.size();
  if (max_points > 0 && output.size() > max_points) {
    const pcl::PointCloud<PointT> distinct = std::move(output);
    report.thinning = thinToPointBudget(distinct, max_points, output);
  }
  return report;
}

std::vector<int> labelsFromThinned(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                   const pcl::PointCloud<pcl::PointNormal>& thinned,
                                   const PlanarSegmentation& segmentation, double max_distance,
                                   std::vector<int>* nearest, const std::function<void(std::size_t)>& on_progress,
                                   unsigned int threads) {
  if (segmentation.labels.size() != thinned.size())
    throw InvalidInputError("labelsFromThinned: " + std::to_string(segmentation.labels.size()) + " labels for " +
                            std::to_string(thinned.size()) + " thinned points");
  for (const int label : segmentation.labels)
    if (label >= static_cast<int>(segmentation.planes.size()))
      throw InvalidInputError("labelsFromThinned: label " + std::to_string(label) + " names no plane (" +
                              std::to_string(segmentation.planes.size()) + " planes)");
  // The search runs on the finite thinned points only, mapped back to their indices.
  auto finite = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>();
  std::vector<int> finite_index;
  for (std::size_t i = 0; i < thinned.size(); ++i)
    if (pcl::isFinite(thinned[i])) {
      finite->push_back(pcl::PointXYZ(thinned[i].x, thinned[i].y, thinned[i].z));
      finite_index.push_back(static_cast<int>(i));
    }
  std::vector<int> labels(cloud.size(), -1);
  if (nearest) nearest->assign(cloud.size(), -1);
  if (finite->empty()) {
    for (const auto& p : cloud)
      if (pcl::isFinite(p))
        throw InvalidInputError("labelsFromThinned: the thinned cloud has no finite point to label from");
    if (on_progress) on_progress(cloud.size());
    return labels;
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(finite);
  // A point near an edge or at a plane's rim can have an unlabelled kept point, or one of the
  // other plane, nearest: the nearest of a few that puts it on its plane labels it.
  constexpr int kCandidates = 8;
  const auto labelPoint = [&](std::size_t i, pcl::Indices& found, std::vector<float>& squared) {
    const auto& p = cloud[i];
    if (!pcl::isFinite(p)) return;
    const int count = tree.nearestKSearch(pcl::PointXYZ(p.x, p.y, p.z), kCandidates, found, squared);
    if (count < 1) return;
    if (nearest) (*nearest)[i] = finite_index[static_cast<std::size_t>(found[0])];
    const Eigen::Vector3d position = p.getVector3fMap().cast<double>();
    for (int k = 0; k < count; ++k) {  // nearest first
      const int label = segmentation.labels[static_cast<std::size_t>(finite_index[static_cast<std::size_t>(found[k])])];
      if (label < 0) continue;
      if (std::abs(segmentation.planes[static_cast<std::size_t>(label)].signedDistance(position)) <= max_distance) {
        labels[i] = label;
        return;
      }
    }
  };
  // Chunks searched in parallel (the tree is only read), with the progress callback between them:
  // it may throw (an interrupt), which must not happen inside a parallel region.
  constexpr std::size_t kChunk = 1 << 16;
  const int team = threads > 0 ? static_cast<int>(threads) : omp_get_max_threads();
  for (std::size_t begin = 0; begin < cloud.size(); begin += kChunk) {
    const auto end = static_cast<std::ptrdiff_t>(std::min(cloud.size(), begin + kChunk));
#pragma omp parallel num_threads(team)
    {
      pcl::Indices found(kCandidates);
      std::vector<float> squared(kCandidates);
#pragma omp for schedule(static)
      for (std::ptrdiff_t i = static_cast<std::ptrdiff_t>(begin); i < end; ++i)
        labelPoint(static_cast<std::size_t>(i), found, squared);
    }
    if (on_progress) on_progress(static_cast<std::size_t>(end));
  }
  if (on_progress && cloud.empty()) on_progress(0);
  return labels;
}

template ScanPreparationReport prepareScanPoints<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&, std::size_t,
                                                                 pcl::PointCloud<pcl::PointXYZ>&, bool);
template ScanPreparationReport prepareScanPoints<pcl::PointNormal>(const pcl::PointCloud<pcl::PointNormal>&,
                                                                    std::size_t, pcl::PointCloud<pcl::PointNormal>&, bool);
template std::vector<int> findStrayPoints<pcl::PointXYZ>(const pcl::PointCloud<pcl::PointXYZ>&);
template std::vector<int> findStrayPoints<pcl::PointNormal>(const pcl::PointCloud<pcl::PointNormal>&);
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
