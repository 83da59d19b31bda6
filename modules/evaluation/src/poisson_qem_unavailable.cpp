// Built instead of poisson_qem.cpp when paco is configured without CGAL.
#include <paco/evaluation/methods.h>

#include <paco/common/error.h>

namespace paco::evaluation {

SurfaceMesh reconstructPoissonQem(const pcl::PointCloud<pcl::PointNormal>&, std::size_t, std::map<std::string, double>*) {
  throw InvalidInputError("reconstructPoissonQem: this build of paco has no CGAL (PACO_WITH_CGAL=OFF)");
}

}  // namespace paco::evaluation
