"""Builds the Python package nhdyn with CMake, for `pip install .` and `python3 -m build --wheel`
(pyproject.toml; docs/install.md, "pip").

The pure-Python files come from python/nhdyn/; the compiled module nhdyn._nhdyn, IPOPT's module
libnhdyn_ipopt.so that Model.optimize loads, and the file that says which interpreter it was built
for (_build_info.py) from a CMake build of the target
nhdyn_python, configured with -DPYTHON_EXECUTABLE set to the interpreter running this build, so
the wheel is for that interpreter (its tag says which, as does the build's output).

The CMake build directory is build-pip/python3.X/ in the checkout (kept between builds: a rebuild
recompiles only what changed). NHDYN_PIP_BUILD_DIR=DIR uses another one; when DIR is an already
configured nhdyn build (for example build/, which make test built), only its nhdyn_python target is
built, without reconfiguring it: it must have been configured for this same interpreter.
"""

import os
import pathlib
import re
import shutil
import subprocess
import sys
import sysconfig

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = pathlib.Path(__file__).resolve().parent


def project_version():
    text = (ROOT / "CMakeLists.txt").read_text()
    return re.search(r"project\(nhdyn VERSION ([0-9]+\.[0-9]+\.[0-9]+)", text).group(1)


def cached(build_dir, name):
    """A variable of an existing CMakeCache.txt, or None."""
    cache = build_dir / "CMakeCache.txt"
    for line in cache.read_text().splitlines():
        if line.startswith(name + ":"):
            return line.split("=", 1)[1]
    return None


def cmake_build_dir():
    """Where the CMake build goes (see the top of this file)."""
    python = "python{}.{}".format(*sys.version_info[:2])
    return pathlib.Path(os.environ.get("NHDYN_PIP_BUILD_DIR") or ROOT / "build-pip" / python).resolve()


class CMakeBuild(build_ext):
    """Builds nhdyn._nhdyn with CMake instead of compiling sources itself."""

    def build_extension(self, ext):
        python = "{}.{}".format(*sys.version_info[:2])
        build_dir = cmake_build_dir()
        print("nhdyn: building the Python package for Python {} ({}, extension suffix {}) in {}".format(
            python, sys.executable, sysconfig.get_config_var("EXT_SUFFIX"), build_dir), flush=True)
        if (build_dir / "CMakeCache.txt").exists() and os.environ.get("NHDYN_PIP_BUILD_DIR"):
            configured_for = cached(build_dir, "PYTHON_EXECUTABLE")
            if configured_for is None or os.path.realpath(configured_for) != os.path.realpath(sys.executable):
                raise RuntimeError(
                    "NHDYN_PIP_BUILD_DIR={} was configured for Python {} but this build runs {}: use a build "
                    "directory configured with -DPYTHON_EXECUTABLE={}, or leave NHDYN_PIP_BUILD_DIR unset".format(
                        build_dir, configured_for, sys.executable, sys.executable))
            if (cached(build_dir, "NHDYN_BUILD_PYTHON") or "").upper() not in ("ON", "1", "TRUE", "YES"):
                raise RuntimeError(
                    "NHDYN_PIP_BUILD_DIR={} was configured without the Python package (NHDYN_BUILD_PYTHON is not ON: "
                    "`make run` configures it so): run `make python` there first, or leave NHDYN_PIP_BUILD_DIR "
                    "unset".format(build_dir))
        else:
            generator = ["-G", "Ninja"] if shutil.which("ninja") else []
            subprocess.run(["cmake", "-S", str(ROOT), "-B", str(build_dir), *generator, "-DCMAKE_BUILD_TYPE=Release",
                            "-DPYTHON_EXECUTABLE=" + sys.executable, "-DNHDYN_BUILD_PYTHON=ON",
                            "-DNHDYN_BUILD_TESTS=OFF", "-DNHDYN_BUILD_BENCH=OFF", "-DNHDYN_BUILD_CLI=OFF"],
                           check=True)
        jobs = os.environ.get("NHDYN_PIP_JOBS", str(os.cpu_count() or 1))
        subprocess.run(["cmake", "--build", str(build_dir), "--target", "nhdyn_python", "-j", jobs], check=True)

        package = build_dir / "python" / "nhdyn"
        built = package / ("_nhdyn" + sysconfig.get_config_var("EXT_SUFFIX"))
        if not built.exists():
            raise RuntimeError("the CMake build made no {} (was it configured for another interpreter?)".format(built))
        target = pathlib.Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(built, target)
        shutil.copy2(package / "_build_info.py", target.parent / "_build_info.py")
        # IPOPT's module, loaded from beside the compiled one by Model.optimize (a build without IPOPT has none).
        if (package / "libnhdyn_ipopt.so").exists():
            shutil.copy2(package / "libnhdyn_ipopt.so", target.parent / "libnhdyn_ipopt.so")


cmake_build_dir().mkdir(parents=True, exist_ok=True)  # egg_info wants its base to exist
setup(
    version=project_version(),
    packages=["nhdyn"],
    package_dir={"nhdyn": "python/nhdyn"},
    package_data={"nhdyn": ["py.typed", "*.pyi"]},  # type stubs of the compiled module (PEP 561)
    ext_modules=[Extension("nhdyn._nhdyn", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # setuptools' own scratch space inside the CMake build directory: not in the checkout's build/
    # (unless that is the CMake build), and apart for two builds at once.
    options={"build": {"build_base": str(cmake_build_dir() / "setuptools")},
             "egg_info": {"egg_base": str(cmake_build_dir())}},
    zip_safe=False,
)
