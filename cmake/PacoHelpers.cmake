# paco_add_module(NAME <m> SOURCES ... PUBLIC_DEPS ... PRIVATE_DEPS ...)
# Creates the library target paco_<m>, its alias paco::<m>, include dirs, warnings and install rules.
function(paco_add_module)
  cmake_parse_arguments(ARG "" "NAME" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS;PRIVATE_DEFINITIONS" ${ARGN})
  set(target paco_${ARG_NAME})
  add_library(${target} ${ARG_SOURCES})
  add_library(paco::${ARG_NAME} ALIAS ${target})
  set_target_properties(${target} PROPERTIES EXPORT_NAME ${ARG_NAME} OUTPUT_NAME paco_${ARG_NAME})
  target_include_directories(${target} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(${target} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_definitions(${target} PRIVATE ${ARG_PRIVATE_DEFINITIONS})
  paco_set_warnings(${target})
  # An installed sanitized library asks its consumers to build sanitized too. Linking needs the
  # sanitizer's runtime (else undefined __asan_* symbols), and compiling needs the same Eigen:
  # under AddressSanitizer Eigen aligns its own allocations, so a vector of PCL points allocated in
  # paco and freed in unsanitized code is freed at the wrong address. In the build tree
  # add_compile_options and add_link_options already apply.
  if(PACO_SANITIZE)
    target_compile_options(${target} INTERFACE $<INSTALL_INTERFACE:-fsanitize=${PACO_SANITIZE}>)
    target_link_options(${target} INTERFACE $<INSTALL_INTERFACE:-fsanitize=${PACO_SANITIZE}>)
  endif()
  install(TARGETS ${target} EXPORT pacoTargets
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endfunction()

# Our own code builds with -Wall -Wextra and no warnings; third-party headers are included as
# SYSTEM by their imported targets, so their warnings do not count against us.
function(paco_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wno-deprecated-declarations)
endfunction()

# paco_add_tool(<name> SOURCES ... DEPS ...): a command-line tool, installed to bin/.
function(paco_add_tool name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS})
  paco_set_warnings(${name})
  install(TARGETS ${name} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endfunction()

# paco_add_gtest(<name> SOURCES ... DEPS ... [LABELS ...]): one GoogleTest executable whose cases
# are registered with ctest one by one.
function(paco_add_gtest name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main paco_test_support)
  paco_set_warnings(${name})
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
endfunction()
