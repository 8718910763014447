"""Shared fixtures of the Python tests: where the sources, the examples and the nhdyn CLI are.
ctest sets NHDYN_SOURCE_DIR, NHDYN_CLI and PYTHONPATH (tests/python/CMakeLists.txt)."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

SOURCE_DIR = pathlib.Path(os.environ.get("NHDYN_SOURCE_DIR", pathlib.Path(__file__).resolve().parents[2]))
EXAMPLES = SOURCE_DIR / "examples"


@pytest.fixture
def examples():
    return EXAMPLES


@pytest.fixture
def cli():
    path = os.environ.get("NHDYN_CLI")
    if not path:
        pytest.skip("NHDYN_CLI is not set (run the tests through ctest)")

    def run(*args, check=True):
        result = subprocess.run([path, *map(str, args)], capture_output=True, text=True)
        if check and result.returncode != 0:
            raise AssertionError("nhdyn {} exited {}: {}".format(" ".join(map(str, args)), result.returncode,
                                                                result.stderr))
        return result

    return run


def read_csv(path):
    """(header, rows x columns array) of a CSV written by nhdyn, after its provenance comment lines."""
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    header = lines[0].rstrip("\n").split(",")
    return header, np.loadtxt(lines[1:], delimiter=",", ndmin=2)
