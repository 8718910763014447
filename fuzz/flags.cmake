# Compiler flags of the fuzz build (NHDYN_FUZZ=ON): every target of the project is instrumented
# for libFuzzer's coverage and built with AddressSanitizer and UndefinedBehaviorSanitizer, so that
# a bug anywhere under the loader is found, not only in the fuzzer's own file. Clang only.
# Optimization and debug info come from the build type (Sanitize: -O1 -g1, see CMakeLists.txt).
# The same instrumented objects serve the sanitizer tests (make asan), which link them without
# libFuzzer: the coverage callbacks then fall back to the sanitizer runtime's empty defaults.
if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  message(FATAL_ERROR "NHDYN_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++-14 "
                      "-DCMAKE_C_COMPILER=clang-14, as fuzz/run does")
endif()
add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                    -fno-omit-frame-pointer ${NHDYN_UBSAN_LEFT_OUT})
add_link_options(-fsanitize=address,undefined)
