# Compiler flags of the fuzz build (NHDYN_FUZZ=ON): every target of the project is instrumented
# for libFuzzer's coverage and built with AddressSanitizer and UndefinedBehaviorSanitizer, so that
# a bug anywhere under the loader is found, not only in the fuzzer's own file. Clang only.
if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
  message(FATAL_ERROR "NHDYN_FUZZ needs clang (libFuzzer): configure with -DCMAKE_CXX_COMPILER=clang++-14 "
                      "-DCMAKE_C_COMPILER=clang-14, as fuzz/run does")
endif()
add_compile_options(-fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined
                    -fno-omit-frame-pointer -g)
add_link_options(-fsanitize=address,undefined)
