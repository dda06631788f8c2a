"""The package itself: version, where it is imported from, its data, the error classes."""
import pathlib

import driftlab
import pytest


def test_the_version_is_the_projects():
    assert driftlab.__version__ == driftlab._driftlab.__version__
    assert driftlab.__version__.count(".") == 2


def test_the_build_trees_package_is_imported_with_its_own_copy_of_the_data(build_dir):
    package = pathlib.Path(driftlab.__file__).resolve().parent
    assert package == (build_dir / "python" / "driftlab").resolve()
    assert (driftlab.devices_dir() / "fmvmg.yaml").is_file()
    assert (driftlab.pipelines_dir() / "li2023.yaml").is_file()
    assert driftlab.devices_dir().resolve().is_relative_to(package)


def test_the_devices_directory_follows_DRIFTLAB_DEVICES_DIR_as_the_command_line_does(monkeypatch, tmp_path):
    monkeypatch.setenv("DRIFTLAB_DEVICES_DIR", str(tmp_path))
    assert driftlab.devices_dir() == tmp_path


def test_the_error_classes_mirror_the_libraries():
    assert issubclass(driftlab.ConfigError, driftlab.Error)
    assert issubclass(driftlab.ConfigError, ValueError)
    assert issubclass(driftlab.DataError, driftlab.Error)
    assert issubclass(driftlab.DataError, ValueError)
    assert issubclass(driftlab.UnknownPluginError, driftlab.ConfigError)
    assert issubclass(driftlab.NotFittedError, driftlab.Error)
    assert issubclass(driftlab.Error, RuntimeError)
    assert driftlab.ConfigError.__module__ == "driftlab"


def test_an_unknown_plugin_raises_UnknownPluginError_with_the_libraries_message():
    with pytest.raises(driftlab.UnknownPluginError, match="decomposition/emd") as info:
        driftlab.plugin_info("decomposition/nonesuch")
    assert info.value.problems[0]["field"] == "decomposition/nonesuch"


def test_the_registry_holds_the_built_in_plugins_with_their_tables():
    assert driftlab.plugins("decomposition") == ["decomposition/ceemdan", "decomposition/eemd", "decomposition/emd",
                                                 "decomposition/vmd"]
    assert "classifier/sample_entropy" in driftlab.plugins()
    info = driftlab.plugin_info("decomposition/vmd")
    assert info["origin"] == "built-in" and info["reference"]
    modes = next(p for p in info["params"] if p["key"] == "modes")
    assert (modes["type"], modes["unit"], modes["constraint"]) == ("integer", "1", "[1, 64]")
