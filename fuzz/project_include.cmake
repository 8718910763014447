# For fuzz/run only, while the top-level CMakeLists.txt has no NHDYN_FUZZ option: included right
# after project() through CMAKE_PROJECT_INCLUDE, it does what the option does. The fuzzer links
# the libraries by name, which CMake resolves once the whole project is read.
include(${CMAKE_CURRENT_LIST_DIR}/flags.cmake)
add_subdirectory(${CMAKE_CURRENT_LIST_DIR} ${CMAKE_BINARY_DIR}/fuzz)
