#include <paco/common/error.h>
#include <paco/segmentation/impl/planar_segmenter.hpp>
#include <paco/segmentation/segmentation.h>

namespace paco {

std::vector<std::string> availablePlanarSegmenters() {
  std::vector<std::string> names{"gocopp", "region-growing", "ransac"};
  if (efficientRansacAvailable()) names.push_back("efficient-ransac");
  return names;
}

template <typename PointT>
typename PlanarSegmenter<PointT>::Ptr makePlanarSegmenter(const std::string& name) {
  if (name == "gocopp") return std::make_shared<GoCoPPSegmenter<PointT>>();
  if (name == "region-growing") return std::make_shared<RegionGrowingSegmenter<PointT>>();
  if (name == "ransac") return std::make_shared<RansacSegmenter<PointT>>();
  if (name == "efficient-ransac") {
    if (!efficientRansacAvailable())
      throw InvalidInputError("planar segmenter 'efficient-ransac' needs CGAL, and this paco was built "
                              "without it (PACO_WITH_CGAL=OFF); use gocopp, region-growing or ransac");
    return std::make_shared<EfficientRansacSegmenter<PointT>>();
  }
  std::string known;
  for (const auto& n : availablePlanarSegmenters()) known += (known.empty() ? "" : ", ") + n;
  throw InvalidInputError("unknown planar segmenter '" + name + "'; choose one of: " + known);
}

template class PlanarSegmenter<pcl::PointXYZ>;
template class PlanarSegmenter<pcl::PointNormal>;
template PlanarSegmenter<pcl::PointXYZ>::Ptr makePlanarSegmenter<pcl::PointXYZ>(const std::string&);
template PlanarSegmenter<pcl::PointNormal>::Ptr makePlanarSegmenter<pcl::PointNormal>(const std::string&);

}  // namespace paco
