# The version of nhdyn (project(VERSION) in the top CMakeLists.txt) and the git commit the build
# was configured from, written into the generated header nhdyn/core/version.hpp.
#
# The commit is read once, at configure time: a build reports the commit its build directory was
# configured at (re-run cmake to refresh it). Outside a git checkout of this project (a source
# tarball, or a tarball unpacked inside some other repository) it is "unknown"; packagers can give
# it with -DNHDYN_GIT_COMMIT=<hash>. The header holds nothing else that varies (no date, no host),
# so that two builds of the same commit are identical.
if(DEFINED CACHE{NHDYN_GIT_COMMIT})
  set(nhdyn_commit "${NHDYN_GIT_COMMIT}")
else()
  set(nhdyn_commit "unknown")
  find_package(Git QUIET)
  if(GIT_FOUND)
    execute_process(COMMAND "${GIT_EXECUTABLE}" rev-parse --show-toplevel
                    WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE nhdyn_git_top
                    RESULT_VARIABLE nhdyn_git_rc OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
    file(REAL_PATH "${PROJECT_SOURCE_DIR}" nhdyn_source_real)
    if(nhdyn_git_rc EQUAL 0 AND EXISTS "${nhdyn_git_top}")
      file(REAL_PATH "${nhdyn_git_top}" nhdyn_git_top)
    endif()
    # Only this project's own repository counts (not one that merely contains the sources).
    if(nhdyn_git_rc EQUAL 0 AND nhdyn_git_top STREQUAL nhdyn_source_real)
      execute_process(COMMAND "${GIT_EXECUTABLE}" rev-parse --short=12 HEAD
                      WORKING_DIRECTORY "${PROJECT_SOURCE_DIR}" OUTPUT_VARIABLE nhdyn_git_head
                      RESULT_VARIABLE nhdyn_git_rc OUTPUT_STRIP_TRAILING_WHITESPACE ERROR_QUIET)
      if(nhdyn_git_rc EQUAL 0 AND nhdyn_git_head MATCHES "^[0-9a-f]+$")
        set(nhdyn_commit "${nhdyn_git_head}")
      endif()
    endif()
  endif()
endif()
set(NHDYN_GIT_COMMIT_CONFIGURED "${nhdyn_commit}")
set(NHDYN_GENERATED_INCLUDE_DIR "${PROJECT_BINARY_DIR}/generated")
configure_file("${PROJECT_SOURCE_DIR}/src/nhdyn/core/version.hpp.in"
               "${NHDYN_GENERATED_INCLUDE_DIR}/nhdyn/core/version.hpp" @ONLY)
message(STATUS "nhdyn ${PROJECT_VERSION} (commit ${nhdyn_commit})")
