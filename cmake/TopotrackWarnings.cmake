# Per-target warnings (no global flags).

# topotrack_unity(TARGET BATCH): compile TARGET's sources as unity sources of BATCH files each (0: one for all).
# The one place the project's unity builds are set. Off under the sanitizers (TOPOTRACK_SANITIZE): there a unity
# source is one long instrumented compile on one core at the end of the build, while its files one by one share
# both cores (tools/sanitize.sh --quick, in CI).
function(topotrack_unity target batch)
  get_target_property(sources ${target} SOURCES)
  list(LENGTH sources n_sources)
  if(n_sources GREATER 1 AND NOT TOPOTRACK_SANITIZE)
    set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_BATCH_SIZE ${batch})
  endif()
endfunction()
function(topotrack_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow=local
    -Wno-deprecated-declarations -Wno-unused-parameter)
endfunction()

# topotrack_library(NAME SOURCES ... DEPS ...): a static library topotrack_NAME with the
# alias topotrack::NAME, headers found from the repository root ("kernels/mesh/x.hpp").
function(topotrack_library name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(topotrack_${name} STATIC ${ARG_SOURCES})
  add_library(topotrack::${name} ALIAS topotrack_${name})
  set_target_properties(topotrack_${name} PROPERTIES EXPORT_NAME ${name})
  target_include_directories(topotrack_${name} PUBLIC
    $<BUILD_INTERFACE:${PROJECT_SOURCE_DIR}>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}/topotrack>)
  target_link_libraries(topotrack_${name} PUBLIC ${ARG_DEPS} PRIVATE ${ARG_PRIVATE_DEPS})
  target_compile_features(topotrack_${name} PUBLIC cxx_std_20)
  topotrack_warnings(topotrack_${name})
  install(TARGETS topotrack_${name} EXPORT topotrackTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR})
  # Install the public headers of this library, keeping their path below the root.
  file(RELATIVE_PATH rel ${PROJECT_SOURCE_DIR} ${CMAKE_CURRENT_SOURCE_DIR})
  install(DIRECTORY ${CMAKE_CURRENT_SOURCE_DIR}/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/topotrack/${rel}
    FILES_MATCHING PATTERN "*.hpp")
endfunction()

# topotrack_test(NAME SOURCES ... DEPS ... [LABELS ...]): one GoogleTest executable, registered with ctest.
function(topotrack_test name)
  cmake_parse_arguments(ARG "" "" "SOURCES;DEPS;LABELS" ${ARGN})
  add_executable(${name} ${ARG_SOURCES})
  target_link_libraries(${name} PRIVATE ${ARG_DEPS} GTest::gtest GTest::gtest_main)
  target_include_directories(${name} PRIVATE ${PROJECT_SOURCE_DIR})
  target_compile_definitions(${name} PRIVATE
    TOPOTRACK_SOURCE_DIR="${PROJECT_SOURCE_DIR}"
    TOPOTRACK_SHARED_DIR="${PROJECT_SOURCE_DIR}/../shared"
    TOPOTRACK_BINARY_DIR="${PROJECT_BINARY_DIR}")
  topotrack_warnings(${name})
  # Several sources: one unity source, so gtest's, Eigen's and OpenVDB's headers are parsed once per executable
  # (the build's time on the 2-core CI machine is mostly those headers; tools/CMakeLists.txt).
  topotrack_unity(${name} 0)
  include(GoogleTest)
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60 PROPERTIES LABELS "${ARG_LABELS}")
endfunction()
