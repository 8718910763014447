"""examples/nhdyn.ipynb runs from top to bottom (jupyter-nbconvert --execute), so it never rots;
its own cells assert the residuals and the bicycle's weave and capsize speeds."""

import os
import shutil
import subprocess
import sys

import pytest


def test_the_example_notebook_runs(examples, tmp_path):
    if shutil.which("jupyter-nbconvert") is None and shutil.which("jupyter") is None:
        pytest.skip("jupyter-nbconvert is not installed (apt-get install jupyter-nbconvert python3-ipykernel)")
    notebook = examples / "nhdyn.ipynb"
    # The kernel runs in examples/: the package's directory must be an absolute path.
    import nhdyn
    package_dir = os.path.dirname(os.path.dirname(os.path.abspath(nhdyn.__file__)))
    env = dict(os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join(
        [package_dir] + [os.path.abspath(p) for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))
    result = subprocess.run(
        [sys.executable, "-m", "nbconvert", "--to", "notebook", "--execute", "--ExecutePreprocessor.timeout=600",
         "--ExecutePreprocessor.kernel_name=python3", "--output-dir", str(tmp_path), str(notebook)],
        capture_output=True, text=True, env=env, cwd=examples)
    assert result.returncode == 0, result.stderr[-4000:]
    assert (tmp_path / "nhdyn.ipynb").exists()
