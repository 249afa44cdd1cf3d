# The fuzz build beside the normal one: the same sources configured again in build/fuzz with
# Debian's clang-14, every library instrumented for libFuzzer's coverage and for AddressSanitizer
# and UndefinedBehaviorSanitizer (-DSAGE_FUZZ_BUILD=ON), and the harnesses of tests/fuzz linked
# with libFuzzer. The gcc Release build stays as it is; `cmake --build build` builds both, and
# ctest runs each harness briefly (label `fuzz`) on its seed corpus (made from the project's own
# missions), the shipped scenarios and every input that once broke something
# (tests/fuzz/regressions). Off with -DSAGE_FUZZ=OFF, or when clang-14 or its libFuzzer runtime
# (libclang-rt-14-dev) is missing. The long run is in the README.
find_program(SAGE_FUZZ_CLANG clang-14)
find_program(SAGE_FUZZ_CLANGXX clang++-14)
find_file(SAGE_FUZZ_RUNTIME libclang_rt.fuzzer-x86_64.a PATHS /usr/lib/llvm-14/lib/clang PATH_SUFFIXES
          14.0.6/lib/linux 14/lib/linux NO_DEFAULT_PATH)
if(NOT SAGE_FUZZ_CLANG OR NOT SAGE_FUZZ_CLANGXX OR NOT SAGE_FUZZ_RUNTIME)
  message(STATUS "Fuzz harnesses: off (need clang-14 and libclang-rt-14-dev; .ci/install-deps installs them)")
  return()
endif()

include(ExternalProject)
set(SAGE_FUZZ_DIR ${CMAKE_BINARY_DIR}/fuzz)
set(sage_fuzz_args
  # -O1 with assertions on: quicker to build, and a broken assertion is a finding too.
  -DCMAKE_BUILD_TYPE=Release
  -DCMAKE_CXX_FLAGS_RELEASE=-O1
  -DCMAKE_C_FLAGS_RELEASE=-O1
  -DCMAKE_C_COMPILER=${SAGE_FUZZ_CLANG}
  -DCMAKE_CXX_COMPILER=${SAGE_FUZZ_CLANGXX}
  -DSAGE_FUZZ_BUILD=ON)
if(CMAKE_CXX_COMPILER_LAUNCHER)
  list(APPEND sage_fuzz_args -DCMAKE_CXX_COMPILER_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER}
       -DCMAKE_C_COMPILER_LAUNCHER=${CMAKE_C_COMPILER_LAUNCHER})
endif()
ExternalProject_Add(sage_fuzz
  SOURCE_DIR ${PROJECT_SOURCE_DIR}
  BINARY_DIR ${SAGE_FUZZ_DIR}
  CMAKE_ARGS ${sage_fuzz_args}
  # $(MAKE) shares the parent build's job slots (-j2 stays -j2).
  BUILD_COMMAND $(MAKE) sage_fuzz_all
  INSTALL_COMMAND ""
  BUILD_ALWAYS ON
  USES_TERMINAL_BUILD OFF)

# A few seconds each (the whole fuzz label takes ~35 s of wall time with ctest -j2); the inputs
# they find go to build/fuzz/corpus/<harness>, which later runs start from.
set(sage_fuzz_seconds 8)
foreach(harness scenario evaluate_csv server_door agent_door)
  set(corpus ${SAGE_FUZZ_DIR}/corpus/${harness})
  set(dirs ${corpus} ${SAGE_FUZZ_DIR}/seeds/${harness} ${PROJECT_SOURCE_DIR}/tests/fuzz/regressions/${harness})
  if(harness STREQUAL "scenario")
    list(APPEND dirs ${PROJECT_SOURCE_DIR}/scenarios)
  endif()
  set(extra)
  if(EXISTS ${PROJECT_SOURCE_DIR}/tests/fuzz/${harness}.dict)
    set(extra -dict=${PROJECT_SOURCE_DIR}/tests/fuzz/${harness}.dict)
  endif()
  file(MAKE_DIRECTORY ${corpus})
  add_test(NAME fuzz.${harness}
    COMMAND ${SAGE_FUZZ_DIR}/bin/sage_fuzz_${harness} -max_total_time=${sage_fuzz_seconds} -timeout=10
            -rss_limit_mb=2048 -seed=1 -print_final_stats=1 ${extra} ${dirs})
  set_tests_properties(fuzz.${harness} PROPERTIES LABELS fuzz TIMEOUT 120)
endforeach()
