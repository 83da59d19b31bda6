// paco_bench_segmentation: every planar segmentation backend on partial clouds with known planes.
// Prints, per backend and cloud size: plane recall and precision (a visible GT plane with >= 50
// points is found when a segment overlaps it with IoU >= 0.5), NC_prim (mean |cos| between
// matched segment and GT plane normals), coverage, mean point-to-plane distance (fraction of the
// bounding-box diagonal) and the CPU time per cloud on one thread.
//   paco_bench_segmentation                          # generated shapes, 2k / 10k / 100k points
//   paco_bench_segmentation --mfcad ../shared/data/mfcad --mfcad-count 20 --million
#include "segmentation_fixtures.h"
#include "shapes.h"

#include <paco/common/angles.h>
#include <paco/common/error.h>
#include <paco/segmentation/segmentation.h>
#ifdef PACO_BENCH_WITH_IO
#include <paco/io/mesh_io.h>
#endif

#include <algorithm>
#include <ctime>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using paco::test::LabelledSample;

struct Shape {
  std::string name;
  paco::SurfaceMesh mesh;
};

/// GT plane id per face: coplanar faces share one (normals within ~0.06°, offsets within
/// 5e-4 of the diagonal, as the shared MFCAD table counts them).
std::vector<int> coplanarGroups(const paco::SurfaceMesh& mesh, std::vector<Eigen::Vector3d>& plane_normals) {
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  const double diagonal = (hi - lo).norm();
  std::vector<int> group(mesh.faces.size(), -1);
  std::vector<double> offsets;
  plane_normals.clear();
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    const Eigen::Vector3d n = paco::faceNormal(mesh, f);
    if (n.squaredNorm() < 0.5) continue;
    const double d = -n.dot(mesh.vertices[mesh.faces[f][0]]);
    for (std::size_t g = 0; g < plane_normals.size(); ++g)
      if (n.dot(plane_normals[g]) > 1.0 - 5.5e-7 && std::abs(d - offsets[g]) < 5e-4 * diagonal) {
        group[f] = static_cast<int>(g);
        break;
      }
    if (group[f] < 0) {
      group[f] = static_cast<int>(plane_normals.size());
      plane_normals.push_back(n);
      offsets.push_back(d);
    }
  }
  return group;
}

/// A partial cloud of about `count` points: sample count / (1 - missing) points, then drop the
/// `missing` fraction nearest a random viewpoint on a sphere around the shape.
LabelledSample partialCloud(const paco::SurfaceMesh& mesh, std::size_t count, double missing, double noise,
                            std::uint64_t seed) {
  const auto full_count = static_cast<std::size_t>(std::round(static_cast<double>(count) / (1.0 - missing)));
  LabelledSample full = paco::test::sampleShape(mesh, full_count, seed);
  std::vector<Eigen::Vector3d> plane_normals;
  const std::vector<int> group = coplanarGroups(mesh, plane_normals);
  for (auto& l : full.labels) l = group[static_cast<std::size_t>(l)];
  full.plane_normals = plane_normals;
  Eigen::Vector3d lo, hi;
  paco::boundingBox(mesh, lo, hi);
  std::mt19937_64 rng(seed * 7919 + 1);
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::Vector3d direction = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
  const Eigen::Vector3d viewpoint = 0.5 * (lo + hi) + direction * (hi - lo).norm();
  LabelledSample partial = paco::test::partialView(full, viewpoint.cast<float>(), missing);
  // Gaussian noise along each coordinate, sigma a fraction of the diagonal.
  std::normal_distribution<float> jitter(0.0f, static_cast<float>(noise * (hi - lo).norm()));
  if (noise > 0)
    for (auto& p : *partial.cloud) p.getVector3fMap() += Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
  return partial;
}

std::vector<Shape> generatedShapes() {
  using paco::test::makePrism;
  std::vector<Shape> shapes;
  shapes.push_back({"box", paco::test::makeBox({0, 0, 0}, {1.0, 0.7, 0.4})});
  shapes.push_back({"l-bracket", paco::test::makeLBracket()});
  shapes.push_back({"chamfered-cube", paco::test::makeChamferedCube()});
  shapes.push_back({"boss-on-slab", paco::test::makeBossOnSlab()});
  shapes.push_back({"hex-prism", makePrism({{1, 0}, {0.5, 0.87}, {-0.5, 0.87}, {-1, 0}, {-0.5, -0.87}, {0.5, -0.87}}, 0.8)});
  shapes.push_back({"t-prism", makePrism({{0, 0}, {0.3, 0}, {0.3, 0.6}, {0.6, 0.6}, {0.6, 0.8}, {-0.3, 0.8}, {-0.3, 0.6}, {0, 0.6}}, 0.5)});
  shapes.push_back({"u-channel", makePrism({{0, 0}, {1, 0}, {1, 0.6}, {0.8, 0.6}, {0.8, 0.2}, {0.2, 0.2}, {0.2, 0.6}, {0, 0.6}}, 1.2)});
  shapes.push_back({"wedge", makePrism({{0, 0}, {1, 0}, {1, 0.3}, {0, 0.8}}, 0.6)});
  // Oblique poses: no face on an axis plane.
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> angle(0.0, 2.0 * paco::kPi);
  for (auto& s : shapes) {
    const Eigen::Matrix3d r = (Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitZ()) *
                               Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitY()) *
                               Eigen::AngleAxisd(angle(rng), Eigen::Vector3d::UnitX()))
                                  .toRotationMatrix();
    paco::test::transformMesh(s.mesh, r, Eigen::Vector3d::Zero());
  }
  return shapes;
}

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 1469598103934665603ull;
  for (const unsigned char c : s) {
    h ^= c;
    h *= 1099511628211ull;
  }
  return h;
}

#ifdef PACO_BENCH_WITH_IO
/// The first `count` MFCAD parts (by name) of a fixed 10 % validation subset (FNV-1a of the name).
std::vector<Shape> mfcadShapes(const std::string& dir, std::size_t count) {
  std::vector<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    if (entry.path().extension() != ".obj") continue;
    const std::string name = entry.path().stem().string();
    if (fnv1a(name) % 10 == 0) names.push_back(name);
  }
  std::sort(names.begin(), names.end());
  std::vector<Shape> shapes;
  for (const auto& name : names) {
    if (shapes.size() >= count) break;
    shapes.push_back({name, paco::io::loadMesh(dir + "/" + name + ".obj")});
  }
  return shapes;
}
#endif

struct Scores {
  double recall = 0, precision = 0, nc_prim = 0, coverage = 0, distance = 0, seconds = 0, planes = 0;
  int clouds = 0;
};

void score(const LabelledSample& gt, const paco::PlanarSegmentation& seg, Scores& s) {
  std::map<int, int> gt_size;
  for (const int l : gt.labels) ++gt_size[l];
  std::vector<int> seg_size(seg.size(), 0);
  for (const int l : seg.labels)
    if (l >= 0) ++seg_size[static_cast<std::size_t>(l)];
  std::map<std::pair<int, int>, int> overlap;
  for (std::size_t i = 0; i < gt.labels.size(); ++i)
    if (seg.labels[i] >= 0) ++overlap[{gt.labels[i], seg.labels[i]}];
  int visible = 0, found = 0;
  double nc = 0;
  std::vector<char> segment_matched(seg.size(), 0);
  for (const auto& [g, size] : gt_size) {
    if (size < 50) continue;
    ++visible;
    for (std::size_t k = 0; k < seg.size(); ++k) {
      const auto it = overlap.find({g, static_cast<int>(k)});
      if (it == overlap.end()) continue;
      const double iou = it->second / static_cast<double>(size + seg_size[k] - it->second);
      if (iou >= 0.5) {  // at most one segment can pass 0.5 with a GT plane
        ++found;
        segment_matched[k] = 1;
        nc += std::min(1.0, std::abs(seg.planes[k].normal.dot(gt.plane_normals[static_cast<std::size_t>(g)])));
        break;
      }
    }
  }
  const double matched_segments = std::count(segment_matched.begin(), segment_matched.end(), 1);
  s.recall += visible > 0 ? static_cast<double>(found) / visible : 1.0;
  s.precision += seg.size() > 0 ? matched_segments / static_cast<double>(seg.size()) : 1.0;
  s.nc_prim += found > 0 ? nc / found : 0.0;
  s.coverage += seg.coverage();
  // Mean point-to-plane distance of the assigned points, as a fraction of the diagonal.
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  for (const auto& p : *gt.cloud) {
    lo = lo.cwiseMin(p.getVector3fMap());
    hi = hi.cwiseMax(p.getVector3fMap());
  }
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < seg.labels.size(); ++i) {
    if (seg.labels[i] < 0) continue;
    sum += std::abs(seg.planes[static_cast<std::size_t>(seg.labels[i])].signedDistance(
        (*gt.cloud)[i].getVector3fMap().cast<double>()));
    ++n;
  }
  s.distance += n > 0 ? sum / static_cast<double>(n) / static_cast<double>((hi - lo).norm()) : 0.0;
  s.planes += static_cast<double>(seg.size());
  ++s.clouds;
}

double cpuSeconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double runOnce(const std::string& backend, const LabelledSample& cloud, bool estimate_normals,
               paco::PlanarSegmentation& result) {
  // CPU time of the process: the machine may be shared, and the backends run on one thread.
  const double start = cpuSeconds();
  if (estimate_normals) {
    auto seg = paco::makePlanarSegmenter<pcl::PointXYZ>(backend);
    seg->setNumberOfThreads(1);
    seg->setInputCloud(paco::test::withoutNormals(*cloud.cloud));
    seg->segment(result);
  } else {
    auto seg = paco::makePlanarSegmenter<pcl::PointNormal>(backend);
    seg->setNumberOfThreads(1);
    seg->setInputCloud(cloud.cloud);
    seg->segment(result);
  }
  return cpuSeconds() - start;
}

std::vector<std::size_t> parseSizes(const std::string& text) {
  std::vector<std::size_t> sizes;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) sizes.push_back(static_cast<std::size_t>(std::stoul(item)));
  return sizes;
}

void printHelp() {
  std::printf(
      "Usage: paco_bench_segmentation [--sizes 2000,10000,100000] [--missing 0.5] [--views 2] [--noise 0]\n"
      "                               [--backends gocopp,ransac,...] [--estimate-normals]\n"
      "                               [--mfcad DIR --mfcad-count 20] [--million]\n"
      "Runs every planar segmentation backend on partial clouds with known planes (generated\n"
      "shapes, and MFCAD validation parts with --mfcad) and prints a table.\n");
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::size_t> sizes{2000, 10000, 100000};
  std::vector<std::string> backends = paco::availablePlanarSegmenters();
  double missing = 0.5, noise = 0.0;
  int views = 2;
  bool estimate_normals = false, million = false;
  std::string mfcad_dir;
  std::size_t mfcad_count = 20;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "missing value after %s\n", a.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--help" || a == "-h") {
      printHelp();
      return 0;
    } else if (a == "--sizes") {
      sizes = parseSizes(next());
    } else if (a == "--missing") {
      missing = std::stod(next());
    } else if (a == "--noise") {
      noise = std::stod(next());
    } else if (a == "--views") {
      views = std::stoi(next());
    } else if (a == "--backends") {
      backends.clear();
      std::stringstream ss(next());
      std::string item;
      while (std::getline(ss, item, ',')) backends.push_back(item);
    } else if (a == "--estimate-normals") {
      estimate_normals = true;
    } else if (a == "--mfcad") {
      mfcad_dir = next();
    } else if (a == "--mfcad-count") {
      mfcad_count = static_cast<std::size_t>(std::stoul(next()));
    } else if (a == "--million") {
      million = true;
    } else {
      std::fprintf(stderr, "unknown argument '%s'; try --help\n", a.c_str());
      return 2;
    }
  }

  try {
    std::vector<std::pair<std::string, std::vector<Shape>>> datasets;
    datasets.emplace_back("generated", generatedShapes());
    if (!mfcad_dir.empty()) {
#ifdef PACO_BENCH_WITH_IO
      datasets.emplace_back("mfcad-val", mfcadShapes(mfcad_dir, mfcad_count));
#else
      std::fprintf(stderr, "--mfcad needs paco::io; build it too\n");
      return 2;
#endif
    }
    std::printf("partial clouds: %.0f %% missing, %d views per shape, noise %.4f x diagonal, normals %s, 1 thread\n\n",
                100 * missing, views, noise, estimate_normals ? "estimated (k = 20)" : "given (face normals)");
    std::printf("| data | points | backend | clouds | recall | precision | NC_prim | coverage | mean dist (x diag) | planes | CPU s / cloud |\n");
    std::printf("|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const auto& [data_name, shapes] : datasets) {
      for (const std::size_t size : sizes) {
        std::vector<LabelledSample> clouds;
        for (std::size_t s = 0; s < shapes.size(); ++s)
          for (int v = 0; v < views; ++v)
            clouds.push_back(partialCloud(shapes[s].mesh, size, missing, noise, 1000 * s + static_cast<std::uint64_t>(v) + 1));
        for (const auto& backend : backends) {
          Scores scores;
          for (const auto& cloud : clouds) {
            paco::PlanarSegmentation result;
            scores.seconds += runOnce(backend, cloud, estimate_normals, result);
            score(cloud, result, scores);
          }
          const double n = scores.clouds;
          std::printf("| %s | %zu | %s | %d | %.3f | %.3f | %.4f | %.3f | %.5f | %.1f | %.4f |\n", data_name.c_str(),
                      size, backend.c_str(), scores.clouds, scores.recall / n, scores.precision / n,
                      scores.nc_prim / n, scores.coverage / n, scores.distance / n, scores.planes / n,
                      scores.seconds / n);
          std::fflush(stdout);
        }
      }
    }
    if (million) {
      std::printf("\n1 M points (l-bracket, %.0f %% missing):\n", 100 * missing);
      const auto shapes = generatedShapes();
      const LabelledSample cloud = partialCloud(shapes[1].mesh, 1000000, missing, noise, 99);
      for (const auto& backend : backends) {
        paco::PlanarSegmentation result;
        const double seconds = runOnce(backend, cloud, estimate_normals, result);
        Scores s;
        score(cloud, result, s);
        std::printf("  %-16s %zu points: %.2f s, %zu planes, recall %.3f, coverage %.3f\n", backend.c_str(),
                    cloud.cloud->size(), seconds, result.size(), s.recall, s.coverage);
        std::fflush(stdout);
      }
    }
  } catch (const paco::Error& e) {
    std::fprintf(stderr, "paco_bench_segmentation: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
