// How often segmentation without normals turns a plane against the face it lies on.
// Usage: paco_orientation_check DATASET_DIR SPLIT CASES [BACKEND [NEIGHBOURS]]
// Takes the first CASES view-0 samples of SPLIT (train|val|test) in a paco_dataset folder, drops
// their normals, segments them (BACKEND, default gocopp; NEIGHBOURS for normal estimation,
// default the segmenter's 20), and counts the segments whose plane faces against the GT face
// normals of most of its points (doc/segmentation.md, "Orienting planes without given normals").
// It also prints the share of points labelled, and the same with the given normals.
#include <paco/common/error.h>
#include <paco/data/dataset.h>
#include <paco/segmentation/segmentation.h>

#include <pcl/console/print.h>

#include <cstdio>
#include <exception>
#include <string>

int main(int argc, char** argv) {
  if (argc < 4 || argc > 6) {
    std::fprintf(stderr, "usage: %s DATASET_DIR SPLIT CASES [BACKEND [NEIGHBOURS]]\n", argv[0]);
    return 2;
  }
  try {
    const paco::data::Dataset dataset(argv[1]);
    const paco::data::Split split = paco::data::splitFromString(argv[2]);
    const std::size_t limit = std::stoul(argv[3]);
    const std::string backend = argc >= 5 ? argv[4] : "gocopp";
    const int neighbours = argc == 6 ? std::stoi(argv[5]) : 0;
    pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
    std::size_t cases = 0, cases_with_wrong = 0, segments = 0, wrong = 0;
    double coverage_estimated = 0.0, coverage_given = 0.0;
    for (const std::size_t index : dataset.select(split, std::nullopt, 0)) {
      if (cases == limit) break;
      const paco::data::Sample sample = dataset.load(split, index);
      pcl::PointCloud<pcl::PointXYZ>::Ptr positions(new pcl::PointCloud<pcl::PointXYZ>);
      for (const auto& p : sample.input) positions->push_back(pcl::PointXYZ(p.x, p.y, p.z));
      auto segmenter = paco::makePlanarSegmenter<pcl::PointXYZ>(backend);
      if (neighbours > 0) segmenter->setNumberOfNeighbours(neighbours);
      segmenter->setInputCloud(positions);
      paco::PlanarSegmentation result;
      segmenter->segment(result);
      auto with_normals = paco::makePlanarSegmenter<pcl::PointNormal>(backend);
      with_normals->setInputCloud(sample.input.makeShared());
      paco::PlanarSegmentation given;
      with_normals->segment(given);
      coverage_estimated += result.coverage();
      coverage_given += given.coverage();
      ++cases;
      bool any_wrong = false;
      for (std::size_t s = 0; s < result.size(); ++s) {
        long votes = 0;
        for (const int i : result.segments[s].indices) {
          const auto& p = sample.input[static_cast<std::size_t>(i)];
          votes += Eigen::Vector3d(p.normal_x, p.normal_y, p.normal_z).dot(result.planes[s].normal) > 0.0 ? 1 : -1;
        }
        ++segments;
        if (votes < 0) {
          ++wrong;
          any_wrong = true;
          std::printf("%s level %d: segment %zu (%zu points) faces inwards\n", sample.part.c_str(),
                      static_cast<int>(sample.level), s, result.segments[s].indices.size());
        }
      }
      cases_with_wrong += any_wrong;
    }
    std::printf("%zu cases, %zu with a segment facing inwards; %zu of %zu segments face inwards\n", cases,
                cases_with_wrong, wrong, segments);
    if (cases > 0)
      std::printf("points labelled: %.1f %% with estimated normals, %.1f %% with the given ones\n",
                  100.0 * coverage_estimated / static_cast<double>(cases),
                  100.0 * coverage_given / static_cast<double>(cases));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
