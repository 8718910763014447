"""nhdyn.__version__ is the CLI's version (one number, from project(VERSION) in CMakeLists.txt), and
an interpreter other than the one the package was built for gets an ImportError naming both."""

import os
import pathlib
import re
import shutil
import subprocess
import sys

import nhdyn
from conftest import SOURCE_DIR


def test_version_is_the_projects_and_the_clis(cli):
    project = re.search(r"project\(nhdyn VERSION (\d+\.\d+\.\d+)", (SOURCE_DIR / "CMakeLists.txt").read_text())
    assert nhdyn.__version__ == project.group(1)
    assert cli("--version").stdout == "nhdyn {} (commit {})\n".format(nhdyn.__version__, nhdyn._nhdyn.__git_commit__)


def _import_copy(tmp_path, edit, python=sys.executable):
    """Imports a copy of the package whose _build_info.py was changed by `edit`."""
    package = pathlib.Path(nhdyn.__file__).parent
    copy = tmp_path / "nhdyn"
    shutil.copytree(package, copy, ignore=shutil.ignore_patterns("__pycache__"))
    info = copy / "_build_info.py"
    info.write_text(edit(info.read_text()))
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    return subprocess.run([python, "-c", "import nhdyn"], capture_output=True, text=True, env=env, cwd=tmp_path)


def test_another_abi_is_refused_with_both_interpreters_named(tmp_path):
    run = _import_copy(tmp_path, lambda text: re.sub(r'extension_suffix = ".*"',
                                                     'extension_suffix = ".cpython-399-x86_64-linux-gnu.so"', text))
    assert run.returncode != 0
    last = run.stderr.strip().splitlines()[-1]
    assert last.startswith("ImportError: nhdyn {} was built for Python".format(nhdyn.__version__)), run.stderr
    assert ".cpython-399-x86_64-linux-gnu.so" in last and "imported by Python {}.{}".format(*sys.version_info[:2]) in last
    assert "cannot be loaded by this interpreter" in last


def test_a_missing_piece_under_another_installation_names_the_built_for_one(tmp_path):
    # The same ABI, another interpreter (as a pyenv python3 first on PATH): the failure to load
    # (here a module made unloadable) is reported with the interpreter the package was built for.
    def edit(text):
        return re.sub(r'python_executable = ".*"', 'python_executable = "/opt/elsewhere/bin/python3"', text)

    run = _import_copy(tmp_path, edit)
    assert run.returncode == 0, run.stderr  # it loads: only a failure gets the message
    for so in (tmp_path / "nhdyn").glob("_nhdyn*.so"):
        so.write_bytes(b"not a shared object")
    env = dict(os.environ, PYTHONPATH=str(tmp_path))
    run = subprocess.run([sys.executable, "-c", "import nhdyn"], capture_output=True, text=True, env=env, cwd=tmp_path)
    last = run.stderr.strip().splitlines()[-1]
    assert "was built for Python" in last and "/opt/elsewhere/bin/python3" in last, run.stderr
