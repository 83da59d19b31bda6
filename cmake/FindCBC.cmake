# FindCBC: COIN-OR CBC (branch and cut MIP solver) through pkg-config, as CBC::CBC.
find_package(PkgConfig REQUIRED)
pkg_check_modules(PC_CBC QUIET IMPORTED_TARGET cbc osi-clp)
include(FindPackageHandleStandardArgs)
find_package_handle_standard_args(CBC REQUIRED_VARS PC_CBC_FOUND
  FAIL_MESSAGE "COIN-OR CBC not found: run scripts/install-deps.sh (Debian package coinor-libcbc-dev)")
if(CBC_FOUND AND NOT TARGET CBC::CBC)
  add_library(CBC::CBC INTERFACE IMPORTED)
  target_link_libraries(CBC::CBC INTERFACE PkgConfig::PC_CBC)
endif()
