"""python/examples/notebook.py, the README's notebook-style example, run as a user runs it: it must
finish and print what the library computes on the same record."""
import os
import pathlib
import subprocess
import sys

import driftlab
import numpy as np

EXAMPLE = pathlib.Path(__file__).resolve().parents[2] / "python" / "examples" / "notebook.py"


def test_the_notebook_example_runs_and_prints_the_librarys_numbers(tmp_path):
    done = subprocess.run([sys.executable, EXAMPLE, "--fs-hz", "1", "--duration-s", "7200",
                           "--plot", tmp_path / "allan.png"], capture_output=True, text=True, env=os.environ)
    assert done.returncode == 0, done.stderr
    out = done.stdout
    rate = driftlab.simulate("fmvmg", fs_hz=1.0, seed=1, duration_s=7200)["rate_rad_s"]
    assert "record: 7200 samples at 1 Hz" in out
    d = driftlab.emd(rate)
    assert f"driftlab.emd: {d.imfs.shape[0]} IMFs" in out
    first = driftlab.sample_entropy(d.imfs[0], m=2, r=0.2).value
    assert f"SampEn per IMF: {first:.3f}," in out
    n = driftlab.allan(rate, fs_hz=1.0).arw_rad_sqrt_s * driftlab.DEG_H_PER_RAD_S
    assert f"N = {n:.4g} deg/h/sqrt(Hz)" in out
    for group in ("noise", "mixed", "drift"):
        assert f"{group:5s} group: rms" in out
    try:
        import matplotlib  # noqa: F401
        assert (tmp_path / "allan.png").stat().st_size > 0
    except ImportError:
        assert "matplotlib is not installed: no plot" in out
    assert np.isfinite(first)
