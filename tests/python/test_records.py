"""read_record, simulate, device_files: the library's readers and simulator against the command
line's output on the same files (`driftlab log export`, `driftlab simulate`)."""
import os
import pathlib

import driftlab
import numpy as np
import pytest
from conftest import read_csv_columns

DEG = np.pi / 180  # rad per degree, as framework/units.hpp deg/s scale
SHARED = pathlib.Path(os.environ.get("DRIFTLAB_SHARED_DATA", "/nonexistent"))


def test_a_csv_record_is_read_in_si_units_as_read_only_views(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("t_s,rate_dps,temp_c\n0,1.5,20\n0.5,-3,20.5\n1,0.25,21\n")
    r = driftlab.read_record(path)
    assert len(r) == 3 and r.sample_rate_hz == 2.0
    assert np.array_equal(r.time_s, [0, 0.5, 1])
    assert np.array_equal(r.channels["rate"], np.array([1.5, -3, 0.25]) * (np.pi / 180))  # deg/s -> rad/s
    assert np.array_equal(r.channels["temperature"], [20, 20.5, 21])
    assert r.units == {"rate": "rad/s", "temperature": "degC"}
    assert r.sources == {"rate": "rate_dps", "temperature": "temp_c"}
    rate = r.channels["rate"]
    assert not rate.flags.owndata and not rate.flags.writeable
    with pytest.raises(ValueError):
        rate[0] = 1.0


def test_column_mappings_and_a_sample_rate_for_files_without_time(tmp_path):
    path = tmp_path / "raw.csv"
    path.write_text("gz,T\n100,20\n-100,21\n")
    r = driftlab.read_record(str(path), columns=["rate=gz:mdps", "temperature=T:degC"], fs_hz=4.0)
    assert np.array_equal(r.time_s, [0, 0.25])
    assert r.channels["rate"] == pytest.approx(np.radians([0.1, -0.1]), rel=1e-15)


def test_reading_errors_are_DataErrors_naming_file_line_and_column(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("t_s,rate_dps\n0,1\n1,oops\n")
    with pytest.raises(driftlab.DataError, match="oops") as info:
        driftlab.read_record(path)
    assert (info.value.file, info.value.line, info.value.field) == (str(path), 3, "rate_dps")
    with pytest.raises(driftlab.DataError):
        driftlab.read_record(tmp_path / "missing.csv")
    with pytest.raises(driftlab.ConfigError):
        driftlab.read_record(path, columns=["rate=x:furlongs"])


@pytest.mark.skipif(not (SHARED / "logs/px4-pyulog/sample.ulg").exists(), reason="no shared data (../shared/data)")
def test_a_px4_ulog_is_read_as_driftlab_log_export_writes_it(cli, tmp_path):
    log = SHARED / "logs/px4-pyulog/sample.ulg"
    cli("log", "export", log, "--out", "imu.csv")
    expected = read_csv_columns(tmp_path / "imu.csv")
    r = driftlab.read_record(log, max_gap_factor=0)  # a flight log has dropouts; export allows them
    assert np.array_equal(r.time_s, expected["t_s"])
    assert set(r.channels) == {f"{s}_{a}" for s in ("gyro", "accel") for a in "xyz"}
    for role, values in r.channels.items():
        column = next(c for c in expected if c.startswith(role + "_"))  # gyro_x_rad_s, accel_x_m_s2
        assert np.array_equal(values, expected[column]), role


def test_the_devices_are_the_packages_and_simulate_finds_them_by_name():
    names = [p.stem for p in driftlab.device_files()]
    assert {"fmvmg", "lsm6dsm", "imu3"} <= set(names)
    assert all(p.parent == driftlab.devices_dir() for p in driftlab.device_files())
    by_name = driftlab.simulate("fmvmg", fs_hz=1.0, duration_s=60)
    by_path = driftlab.simulate(driftlab.devices_dir() / "fmvmg.yaml", fs_hz=1.0, duration_s=60)
    assert np.array_equal(by_name["rate_rad_s"], by_path["rate_rad_s"])


def test_simulate_equals_driftlab_simulate_with_the_same_seed(cli, tmp_path):
    cli("simulate", "--device", "fmvmg", "--fs", 2, "--duration", 1800, "--seed", 11, "--out", "sim.csv")
    theirs = driftlab.read_record(tmp_path / "sim.csv")
    ours = driftlab.simulate("fmvmg", fs_hz=2.0, duration_s=1800, seed=11)
    assert np.array_equal(ours["time_s"], theirs.time_s)
    # The CSV holds deg/s snapped to the device's resolution for display: equal to that resolution.
    resolution_rad_s = np.radians(1e-6)
    assert np.abs(ours["rate_rad_s"] - theirs.channels["rate"]).max() <= resolution_rad_s
    assert ours["die_temp_c"] == pytest.approx(theirs.channels["die_temperature"], abs=1e-12)
    assert ours["temp_c"] == pytest.approx(theirs.channels["temperature"], abs=1e-9)  # snapped to 0.01 degC


def si_name(written):
    """The Python name of a column `driftlab simulate` writes: gyro deg/s -> rad/s, t_s -> time_s."""
    return "time_s" if written == "t_s" else written.replace("_dps", "_rad_s")


def test_a_whole_imu_equals_driftlab_simulate_column_by_column(cli, tmp_path):
    cli("simulate", "--device", "imu3", "--fs", 8, "--duration", 900, "--seed", 3, "--out", "imu.csv")
    written = read_csv_columns(tmp_path / "imu.csv")
    ours = driftlab.simulate("imu3", fs_hz=8.0, duration_s=900, seed=3)
    assert list(ours) == [si_name(name) for name in written]  # every column, in the CSV's order
    for name, values in written.items():
        mine = ours[si_name(name)]
        assert mine.dtype == np.float64 and mine.shape == (8 * 900,)
        # The same simulator and the same columns: the CSV's text is exactly our SI value in its unit.
        assert np.array_equal(mine / DEG if name.endswith("_dps") else mine, values), name
    # devices/imu3.yaml: 2 instances x (gyro + accelerometer) x 3 axes, each with its temperature.
    measured = [n for n in ours if n.startswith(("gyro", "accel"))]
    assert measured == [f"{s}{i}_{a}_{u}" for i in ("", "1") for s, u in (("gyro", "rad_s"), ("accel", "mps2"))
                        for a in "xyz"]
    assert {"temp_c", "temp1_c"} <= set(ours)
    # Independent physics: at rest on a level table (z up) the accelerometer's input is +g on z, 0 on x.
    g = 9.80665
    assert np.array_equal(ours["true_accel_z_mps2"], np.full(len(ours["time_s"]), g))
    assert np.array_equal(ours["true_accel_x_mps2"], np.zeros(len(ours["time_s"])))
    assert np.array_equal(np.diff(ours["time_s"]) * 8.0, np.ones(8 * 900 - 1))


def test_the_same_seed_gives_the_same_record_and_another_seed_another():
    a = driftlab.simulate("fmvmg", fs_hz=1.0, duration_s=120, seed=3)
    b = driftlab.simulate("fmvmg", fs_hz=1.0, duration_s=120, seed=3)
    c = driftlab.simulate("fmvmg", fs_hz=1.0, duration_s=120, seed=4)
    assert np.array_equal(a["rate_rad_s"], b["rate_rad_s"])
    assert not np.array_equal(a["rate_rad_s"], c["rate_rad_s"])
    assert np.array_equal(a["systematic_rate_rad_s"], c["systematic_rate_rad_s"])


def test_simulation_errors():
    with pytest.raises(driftlab.ConfigError, match="nonesuch"):
        driftlab.simulate("nonesuch")
    with pytest.raises(driftlab.ConfigError, match="MB needed"):
        driftlab.simulate("fmvmg", fs_hz=1e9, duration_s=1e9)
