# RADMESH_SANITIZE: every target of the project built with AddressSanitizer and
# UndefinedBehaviorSanitizer; any report aborts the program (so a test fails).
# RADMESH_FUZZ: also the libFuzzer targets in fuzz/ (clang only), with the
# readers and meshing instrumented for coverage (radmesh_fuzzed).
option(RADMESH_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer" OFF)
option(RADMESH_FUZZ "Build the libFuzzer targets in fuzz/ (clang; implies RADMESH_SANITIZE)" OFF)

if(RADMESH_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "RADMESH_FUZZ needs clang (libFuzzer): configure with CC=clang-14 CXX=clang++-14")
  endif()
  set(RADMESH_SANITIZE ON CACHE BOOL "" FORCE)
endif()

if(RADMESH_SANITIZE)
  # Not vptr: CGAL's arrangement iterators (used by the exact direct light)
  # downcast a base to the filtered iterator type, which vptr reports on every
  # use although the memory is that object's.
  set(radmesh_sanitizer_flags -fsanitize=address,undefined -fno-sanitize=vptr -fno-sanitize-recover=undefined
      -fno-omit-frame-pointer)
  if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    # Line tables are enough for the reports and cheap on the CGAL files.
    list(APPEND radmesh_sanitizer_flags -gline-tables-only)
  else()
    list(APPEND radmesh_sanitizer_flags -g1)
  endif()
  add_compile_options(${radmesh_sanitizer_flags})
  add_link_options(-fsanitize=address,undefined)
  # Compiled into every executable (tests, CLI, fuzzers): the sanitizers'
  # default settings and leak suppressions.
  set(RADMESH_SANITIZER_SOURCES ${PROJECT_SOURCE_DIR}/cmake/sanitizer_defaults.cpp)
endif()

# libFuzzer's coverage instrumentation (counters and comparison tracing) for
# the code the fuzz targets reach: the readers (io) and meshing. Not for the
# solvers, which no fuzz target calls: there it would only slow the
# sanitizer suite's tests (docs/decisions.md).
function(radmesh_fuzzed target)
  if(RADMESH_FUZZ)
    target_compile_options(${target} PRIVATE -fsanitize=fuzzer-no-link)
  endif()
endfunction()
