# Finds every third-party dependency of paco. Used by the build and, installed, by
# pacoConfig.cmake so that a consumer's find_package(paco) finds the same dependencies.
include(CMakeFindDependencyMacro)
list(APPEND CMAKE_MODULE_PATH "${CMAKE_CURRENT_LIST_DIR}")

if(NOT DEFINED PACO_WITH_CGAL)
  set(PACO_WITH_CGAL ON)
endif()
if(NOT DEFINED PACO_WITH_TORCH)
  set(PACO_WITH_TORCH ON)
endif()

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(Threads REQUIRED)
find_package(OpenMP REQUIRED COMPONENTS CXX)
# Only the PCL components we use: each further one drags in more of VTK and Qt.
find_package(PCL 1.12 REQUIRED COMPONENTS common io kdtree search features segmentation
             sample_consensus filters)
# Debian's VTK (linked by pcl_features and pcl_io) lists MPI::MPI_C in VTK::mpi's interface, but
# paco enables no C language, so FindMPI cannot create it: stand in an empty target (the VTK
# shared libraries carry their own MPI dependency).
if(TARGET VTK::mpi AND NOT TARGET MPI::MPI_C)
  add_library(MPI::MPI_C INTERFACE IMPORTED)
endif()
# PCL's own FindFLANN provides FLANN::FLANN (FLANN ships no CMake config).
if(NOT TARGET FLANN::FLANN)
  find_package(FLANN REQUIRED)
endif()
find_package(Boost 1.71 REQUIRED COMPONENTS program_options)

if(PACO_WITH_CGAL)
  # CGAL 5 is header-only; GMP/MPFR come with its exact kernels.
  set(CGAL_DO_NOT_WARN_ABOUT_CMAKE_BUILD_TYPE TRUE)
  find_package(CGAL 5.4 REQUIRED)
  find_package(CBC REQUIRED)
  find_package(GLPK REQUIRED)
endif()

if(PACO_WITH_TORCH)
  find_package(Torch REQUIRED)
  # zlib's CRC-32 checks model weights (13x faster than Boost.CRC's on 16 MB).
  find_package(ZLIB REQUIRED)
endif()
