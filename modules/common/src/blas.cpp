#include <paco/common/blas.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <mutex>
#include <string>

namespace paco {

std::string BlasInfo::warning() const {
  if (is_openmp_openblas) return "";
  return "paco: warning: the BLAS in use is '" +
         (library_path.empty() ? std::string("unknown") : library_path) +
         "', not the OpenMP build of OpenBLAS; LibTorch runs 2.5-19x slower. Fix: run "
         "scripts/install-deps.sh as root (it installs libopenblas0-openmp and selects it with "
         "update-alternatives).";
}

namespace {
std::string resolve(const std::string& path) {
  char* real = realpath(path.c_str(), nullptr);
  if (!real) return "";
  std::string out(real);
  std::free(real);
  return out;
}
}  // namespace

BlasInfo detectBlas() {
  BlasInfo info;
  // Prefer what this process has actually mapped (LibTorch loads libblas.so.3 at start-up).
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    const auto slash = line.find('/');
    if (slash == std::string::npos) continue;
    const std::string path = line.substr(slash);
    if (path.find("libblas.so") != std::string::npos || path.find("libopenblas") != std::string::npos) {
      info.library_path = resolve(path);
      break;
    }
  }
  if (info.library_path.empty()) {
    for (const char* candidate : {"/usr/lib/x86_64-linux-gnu/libblas.so.3", "/usr/lib/aarch64-linux-gnu/libblas.so.3",
                                  "/usr/lib/libblas.so.3"}) {
      info.library_path = resolve(candidate);
      if (!info.library_path.empty()) break;
    }
  }
  info.is_openmp_openblas = info.library_path.find("openblas-openmp") != std::string::npos;
  return info;
}

void warnIfSlowBlas() {
  static std::once_flag once;
  std::call_once(once, [] {
    const BlasInfo info = detectBlas();
    if (!info.is_openmp_openblas) std::cerr << info.warning() << std::endl;
  });
}

}  // namespace paco
