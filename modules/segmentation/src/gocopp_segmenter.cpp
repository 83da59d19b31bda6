#include <paco/common/error.h>
#include <paco/segmentation/gocopp_segmenter.h>

#include <string>

namespace paco {

template <typename PointT>
void GoCoPPSegmenter<PointT>::setLambdaSimplicity(double lambda) {
  if (!(lambda >= 0.0 && lambda < 3.0))
    throw InvalidInputError("GoCoPPSegmenter::setLambdaSimplicity: λs must be in [0, 3); got " + std::to_string(lambda));
  lambda_simplicity_ = lambda;
}

template <typename PointT>
void GoCoPPSegmenter<PointT>::setLambdaCompleteness(double lambda) {
  if (!(lambda >= 0.0 && lambda < 3.0))
    throw InvalidInputError("GoCoPPSegmenter::setLambdaCompleteness: λc must be in [0, 3); got " + std::to_string(lambda));
  lambda_completeness_ = lambda;
}

template <typename PointT>
void GoCoPPSegmenter<PointT>::setMaxRounds(int rounds) {
  if (rounds < 0)
    throw InvalidInputError("GoCoPPSegmenter::setMaxRounds: rounds must be >= 0; got " + std::to_string(rounds));
  max_rounds_ = rounds;
}

template <typename PointT>
void GoCoPPSegmenter<PointT>::performSegmentation(std::vector<int>& labels) {
  GoCoPPParameters parameters;
  parameters.epsilon = this->used_distance_threshold_;  // the working frame has a unit diagonal
  parameters.normal_threshold = this->normal_threshold_;
  parameters.min_points = this->used_min_points_;
  parameters.neighbours = this->neighbours_;
  parameters.lambda_simplicity = lambda_simplicity_;
  parameters.lambda_completeness = lambda_completeness_;
  parameters.max_rounds = max_rounds_;
  const auto& prepared = this->prepared_;
  GoCoPPOptimizer optimizer(*prepared.points, prepared.neighbours(this->neighbours_), parameters);
  optimizer.growRegions();
  initial_energy_ = optimizer.energy();
  optimizer.optimize();
  final_energy_ = optimizer.energy();
  labels = optimizer.labels();
}

template class GoCoPPSegmenter<pcl::PointXYZ>;
template class GoCoPPSegmenter<pcl::PointNormal>;

}  // namespace paco
