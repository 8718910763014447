# `cmake --install build --prefix P`: what nhdyn puts where (docs/install.md).
#   P/bin/nhdyn                                      the command line
#   P/include/nhdyn/...                              the library's headers (and the generated version.hpp)
#   P/lib/libnhdyn_*.a                               the library's modules, static
#   P/lib/nhdyn/libnhdyn_ipopt.so                    IPOPT's module, loaded by `nhdyn optimize` alone
#   P/lib/cmake/nhdyn/nhdynConfig.cmake (+Version)   find_package(nhdyn 0.2 CONFIG) -> nhdyn::nhdyn
#   P/lib/pkgconfig/nhdyn.pc                         pkg-config --cflags --libs nhdyn
#   P/lib/python3.X/site-packages/nhdyn              the Python package (the interpreter's layout: below)
#   P/share/doc/nhdyn                                README, CHANGELOG, docs/, examples/
#   P/share/doc/nhdyn/html                           the documentation site, when `make docs` has built it
#   P/share/man/man1/nhdyn.1                         the man page (help2man, when installed)
#   P/share/bash-completion/completions/nhdyn        bash completion
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

# --- The library: every module's static library, the interface target nhdyn::nhdyn over them, and
# the headers. Each module is exported as nhdyn::<module> (nhdyn::core, nhdyn::io, ...).
set(nhdyn_installed_modules core model formulation sundials integrators analysis symbolic jit io frontend studies)
set(nhdyn_installed_targets nhdyn)
foreach(module ${nhdyn_installed_modules})
  set_target_properties(nhdyn_${module} PROPERTIES EXPORT_NAME ${module})
  list(APPEND nhdyn_installed_targets nhdyn_${module})
endforeach()
install(TARGETS ${nhdyn_installed_targets} EXPORT nhdynTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
# optimize/ is not an installed module (its library links IPOPT, which the CLI and the Python
# package carry): its headers stay out with it. Neither are the modules' detail/ folders: the
# library's own headers, which no installed header includes (tests/layering checks it).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/nhdyn DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.hpp" PATTERN "resources" EXCLUDE PATTERN "optimize" EXCLUDE
        PATTERN "detail" EXCLUDE)
install(FILES ${NHDYN_GENERATED_INCLUDE_DIR}/nhdyn/core/version.hpp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/nhdyn/core)

set(nhdyn_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/nhdyn)
install(EXPORT nhdynTargets NAMESPACE nhdyn:: DESTINATION ${nhdyn_cmake_dir})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/nhdynConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/cmake/nhdynConfig.cmake INSTALL_DESTINATION ${nhdyn_cmake_dir})
# 0.x: a minor version may change the interface, so 0.2 accepts 0.2.* only; from 1.0 on, SameMajorVersion.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/cmake/nhdynConfigVersion.cmake
                                 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/cmake/nhdynConfig.cmake ${PROJECT_BINARY_DIR}/cmake/nhdynConfigVersion.cmake
        DESTINATION ${nhdyn_cmake_dir})

# pkg-config: relocatable (paths relative to the .pc file), so any --prefix works.
set(CMAKE_DL_LIBS_FLAG "")
if(CMAKE_DL_LIBS)
  set(CMAKE_DL_LIBS_FLAG "-l${CMAKE_DL_LIBS}")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/nhdyn.pc.in ${PROJECT_BINARY_DIR}/nhdyn.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/nhdyn.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

# --- The command line, its man page and its bash completion.
if(TARGET nhdyn_cli)
  install(TARGETS nhdyn_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  # IPOPT's module, which `nhdyn optimize` loads from there (src/nhdyn/optimize/ipopt/solver_module.cpp).
  if(TARGET nhdyn_ipopt_solver)
    install(FILES $<TARGET_FILE:nhdyn_ipopt_solver> DESTINATION ${CMAKE_INSTALL_LIBDIR}/nhdyn)
  endif()
  install(FILES ${PROJECT_SOURCE_DIR}/scripts/nhdyn.bash-completion DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions
          RENAME nhdyn)
  find_program(NHDYN_HELP2MAN help2man)
  if(NHDYN_HELP2MAN)
    # Written from the command's own --help (every subcommand's), so it cannot disagree with it.
    set(nhdyn_man ${PROJECT_BINARY_DIR}/man/nhdyn.1)
    add_custom_command(OUTPUT ${nhdyn_man}
                       COMMAND ${CMAKE_COMMAND} -DNHDYN=$<TARGET_FILE:nhdyn_cli> -DHELP2MAN=${NHDYN_HELP2MAN} -DOUT=${nhdyn_man}
                               -P ${PROJECT_SOURCE_DIR}/cmake/manpage.cmake
                       DEPENDS nhdyn_cli ${PROJECT_SOURCE_DIR}/cmake/manpage.cmake
                       COMMENT "Writing the man page nhdyn.1 (help2man)" VERBATIM)
    add_custom_target(nhdyn_man ALL DEPENDS ${nhdyn_man})
    install(FILES ${nhdyn_man} DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
  else()
    message(STATUS "help2man not found: no man page (apt-get install help2man, or scripts/install-deps)")
  endif()
  # What `make run` builds: the command and every file its install takes (the man page, IPOPT's
  # module), so that `cmake --install` after `make run` finds them all.
  add_custom_target(nhdyn_command)
  add_dependencies(nhdyn_command nhdyn_cli)
  foreach(part nhdyn_man nhdyn_ipopt_solver)
    if(TARGET ${part})
      add_dependencies(nhdyn_command ${part})
    endif()
  endforeach()
endif()

# --- The Python package, in the layout of the interpreter it was built for: for the prefix /usr,
# Debian's system directory (lib/python3/dist-packages); for /usr/local, Debian's local one
# (lib/python3.X/dist-packages); for any other prefix, lib/python3.X/site-packages (a venv's layout:
# `cmake --install build --prefix VENV` makes it importable there; elsewhere add it to PYTHONPATH).
# The interpreter says which directory each scheme uses; NHDYN_INSTALL_PYTHONDIR overrides.
if(TARGET nhdyn_python)
  execute_process(COMMAND ${PYTHON_EXECUTABLE} -c [=[
import sysconfig
def rel(scheme):
    if scheme not in sysconfig.get_scheme_names():
        scheme = "posix_prefix"
    return sysconfig.get_path("platlib", scheme, vars={"platbase": "@", "base": "@"})[2:]
print(rel("deb_system") + ";" + rel("posix_local") + ";" + rel("posix_prefix"))
]=] OUTPUT_VARIABLE nhdyn_python_layouts OUTPUT_STRIP_TRAILING_WHITESPACE COMMAND_ERROR_IS_FATAL ANY)
  list(GET nhdyn_python_layouts 0 nhdyn_python_usr)
  list(GET nhdyn_python_layouts 1 nhdyn_python_usr_local)
  list(GET nhdyn_python_layouts 2 nhdyn_python_prefix)
  set(NHDYN_INSTALL_PYTHONDIR "" CACHE STRING
      "Where to install the Python package, relative to the prefix (empty: the interpreter's layout for the prefix)")
  install(CODE "
    set(nhdyn_pydir \"${NHDYN_INSTALL_PYTHONDIR}\")
    if(NOT nhdyn_pydir AND CMAKE_INSTALL_PREFIX STREQUAL \"/usr\")
      set(nhdyn_pydir \"${nhdyn_python_usr}\")
    elseif(NOT nhdyn_pydir AND CMAKE_INSTALL_PREFIX STREQUAL \"/usr/local\")
      set(nhdyn_pydir \"${nhdyn_python_usr_local}\")
    elseif(NOT nhdyn_pydir)
      set(nhdyn_pydir \"${nhdyn_python_prefix}\")
    endif()
    file(INSTALL \"${NHDYN_PYTHON_DIR}/nhdyn\" DESTINATION \"\${CMAKE_INSTALL_PREFIX}/\${nhdyn_pydir}\"
         PATTERN __pycache__ EXCLUDE)
  ")
endif()

# --- Documentation and examples.
install(FILES ${PROJECT_SOURCE_DIR}/README.md ${PROJECT_SOURCE_DIR}/CHANGELOG.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/examples/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples
        PATTERN "CMakeLists.txt" EXCLUDE)
install(FILES ${PROJECT_SOURCE_DIR}/examples/find_package/CMakeLists.txt DESTINATION ${CMAKE_INSTALL_DOCDIR}/examples/find_package)
# The documentation site, if `make docs` has built it into this build directory: a build without
# Sphinx installs everything else.
install(DIRECTORY ${PROJECT_BINARY_DIR}/docs/html/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/html OPTIONAL
        PATTERN ".buildinfo" EXCLUDE)
