# Sanitizer and fuzzing builds (issue #9), off by default.
#   -DTOPOTRACK_SANITIZE=address,undefined  every target of the project compiled and linked with these
#       sanitizers (frame pointers kept, UBSan fatal). Global on purpose: ASan wants every translation unit
#       of the project instrumented. tools/sanitize.sh builds and runs the suite this way in build-asan.
#   -DTOPOTRACK_FUZZ=ON (clang only)  additionally instruments the project for libFuzzer coverage and builds
#       the fuzz targets of tests/fuzz; tools/fuzz.sh builds and runs them in build-fuzz.
set(TOPOTRACK_SANITIZE "" CACHE STRING "Comma-separated sanitizers for every target (e.g. address,undefined)")
option(TOPOTRACK_FUZZ "Build the libFuzzer targets of tests/fuzz (clang)" OFF)

if(TOPOTRACK_SANITIZE)
  set(_tt_san -fsanitize=${TOPOTRACK_SANITIZE} -fno-omit-frame-pointer)
  if(TOPOTRACK_SANITIZE MATCHES "undefined")
    list(APPEND _tt_san -fno-sanitize-recover=undefined)
  endif()
  add_compile_options(${_tt_san})
  add_link_options(-fsanitize=${TOPOTRACK_SANITIZE})
  message(STATUS "topotrack: sanitizers ${TOPOTRACK_SANITIZE}")
endif()

if(TOPOTRACK_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "TOPOTRACK_FUZZ needs clang (libFuzzer): CXX=clang++-14")
  endif()
  # -Wno-unknown-warning-option: the project's warning set has GCC-only spellings (-Wshadow=local).
  add_compile_options(-fsanitize=fuzzer-no-link -Wno-unknown-warning-option)
endif()
