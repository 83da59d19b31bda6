#pragma once
// Exact nearest-neighbour kernels behind the matching cost and the chamfer and repulsion losses.
// They run without autograd on raw float xyz rows (3 floats per point); the losses then gather
// the found neighbours with autograd. Plain loops over small sets (a plane's points against
// another plane's) beat LibTorch's distance-matrix ops, which pay for allocation and an extra
// pass per op; large sets use exact FLANN kd-trees. Internal to paco_completion.
#include <cstdint>
#include <vector>

namespace paco::completion::detail {

/// For each point of `a` (na points) the index of its nearest point in `b` (nb points), and for
/// each point of `b` its nearest in `a` (squared L2, exact; ties take the lower index).
/// Brute force below `kBruteForcePairs` pairs, FLANN kd-trees above. Needs na, nb > 0.
void mutualNearest(const float* a, std::int64_t na, const float* b, std::int64_t nb, std::int64_t* nearest_in_b,
                   std::int64_t* nearest_in_a);

/// For each of the `n_queries` query points the index of its nearest point of `data` (`n_data`
/// > 0 points; exact, one FLANN kd-tree over `data`).
void nearestIn(const float* data, std::int64_t n_data, const float* queries, std::int64_t n_queries,
               std::int64_t* nearest);

/// Above this many pairs mutualNearest() uses kd-trees.
constexpr std::int64_t kBruteForcePairs = std::int64_t{1} << 21;

/// The index of the nearest other point of each of the `count` points (count >= 2); brute force
/// below `kBruteForcePairs` pairs, a FLANN kd-tree above.
void nearestOtherPoint(const float* points, std::int64_t count, std::int64_t* nearest);

/// Indices (p·k + i) of the k nearest other points of each of the `count` points (count > k > 0;
/// brute force, for small sets).
void kNearestWithinSet(const float* points, std::int64_t count, int k, std::int64_t* neighbours);

/// Chamfer part of the matching cost. For every predicted plane j (its `per_plane` points start at
/// predicted + j·per_plane·3, `planes_predicted` planes) and every GT plane g (its points are the
/// rows of `gt` labelled g, labels in [0, gt_planes)), writes
///   chamfer(j, g) = mean over j's points of the squared distance to the nearest point of g
///                 + mean over g's points of the squared distance to the nearest point of j
/// to chamfer[g · planes_predicted + j]. GT planes without points get 0.
void planeChamferTable(const float* predicted, std::int64_t planes_predicted, std::int64_t per_plane,
                       const float* gt, const std::int64_t* labels, std::int64_t gt_count, int gt_planes,
                       double* chamfer);

}  // namespace paco::completion::detail
