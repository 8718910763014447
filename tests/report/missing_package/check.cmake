# Configures missing_package/ with NHDYN_THREE_JS pointing nowhere and checks that the error names
# the Debian package to install (libjs-three).
file(REMOVE_RECURSE "${WORK}")
execute_process(COMMAND ${CMAKE_COMMAND} -S "${SOURCE}" -B "${WORK}" -DRESOURCES=${RESOURCES}
                        -DNHDYN_THREE_JS=/nonexistent/three.min.js
                RESULT_VARIABLE result OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(result EQUAL 0)
  message(FATAL_ERROR "configuring without three.js succeeded; it must stop and name libjs-three")
endif()
string(REGEX REPLACE "[ \n]+" " " flat "${err}")  # CMake wraps its messages
string(FIND "${flat}" "install the Debian package libjs-three" found)
if(found EQUAL -1)
  message(FATAL_ERROR "the configuration failed without naming libjs-three:\n${err}")
endif()
message(STATUS "the build names the package: ok")
