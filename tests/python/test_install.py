"""`cmake --install` into a fresh prefix gives a package that imports from there, from any working
directory, and reads its data (devices, pipelines) from its own location, not the source or build tree."""
import json
import os
import pathlib
import subprocess
import sys


def test_the_installed_package_imports_and_finds_its_data_from_its_install_location(build_dir, cmake_command,
                                                                                   tmp_path):
    prefix = tmp_path / "prefix"
    subprocess.run([cmake_command, "--install", str(build_dir), "--prefix", str(prefix), "--component", "python"],
                   check=True, capture_output=True)
    packages = [p.parent.parent for p in prefix.rglob("driftlab/__init__.py")]
    assert len(packages) == 1
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    env = {k: v for k, v in os.environ.items() if not k.startswith("DRIFTLAB_")}
    env["PYTHONPATH"] = str(packages[0])
    probe = ("import driftlab, json; print(json.dumps({'file': driftlab.__file__, 'version': driftlab.__version__, "
             "'devices': [str(p) for p in driftlab.device_files()], "
             "'simulated': len(driftlab.simulate('fmvmg', fs_hz=1.0, duration_s=10)['rate_rad_s']), "
             "'pipeline_steps': len(driftlab.Pipeline.from_yaml('li2023').steps)}))")
    done = subprocess.run([sys.executable, "-c", probe], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    found = json.loads(done.stdout)
    installed = packages[0] / "driftlab"
    assert pathlib.Path(found["file"]).parent == installed
    assert found["version"] == subprocess.run([sys.executable, "-c", "import driftlab; print(driftlab.__version__)"],
                                              capture_output=True, text=True, check=True).stdout.strip()
    devices = [pathlib.Path(p) for p in found["devices"]]
    assert "fmvmg.yaml" in [p.name for p in devices]
    assert all(p.is_relative_to(installed) for p in devices)
    assert found["simulated"] == 10  # the device found by name in the installed data
    assert found["pipeline_steps"] > 0  # the shipped pipeline found by name
