"""driftlab: MEMS gyroscope / IMU temperature-drift modelling and compensation, from Python.

numpy arrays in (float64; lists and other dtypes are converted), numpy arrays out (never copied),
results as small objects whose field names carry their units, and the library's typed errors as
Python exceptions (ConfigError, DataError, UnknownPluginError, NotFittedError; all driftlab.Error).
The GIL is released while a kernel runs, so threads calling driftlab run in parallel.
Units are SI: rates in rad/s, times in s, frequencies in Hz, temperatures in degC.
See python/README.md.
"""
import inspect
import os
import pathlib

from . import _driftlab
from ._driftlab import (DEG_H_PER_RAD_S, Allan, BiasInstability, Calibration, CalibrationModel, Compensation,
                        ConfigError, DataError, Decomposition, Discrepancy, Error, NoiseTerm, NoiseTerms, NotFittedError, Pipeline,
                        PipelineRun, Record, SampleEntropy, UnknownPluginError, allan, calibrate, device_files,
                        discrepancy, load_calibration, plugin_info, plugins, read_record, simulate)

__version__ = _driftlab.__version__

# The result classes are the package's, whichever file defines them.
for _class in (Allan, BiasInstability, Calibration, CalibrationModel, Compensation, Decomposition, Discrepancy, NoiseTerm, NoiseTerms, Pipeline,
               PipelineRun, Record, SampleEntropy):
    _class.__module__ = __name__

# The package's data (device files, pipelines), beside its own files in the build tree and in an
# installed copy alike (python/CMakeLists.txt lays both out).
DATA_DIR = pathlib.Path(__file__).resolve().parent / "data"


def devices_dir():
    """The directory of device files: $DRIFTLAB_DEVICES_DIR when set (as for the command line), else
    the package's data/devices."""
    return pathlib.Path(os.environ.get("DRIFTLAB_DEVICES_DIR") or DATA_DIR / "devices")


def pipelines_dir():
    """The directory of the pipelines shipped with driftlab (models/pipelines in the source tree)."""
    return DATA_DIR / "pipelines"


def decompose(x, plugin="decomposition/emd", *, threads=1, fs_hz=None, **params):
    """Runs any decomposition plugin (built-in or loaded from $DRIFTLAB_PLUGIN_PATH) on x.

    params are the plugin's parameters by their pipeline keys (driftlab.plugin_info(plugin) lists them);
    threads: worker threads (results do not depend on it); fs_hz: sample rate of x in Hz, only for
    diagnostics in Hz. Returns a Decomposition (imfs, shape (K, N); residue; params; diagnostics)."""
    return _driftlab.decompose(plugin, x, params, threads, fs_hz)


def _decomposition_function(name, plugin):
    """driftlab.<name>(x, **params): the plugin's parameters as keyword arguments, their defaults and
    docs read from its declared table (the one the pipelines and `driftlab plugins describe` use)."""
    info = plugin_info(plugin)

    def run(x, *, threads=1, fs_hz=None, **params):
        return _driftlab.decompose(plugin, x, params, threads, fs_hz)

    keyword = inspect.Parameter.KEYWORD_ONLY
    run.__signature__ = inspect.Signature(
        [inspect.Parameter("x", inspect.Parameter.POSITIONAL_OR_KEYWORD)]
        + [inspect.Parameter(p["key"], keyword, default=p["default"]) for p in info["params"]]
        + [inspect.Parameter("threads", keyword, default=1), inspect.Parameter("fs_hz", keyword, default=None)],
        return_annotation=Decomposition)
    lines = [f"{info['summary']} ({plugin}).", "", f"Reference: {info['reference']}.", "",
             "x: 1-D samples, any unit; the IMFs and the residue are in the same unit, x = imfs.sum(0) + residue.",
             "", "Parameters (the plugin's table; unit '1' = dimensionless):"]
    for p in info["params"]:
        lines.append(f"  {p['key']} = {p['default']!r}  [{p['unit']}; {p['constraint'] or 'any'}]: {p['doc']}")
    lines += [f"  rule: {rule}" for rule in info["rules"]]
    lines += ["  threads = 1: worker threads for ensemble members (results do not depend on it)",
              "  fs_hz = None: sample rate of x in Hz, for diagnostics in Hz", "",
              "Returns a Decomposition: imfs (K, N), residue (N,), params (all values used), diagnostics.",
              "Raises ConfigError for a bad parameter (listing every problem), DataError for bad data."]
    run.__name__ = run.__qualname__ = name
    run.__doc__ = "\n".join(lines)
    return run


emd = _decomposition_function("emd", "decomposition/emd")
eemd = _decomposition_function("eemd", "decomposition/eemd")
ceemdan = _decomposition_function("ceemdan", "decomposition/ceemdan")
vmd = _decomposition_function("vmd", "decomposition/vmd")


_sample_entropy_defaults = {p["key"]: p["default"] for p in plugin_info("classifier/sample_entropy")["params"]}


def sample_entropy(x, m=_sample_entropy_defaults["m"], r=_sample_entropy_defaults["r"]):
    """Sample entropy SampEn(m, r) = -ln(A / B) of x (Richman & Moorman 2000, with PhysioNet sampen.c's
    counts: N - m templates for both lengths, Chebyshev distance < r x SD, self-matches excluded).

    x: 1-D samples, any unit. m: template length (0..10). r: tolerance as a multiple of the population
    standard deviation (divisor N) of x, > 0. The defaults are classifier/sample_entropy's.
    Exact counts in O(N log N + candidate pairs) (plugins/sample_entropy/sample_entropy.hpp).
    Returns SampleEntropy: value (inf when A or B is 0), a, b, n, m, r, tolerance (r x SD, unit of x),
    status ('finite', 'no_matches': A = 0 < B, 'undefined': B = 0)."""
    return _driftlab.sample_entropy(x, m, r)
