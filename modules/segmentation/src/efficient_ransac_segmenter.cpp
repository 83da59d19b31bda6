// The only file of paco::segmentation that includes CGAL (a private dependency).
#include <paco/common/error.h>
#include <paco/segmentation/efficient_ransac_segmenter.h>

#include <string>

#ifdef PACO_SEGMENTATION_WITH_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Random.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/property_map.h>

#include <tuple>
#include <utility>
#include <vector>
#endif

namespace paco {

bool efficientRansacAvailable() {
#ifdef PACO_SEGMENTATION_WITH_CGAL
  return true;
#else
  return false;
#endif
}

template <typename PointT>
void EfficientRansacSegmenter<PointT>::setProbability(double probability) {
  if (!(probability > 0.0 && probability < 1.0))
    throw InvalidInputError("EfficientRansacSegmenter::setProbability: needs a value in (0, 1); got " +
                            std::to_string(probability));
  probability_ = probability;
}

template <typename PointT>
void EfficientRansacSegmenter<PointT>::setClusterEpsilon(double fraction_of_diagonal) {
  if (!(fraction_of_diagonal >= 0.0 && fraction_of_diagonal < 1.0))
    throw InvalidInputError("EfficientRansacSegmenter::setClusterEpsilon: a fraction of the diagonal in [0, 1) "
                            "(0: automatic); got " + std::to_string(fraction_of_diagonal));
  cluster_epsilon_ = fraction_of_diagonal;
}

template <typename PointT>
void EfficientRansacSegmenter<PointT>::performSegmentation(std::vector<int>& labels) {
#ifdef PACO_SEGMENTATION_WITH_CGAL
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  // CGAL reorders the input range in place: each point carries its own index.
  using PointWithNormal = std::tuple<Kernel::Point_3, Kernel::Vector_3, int>;
  using PointList = std::vector<PointWithNormal>;
  using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, PointList,
                                                                CGAL::Nth_of_tuple_property_map<0, PointWithNormal>,
                                                                CGAL::Nth_of_tuple_property_map<1, PointWithNormal>>;
  using Detector = CGAL::Shape_detection::Efficient_RANSAC<Traits>;
  using PlaneShape = CGAL::Shape_detection::Plane<Traits>;

  const auto& prepared = this->prepared_;
  PointList list;
  list.reserve(prepared.size());
  for (std::size_t i = 0; i < prepared.size(); ++i) {
    const auto& p = (*prepared.points)[i];
    list.emplace_back(Kernel::Point_3(p.x, p.y, p.z), Kernel::Vector_3(p.normal_x, p.normal_y, p.normal_z),
                      static_cast<int>(i));
  }

  CGAL::get_default_random() = CGAL::Random(seed_);
  Detector detector;
  detector.set_input(list);
  detector.template add_shape_factory<PlaneShape>();
  typename Detector::Parameters parameters;
  parameters.probability = probability_;
  parameters.min_points = static_cast<std::size_t>(this->used_min_points_);
  parameters.epsilon = this->used_distance_threshold_;
  parameters.normal_threshold = this->normal_threshold_;
  parameters.cluster_epsilon = cluster_epsilon_ > 0.0 ? cluster_epsilon_ : 3.0 * prepared.averageSpacing();
  detector.detect(parameters);
  int label = 0;
  for (const auto& shape : detector.shapes()) {
    for (const auto i : shape->indices_of_assigned_points())
      labels[static_cast<std::size_t>(std::get<2>(list[i]))] = label;
    ++label;
  }
#else
  (void)labels;
  throw Error("efficient-ransac: this paco was built without CGAL (PACO_WITH_CGAL=OFF); rebuild with CGAL "
              "or use gocopp, region-growing or ransac");
#endif
}

template class EfficientRansacSegmenter<pcl::PointXYZ>;
template class EfficientRansacSegmenter<pcl::PointNormal>;

}  // namespace paco
