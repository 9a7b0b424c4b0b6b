# Helpers shared by every millwatch target.

# a·b + c is never fused into one FMA, whatever -march a packager adds: the results (and the
# tests that compare code paths bit for bit, e.g. the low-pass's SSE2 and AVX kernels and
# step()) do not depend on the build flags. GCC's default in C++ is -ffp-contract=fast.
add_compile_options(-ffp-contract=off)

# Warnings (as errors) for the project's own code only; third-party headers are SYSTEM.
function(millwatch_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Werror -Wshadow
                                           -Wnon-virtual-dtor -Wold-style-cast)
endfunction()

if(MILLWATCH_FUZZ)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "MILLWATCH_FUZZ needs clang (-DCMAKE_CXX_COMPILER=clang++): "
                        "libFuzzer is part of clang")
  endif()
  # Every target gets libFuzzer's coverage instrumentation and the sanitizers; only the fuzz
  # targets link libFuzzer's main (tests/fuzz). vptr off for the same reason as below.
  add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize=vptr
                      -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  add_link_options(-fsanitize=address,undefined)
elseif(MILLWATCH_SANITIZE)
  # -fno-sanitize=vptr: with UBSan's vptr check on, lcm 1.3.1's C++ subscription callbacks
  # (lcm-cpp-impl.hpp's cb_func) are handed a user_data that is not their subscription object and
  # fail on the first message; without the check they work (tests/messaging/lcm_output_test.cpp).
  add_compile_options(-fsanitize=address,undefined -fno-sanitize=vptr -fno-omit-frame-pointer
                      -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

# Sanitized, a test's own code (set-up and assertions) is compiled without optimisation, and
# with it the inline and template code of the libraries' headers that a test instantiates; the
# libraries' own sources keep the build's -O1. The test executables then compile in about 60 %
# of the time, and the suite runs 3–5 % longer (the same results: -ffp-contract=off). The tests'
# precompiled header (tests/support) is compiled with the same options, as it must be.
set(MILLWATCH_TEST_CODE_OPTIONS "")
if(MILLWATCH_SANITIZE)
  set(MILLWATCH_TEST_CODE_OPTIONS -O0)
endif()

# millwatch_test(<source>): one GoogleTest executable per *_test.cpp, registered with CTest.
function(millwatch_test source)
  get_filename_component(name ${source} NAME_WE)
  add_executable(${name} ${source})
  target_link_libraries(${name} PRIVATE millwatch::test_support GTest::gtest_main)
  millwatch_warnings(${name})
  target_precompile_headers(${name} REUSE_FROM millwatch_test_pch)  # tests/support/
  target_compile_options(${name} PRIVATE ${MILLWATCH_TEST_CODE_OPTIONS})
  # Multi-process LCM sessions (tests/daemon) run alone: on a busy 2-core machine the UDP
  # receivers of a paced session can fall behind.
  set(serial FALSE)
  if(source MATCHES "/tests/daemon/")
    set(serial TRUE)
  endif()
  gtest_discover_tests(${name} DISCOVERY_TIMEOUT 60
                       PROPERTIES ENVIRONMENT "MILLWATCH_SHARED_DIR=${MILLWATCH_SHARED_DIR}"
                                  RUN_SERIAL ${serial})
endfunction()
