#pragma once
// Usage:
//   paco::BlasInfo info = paco::detectBlas();
//   if (!info.is_openmp_openblas) std::cerr << info.warning() << "\n";
//   paco::warnIfSlowBlas();   // prints that warning once per process, to stderr
#include <string>

namespace paco {

/// Which BLAS library LibTorch will call. Debian selects it through the alternatives system; the
/// OpenMP build of OpenBLAS is 2.5x faster than the pthread build and ~19x faster than the
/// reference BLAS for our transformer.
struct BlasInfo {
  std::string library_path;  ///< resolved path of the libblas.so.3 in use (empty if unknown)
  bool is_openmp_openblas = false;
  std::string warning() const;
};

/// Looks at the libblas.so.3 already mapped into this process, or else the one the dynamic
/// linker would pick (the Debian alternative).
BlasInfo detectBlas();
/// Prints BlasInfo::warning() to stderr once per process when the BLAS is not OpenMP OpenBLAS.
void warnIfSlowBlas();

}  // namespace paco
