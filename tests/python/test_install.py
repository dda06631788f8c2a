"""`cmake --install` into a fresh prefix gives a package that imports from there, from any working
directory, and reads its data (devices, pipelines) from its own location, not the source or build tree;
it reads MRPT rawlogs and ROS 1 bags through the reader modules installed beside it."""
import json
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest


def install(build_dir, cmake_command, tmp_path):
    """Installs the package into a fresh prefix; returns the directory that holds it (for PYTHONPATH)."""
    prefix = tmp_path / "prefix"
    subprocess.run([cmake_command, "--install", str(build_dir), "--prefix", str(prefix), "--component", "python"],
                   check=True, capture_output=True)
    packages = [p.parent.parent for p in prefix.rglob("driftlab/__init__.py")]
    assert len(packages) == 1
    return packages[0]


def run_installed(package_dir, probe, tmp_path):
    """Runs the Python code `probe` (which prints JSON) with only the installed package on the path, in
    a directory outside the source and build trees; returns what it printed."""
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir(exist_ok=True)
    env = {k: v for k, v in os.environ.items() if not k.startswith("DRIFTLAB_")}
    env["PYTHONPATH"] = str(package_dir)
    done = subprocess.run([sys.executable, "-c", probe], cwd=elsewhere, env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def test_the_installed_package_imports_and_finds_its_data_from_its_install_location(build_dir, cmake_command,
                                                                                   tmp_path):
    package_dir = install(build_dir, cmake_command, tmp_path)
    probe = ("import driftlab, json; print(json.dumps({'file': driftlab.__file__, 'version': driftlab.__version__, "
             "'devices': [str(p) for p in driftlab.device_files()], "
             "'simulated': len(driftlab.simulate('fmvmg', fs_hz=1.0, duration_s=10)['rate_rad_s']), "
             "'pipeline_steps': len(driftlab.Pipeline.from_yaml('li2023').steps)}))")
    found = run_installed(package_dir, probe, tmp_path)
    installed = package_dir / "driftlab"
    assert pathlib.Path(found["file"]).parent == installed
    assert found["version"] == subprocess.run([sys.executable, "-c", "import driftlab; print(driftlab.__version__)"],
                                              capture_output=True, text=True, check=True).stdout.strip()
    devices = [pathlib.Path(p) for p in found["devices"]]
    assert "fmvmg.yaml" in [p.name for p in devices]
    assert all(p.is_relative_to(installed) for p in devices)
    assert found["simulated"] == 10  # the device found by name in the installed data
    assert found["pipeline_steps"] > 0  # the shipped pipeline found by name


def test_the_installed_package_reads_an_mrpt_rawlog_as_the_command_line_wrote_it(build_dir, cmake_command, cli,
                                                                                tmp_path):
    if not any(build_dir.rglob("libdriftlab_rawlog.so")):
        pytest.skip("built without MRPT (libmrpt-obs-dev): rawlogs are not read")
    t = np.arange(50) / 10.0
    rate = 0.01 * np.sin(t)
    temperature = 20.0 + 0.1 * t
    np.savetxt(tmp_path / "in.csv", np.column_stack([t, rate, temperature]), delimiter=",", header="t_s,rate_rps,temp_c",
               comments="", fmt="%.17g")
    cli("mrpt", "export", "in.csv", "--out", "in.rawlog")
    package_dir = install(build_dir, cmake_command, tmp_path)
    assert (package_dir / "driftlab" / "libdriftlab_rawlog.so").is_file()
    probe = ("import driftlab, json; r = driftlab.read_record(%r); "
             "print(json.dumps({'t': r.time_s.tolist(), **{k: v.tolist() for k, v in r.channels.items()}}))"
             % str(tmp_path / "in.rawlog"))
    found = run_installed(package_dir, probe, tmp_path)
    assert set(found) == {"t", "gyro_z", "temperature"}
    assert np.array_equal(found["t"], t)  # 0.1-s steps survive MRPT's 100-ns ticks exactly (rawlog_io.hpp)
    assert np.array_equal(found["gyro_z"], rate)
    assert np.array_equal(found["temperature"], temperature)


def test_the_installed_package_reads_a_ros1_bag_as_the_build_tree_does(build_dir, cmake_command, tmp_path):
    if not any(build_dir.rglob("libdriftlab_ros1bag.so")):
        pytest.skip("built without librosbag-storage-dev: ROS 1 bags are not read")
    bag = pathlib.Path(__file__).parent.parent / "data" / "logs" / "ros1-robot-localization" / "test2.bag"
    import driftlab  # the build tree's package (PYTHONPATH), whose reader module sits beside its framework
    expected = driftlab.read_record(bag)
    package_dir = install(build_dir, cmake_command, tmp_path)
    assert (package_dir / "driftlab" / "libdriftlab_ros1bag.so").is_file()
    probe = ("import driftlab, json; r = driftlab.read_record(%r); "
             "print(json.dumps({'t': r.time_s.tolist(), **{k: v.tolist() for k, v in r.channels.items()}}))" % str(bag))
    found = run_installed(package_dir, probe, tmp_path)
    assert set(found) == {"t", *expected.channels}
    assert np.array_equal(found["t"], expected.time_s)
    for role, values in expected.channels.items():
        assert np.array_equal(found[role], values), role
