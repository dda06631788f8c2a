"""Shared fixtures of the Python module's tests. ctest sets PYTHONPATH to the build tree's package,
DRIFTLAB_EXE to the command line, DRIFTLAB_BUILD_DIR and CMAKE_COMMAND (tests/python/CMakeLists.txt)."""
import os
import pathlib
import subprocess

import numpy as np
import pytest


def _env(name):
    value = os.environ.get(name)
    if not value:
        pytest.fail(f"{name} is not set: run these tests through ctest (tests/python/CMakeLists.txt)")
    return value


@pytest.fixture
def cli(tmp_path):
    """Runs `driftlab ARGS...` in tmp_path; returns its standard output, fails the test on a non-zero exit.
    cli.fails(ARGS...) runs one that must fail and returns the completed process."""
    exe = _env("DRIFTLAB_EXE")

    def run(*args):
        done = subprocess.run([exe, *map(str, args)], cwd=tmp_path, capture_output=True, text=True)
        assert done.returncode == 0, f"driftlab {' '.join(map(str, args))}: {done.stderr}"
        return done.stdout

    def fails(*args):
        """The completed process of a run that must fail."""
        done = subprocess.run([exe, *map(str, args)], cwd=tmp_path, capture_output=True, text=True)
        assert done.returncode != 0, f"driftlab {' '.join(map(str, args))} succeeded"
        return done

    run.fails = fails
    return run


@pytest.fixture
def build_dir():
    return pathlib.Path(_env("DRIFTLAB_BUILD_DIR"))


@pytest.fixture
def cmake_command():
    return _env("CMAKE_COMMAND")


def write_record(path, x, fs, column="x", unit="rad/s"):
    """A CSV record the command line reads with `--column rate=x:rad/s`: t_s = i / fs and the samples,
    written with repr (shortest round trip), so the command line reads exactly x. fs should be a power
    of two so that the time stamps, and the sample rate derived from them, are exact."""
    t = np.arange(len(x)) / fs
    with open(path, "w") as f:
        f.write(f"t_s,{column}\n")
        f.writelines(f"{ti!r},{xi!r}\n" for ti, xi in zip(t.tolist(), np.asarray(x, float).tolist()))
    return ["--data", path, "--column", f"rate={column}:{unit}"]


def read_csv_columns(path):
    """The columns of a CSV the command line wrote, by header name, as float64 arrays."""
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=float)
    return {name: np.atleast_1d(data[name]) for name in data.dtype.names}
