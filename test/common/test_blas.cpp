#include <paco/common/blas.h>

#include <gtest/gtest.h>

// The install script selects the OpenMP OpenBLAS; LibTorch is 2.5-19x slower on any other BLAS.
// This fails loudly (with the fix in the message) when a machine is set up differently.
TEST(Blas, OpenMpOpenBlasIsSelected) {
  const paco::BlasInfo info = paco::detectBlas();
  EXPECT_TRUE(info.is_openmp_openblas) << info.warning();
  EXPECT_TRUE(info.warning().empty() == info.is_openmp_openblas);
}

TEST(Blas, WarningNamesTheLibraryAndTheFix) {
  paco::BlasInfo info;
  info.library_path = "/usr/lib/x86_64-linux-gnu/blas/libblas.so.3.11.0";
  info.is_openmp_openblas = false;
  EXPECT_NE(info.warning().find("blas/libblas.so.3.11.0"), std::string::npos);
  EXPECT_NE(info.warning().find("install-deps.sh"), std::string::npos);
}
