"""driftlab: MEMS gyroscope / IMU temperature-drift modelling and compensation, from Python.

numpy arrays in (float64; lists and other dtypes are converted), numpy arrays out (never copied),
results as small objects whose field names carry their units, and the library's typed errors as
Python exceptions (ConfigError, DataError, UnknownPluginError, NotFittedError; all driftlab.Error).
The GIL is released while a kernel runs, so threads calling driftlab run in parallel.
Units are SI: rates in rad/s, times in s, frequencies in Hz, temperatures in degC.
See python/README.md.
"""
import os
import pathlib

from . import _driftlab
from ._driftlab import (ConfigError, DataError, Error, NotFittedError, UnknownPluginError, plugin_params,
                        plugins)

__version__ = _driftlab.__version__

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
