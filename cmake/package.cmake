# `make package` (cpack -G DEB in the build directory): a Debian package of what `cmake --install`
# installs, under /usr (the Python package in /usr/lib/python3/dist-packages). Its dependencies:
# the shared libraries the command and the Python module load, found by dpkg-shlibdeps; the
# interpreter the Python module was built for and its NumPy; what building against the library
# and the optional parts need (headers of GiNaC, SUNDIALS, Eigen, fmt, toml++; g++ for
# --evaluator compiled; gnuplot for --plot) as Recommends. docs/install.md.
set(CPACK_GENERATOR DEB)
set(CPACK_PACKAGE_NAME nhdyn)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_VENDOR "nhdyn")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "equations of motion of constrained mechanical systems (Do Sanh form)")
# The summary above is the description's first line; CPack indents these for the control file.
set(CPACK_DEBIAN_PACKAGE_DESCRIPTION "nhdyn simulates constrained mechanical systems, holonomic and nonholonomic,
with the equations of motion in the form of Do Sanh: a command line (nhdyn),
a C++ library (find_package(nhdyn), pkg-config nhdyn) and a Python package
(import nhdyn).")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_MAINTAINER "nhdyn maintainers <nhdyn@localhost>")
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
set(nhdyn_deb_depends "")
if(TARGET nhdyn_python)
  # The module is built for one interpreter's ABI (NHDYN_PYTHON_VERSION, from python/CMakeLists.txt).
  string(REGEX MATCH "^([0-9]+)\\.([0-9]+)" _ "${NHDYN_PYTHON_VERSION}")
  math(EXPR nhdyn_python_next "${CMAKE_MATCH_2} + 1")
  set(nhdyn_deb_depends "python3 (>= ${NHDYN_PYTHON_VERSION}), python3 (<< ${CMAKE_MATCH_1}.${nhdyn_python_next}), python3-numpy")
endif()
set(CPACK_DEBIAN_PACKAGE_DEPENDS "${nhdyn_deb_depends}")
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "g++, gnuplot-nox, pkg-config, cmake, libeigen3-dev, libfmt-dev, libtomlplusplus-dev, libginac-dev, libcln-dev, libsundials-dev, libsuitesparse-dev")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "python3-pandas, python3-matplotlib, python3-dask")
include(CPack)
