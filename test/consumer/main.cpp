// Builds against an installed paco and runs: normalises a cloud, writes it, and reads it back.
#include <paco/common/normalization.h>
#include <paco/io/cloud_io.h>

#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
  const std::string path = argc > 1 ? argv[1] : "consumer_cloud.pcd";
  pcl::PointCloud<pcl::PointNormal> cloud;
  for (int i = 0; i < 10; ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(i); p.y = 2.0f * static_cast<float>(i); p.z = 5.0f;
    p.normal_x = 0; p.normal_y = 0; p.normal_z = 1;
    cloud.push_back(p);
  }
  const auto norm = paco::Normalization::fromBoundingBox(cloud);
  norm.apply(cloud);
  paco::io::LabelledCloud out;
  out.points = cloud;
  out.has_normals = true;
  paco::io::saveCloud(path, out);
  const paco::io::LabelledCloud back = paco::io::loadCloud(path);
  std::printf("consumer: read %zu points back\n", back.points.size());
  return back.points.size() == cloud.size() ? 0 : 1;
}
