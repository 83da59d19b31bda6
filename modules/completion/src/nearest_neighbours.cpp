#include "nearest_neighbours.h"

#include <flann/flann.hpp>

#include <algorithm>
#include <limits>
#include <optional>

namespace paco::completion::detail {
namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// Coordinates as three separate arrays, so the distance loops below vectorise.
struct Columns {
  std::vector<float> x, y, z;
  Columns(const float* rows, std::int64_t count) : x(count), y(count), z(count) {
    for (std::int64_t i = 0; i < count; ++i) {
      x[i] = rows[3 * i];
      y[i] = rows[3 * i + 1];
      z[i] = rows[3 * i + 2];
    }
  }
};

// distances[j] = squared distance from (px, py, pz) to point j of `c`, for j in [0, count).
inline void distancesTo(const Columns& c, std::int64_t count, float px, float py, float pz, float* distances) {
  const float* x = c.x.data();
  const float* y = c.y.data();
  const float* z = c.z.data();
  for (std::int64_t j = 0; j < count; ++j) {
    const float dx = x[j] - px, dy = y[j] - py, dz = z[j] - pz;
    distances[j] = dx * dx + dy * dy + dz * dz;
  }
}

inline std::int64_t argmin(const float* values, std::int64_t count) {
  std::int64_t best = 0;
  for (std::int64_t j = 1; j < count; ++j)
    if (values[j] < values[best]) best = j;
  return best;
}

void kdTreeNearest(const float* data, std::int64_t n_data, const float* queries, std::int64_t n_queries,
                   std::int64_t* nearest) {
  // FLANN takes non-const pointers but only reads the data and the queries.
  flann::Matrix<float> data_matrix(const_cast<float*>(data), static_cast<std::size_t>(n_data), 3);
  flann::Matrix<float> query_matrix(const_cast<float*>(queries), static_cast<std::size_t>(n_queries), 3);
  flann::Index<flann::L2_Simple<float>> index(data_matrix, flann::KDTreeSingleIndexParams(15));
  index.buildIndex();
  std::vector<int> found(static_cast<std::size_t>(n_queries));
  std::vector<float> distances(found.size());
  flann::Matrix<int> found_matrix(found.data(), found.size(), 1);
  flann::Matrix<float> distance_matrix(distances.data(), distances.size(), 1);
  index.knnSearch(query_matrix, found_matrix, distance_matrix, 1, flann::SearchParams(-1));
  std::copy(found.begin(), found.end(), nearest);
  // FLANN finds nothing when every squared distance overflows a float (coordinates near 1e20), and
  // then returns an arbitrary index: the brute force below still returns a valid one.
  std::optional<Columns> columns;  // copied only when a query needs the fallback
  std::vector<float> all;
  for (std::int64_t i = 0; i < n_queries; ++i) {
    if (nearest[i] >= 0 && nearest[i] < n_data && distances[static_cast<std::size_t>(i)] < kInfinity) continue;
    if (!columns) columns.emplace(data, n_data);
    all.resize(static_cast<std::size_t>(n_data));
    distancesTo(*columns, n_data, queries[3 * i], queries[3 * i + 1], queries[3 * i + 2], all.data());
    nearest[i] = argmin(all.data(), n_data);
  }
}

void kdTreeNearestOther(const float* points, std::int64_t count, std::int64_t* nearest) {
  flann::Matrix<float> matrix(const_cast<float*>(points), static_cast<std::size_t>(count), 3);
  flann::Index<flann::L2_Simple<float>> index(matrix, flann::KDTreeSingleIndexParams(15));
  index.buildIndex();
  std::vector<int> found(2 * static_cast<std::size_t>(count), -1);
  std::vector<float> distances(found.size());
  flann::Matrix<int> found_matrix(found.data(), static_cast<std::size_t>(count), 2);
  flann::Matrix<float> distance_matrix(distances.data(), static_cast<std::size_t>(count), 2);
  index.knnSearch(matrix, found_matrix, distance_matrix, 2, flann::SearchParams(-1));
  for (std::int64_t i = 0; i < count; ++i) {
    // The point itself is one of the two (first, unless a duplicate ties with it).
    const int first = found[2 * static_cast<std::size_t>(i)], second = found[2 * static_cast<std::size_t>(i) + 1];
    const int other = first == i ? second : first;
    const float distance = distances[2 * static_cast<std::size_t>(i) + (first == i ? 1 : 0)];
    nearest[i] = other >= 0 && other < count && other != i && distance < kInfinity ? other : (i == 0 ? 1 : 0);
  }
}

}  // namespace

void nearestIn(const float* data, std::int64_t n_data, const float* queries, std::int64_t n_queries,
               std::int64_t* nearest) {
  if (n_queries > 0) kdTreeNearest(data, n_data, queries, n_queries, nearest);
}

void mutualNearest(const float* a, std::int64_t na, const float* b, std::int64_t nb, std::int64_t* nearest_in_b,
                   std::int64_t* nearest_in_a) {
  if (na * nb > kBruteForcePairs) {
    kdTreeNearest(b, nb, a, na, nearest_in_b);
    kdTreeNearest(a, na, b, nb, nearest_in_a);
    return;
  }
  const Columns cb(b, nb);
  std::vector<float> distances(static_cast<std::size_t>(nb));
  std::vector<float> best_for_b(static_cast<std::size_t>(nb), kInfinity);
  std::fill(nearest_in_a, nearest_in_a + nb, std::int64_t{0});
  for (std::int64_t i = 0; i < na; ++i) {
    distancesTo(cb, nb, a[3 * i], a[3 * i + 1], a[3 * i + 2], distances.data());
    nearest_in_b[i] = argmin(distances.data(), nb);
    for (std::int64_t j = 0; j < nb; ++j)
      if (distances[j] < best_for_b[j]) {
        best_for_b[j] = distances[j];
        nearest_in_a[j] = i;
      }
  }
}

void nearestOtherPoint(const float* points, std::int64_t count, std::int64_t* nearest) {
  if (count * count > kBruteForcePairs) {
    kdTreeNearestOther(points, count, nearest);
    return;
  }
  kNearestWithinSet(points, count, 1, nearest);
}

void kNearestWithinSet(const float* points, std::int64_t count, int k, std::int64_t* neighbours) {
  const Columns c(points, count);
  std::vector<float> distances(static_cast<std::size_t>(count));
  std::vector<float> best(static_cast<std::size_t>(k));
  std::vector<std::int64_t> best_index(static_cast<std::size_t>(k));
  for (std::int64_t p = 0; p < count; ++p) {
    distancesTo(c, count, c.x[p], c.y[p], c.z[p], distances.data());
    distances[p] = kInfinity;  // not its own neighbour
    std::fill(best.begin(), best.end(), kInfinity);
    std::fill(best_index.begin(), best_index.end(), std::int64_t{0});
    for (std::int64_t j = 0; j < count; ++j) {
      const float d = distances[j];
      if (!(d < best[k - 1])) continue;
      int slot = k - 1;  // insertion into the sorted k best
      while (slot > 0 && d < best[slot - 1]) {
        best[slot] = best[slot - 1];
        best_index[slot] = best_index[slot - 1];
        --slot;
      }
      best[slot] = d;
      best_index[slot] = j;
    }
    std::copy(best_index.begin(), best_index.end(), neighbours + p * k);
  }
}

void planeChamferTable(const float* predicted, std::int64_t planes_predicted, std::int64_t per_plane,
                       const float* gt, const std::int64_t* labels, std::int64_t gt_count, int gt_planes,
                       double* chamfer) {
  std::vector<std::int64_t> points_of_plane(static_cast<std::size_t>(gt_planes), 0);
  for (std::int64_t q = 0; q < gt_count; ++q)
    if (labels[q] >= 0 && labels[q] < gt_planes) ++points_of_plane[labels[q]];
  // nearest_to_gt_plane[g · per_plane + p]: distance from point p of the current prediction to GT plane g.
  std::vector<float> nearest_to_gt_plane(static_cast<std::size_t>(gt_planes * per_plane));
  std::vector<double> gt_to_prediction(static_cast<std::size_t>(gt_planes));
  std::vector<float> distances(static_cast<std::size_t>(per_plane));
  for (std::int64_t j = 0; j < planes_predicted; ++j) {
    const Columns c(predicted + j * per_plane * 3, per_plane);
    std::fill(nearest_to_gt_plane.begin(), nearest_to_gt_plane.end(), kInfinity);
    std::fill(gt_to_prediction.begin(), gt_to_prediction.end(), 0.0);
    for (std::int64_t q = 0; q < gt_count; ++q) {
      const std::int64_t g = labels[q];
      if (g < 0 || g >= gt_planes) continue;
      distancesTo(c, per_plane, gt[3 * q], gt[3 * q + 1], gt[3 * q + 2], distances.data());
      float* to_plane = nearest_to_gt_plane.data() + g * per_plane;
      float nearest = kInfinity;
      for (std::int64_t p = 0; p < per_plane; ++p) {
        nearest = std::min(nearest, distances[p]);
        to_plane[p] = std::min(to_plane[p], distances[p]);
      }
      gt_to_prediction[g] += nearest;
    }
    for (int g = 0; g < gt_planes; ++g) {
      double value = 0.0;
      if (points_of_plane[g] > 0) {
        double sum = 0.0;
        for (std::int64_t p = 0; p < per_plane; ++p) sum += nearest_to_gt_plane[g * per_plane + p];
        value = sum / static_cast<double>(per_plane) + gt_to_prediction[g] / static_cast<double>(points_of_plane[g]);
      }
      chamfer[g * planes_predicted + j] = value;
    }
  }
}

}  // namespace paco::completion::detail
