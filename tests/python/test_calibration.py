"""calibrate, load_calibration, CalibrationModel.compensate / to_json / export against `driftlab
calibrate`, `compensate` and `export` on the same records (same code: the same numbers): a simulated
single-axis oven run, a simulated whole IMU (devices/imu3.yaml) with channel selection and the
same-device rule, and a real IMU's thermal cycle; compensation also against the simulator's truth."""
import json
import os
import pathlib

import driftlab
import numpy as np
import pytest
from conftest import read_csv_columns

DEG = np.pi / 180  # rad per degree, as framework/units.hpp's deg/s scale


@pytest.fixture
def oven(cli, tmp_path):
    """A model fitted on one simulated oven run (seed 1) and a second run (seed 2) to apply it to."""
    cli("simulate", "--device", "fmvmg", "--fs", 1, "--seed", 1, "--out", "fit.csv")
    cli("simulate", "--device", "fmvmg", "--fs", 1, "--seed", 2, "--out", "apply.csv")
    cli("calibrate", "--data", "fit.csv", "--model", "physical", "--out", "model.json")
    return tmp_path


def test_compensation_equals_driftlab_compensate(cli, oven):
    cli("compensate", "--model", "model.json", "--data", "apply.csv", "--out", "compensated.csv")
    expected = read_csv_columns(oven / "compensated.csv")
    model = driftlab.load_calibration(oven / "model.json")
    record = driftlab.read_record(oven / "apply.csv")
    c = model.compensate(record.time_s, record.channels["rate"], record.channels["temperature"])
    # The command line writes the column back in its own unit, deg/s: value / (pi / 180).
    assert np.array_equal(c.rate_rad_s / DEG, expected["rate_dps"])
    assert np.array_equal(c.bias_rad_s / DEG, expected["bias_rate_dps"])
    assert np.array_equal(c.extrapolated, expected["extrapolated"])
    assert not c.rate_rad_s.flags.owndata  # the compensator's own storage


def test_compensation_removes_the_temperature_drift(oven):
    model = driftlab.load_calibration(oven / "model.json")
    record = driftlab.read_record(oven / "apply.csv")
    truth = driftlab.simulate("fmvmg", fs_hz=1.0, seed=2)
    c = model.compensate(record.time_s, record.channels["rate"], record.channels["temperature"])
    drift_before = np.std(truth["systematic_rate_rad_s"])
    residual = c.rate_rad_s - truth["true_rate_rad_s"] - (record.channels["rate"] - truth["systematic_rate_rad_s"])
    assert np.std(residual) < 0.1 * drift_before  # what is left of the systematic rate after compensation


def test_the_model_reads_back_as_written_and_exports_as_driftlab_export(cli, oven):
    model = driftlab.load_calibration(oven / "model.json")
    assert json.loads(model.to_json()) == json.loads((oven / "model.json").read_text())
    (channel,) = model.channels
    assert (channel["role"], channel["column"], channel["unit"]) == ("rate", "rate_dps", "rad/s")
    assert channel["kind"] == json.loads((oven / "model.json").read_text())["channels"][0]["model"]["kind"]
    for fmt, out in [("px4", "tc.params"), ("ardupilot", "tcal.params"), ("c-header", "cal.h")]:
        cli("export", "--model", "model.json", "--format", fmt, "--out", out)
        text, notes = model.export(fmt)
        assert text == (oven / out).read_text(), fmt
        assert all(isinstance(n, str) for n in notes)


def test_errors(oven, tmp_path):
    with pytest.raises(driftlab.ConfigError, match="cannot open|does not exist|No such"):
        driftlab.load_calibration(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text('{"format": "driftlab-calibration/9"}')
    with pytest.raises(driftlab.ConfigError, match="format"):
        driftlab.load_calibration(bad)
    model = driftlab.load_calibration(oven / "model.json")
    with pytest.raises(driftlab.ConfigError, match="no channel 'gyro_x'"):
        model.compensate([0.0, 1.0], [0.0, 0.0], [20.0, 20.0], channel="gyro_x")
    with pytest.raises(driftlab.DataError, match="differ in length"):
        model.compensate([0.0, 1.0], [0.0], [20.0, 20.0])
    with pytest.raises(driftlab.DataError):
        model.compensate([1.0, 0.0], [0.0, 0.0], [20.0, 20.0])  # time going backwards
    with pytest.raises(driftlab.ConfigError, match="expected c-header"):
        model.export("xml")


def test_calibrate_fits_what_driftlab_calibrate_fits(oven):
    fitted = driftlab.calibrate(driftlab.read_record(oven / "fit.csv"), model="physical")
    ours = json.loads(fitted.model.to_json())["channels"][0]["model"]
    theirs = json.loads((oven / "model.json").read_text())["channels"][0]["model"]
    assert ours["kind"] == theirs["kind"]
    assert ours["bias"] == theirs["bias"]
    assert [f["code"] for f in fitted.gate] == []  # the simulated oven run passes the quality gate


def test_calibrate_enforces_the_quality_gate_and_checks_its_arguments():
    t = np.arange(0, 3600.0, 1.0)
    flat = {"time": t, "rate": np.zeros_like(t), "temperature": np.full_like(t, 25.0)}
    with pytest.raises(driftlab.DataError, match="quality gate"):
        driftlab.calibrate(flat)  # no temperature span: nothing to fit
    with pytest.raises(driftlab.ConfigError, match="poly, physical or rbf"):
        driftlab.calibrate(flat, model="cubic")
    with pytest.raises(driftlab.DataError, match="no gyro or accelerometer column"):
        driftlab.calibrate({"time": t, "temperature": t})
    with pytest.raises(driftlab.ConfigError, match="min_order"):
        driftlab.calibrate(flat, min_order=4, max_order=2)


@pytest.fixture
def imu_oven(cli, tmp_path):
    """Two simulated oven runs of the whole IMU devices/imu3.yaml (2 instances x gyro + accel x 3 axes)."""
    cli("simulate", "--device", "imu3", "--fs", 1, "--seed", 1, "--out", "imu_fit.csv")
    cli("simulate", "--device", "imu3", "--fs", 1, "--seed", 2, "--out", "imu_apply.csv")
    return tmp_path


def column_unit_scale(column):
    """Internal units per written unit of a column `driftlab compensate` writes (deg/s or SI)."""
    return DEG if column.endswith("_dps") else 1.0


def test_a_whole_imu_is_calibrated_and_compensated_as_driftlab_calibrate_and_compensate_do(cli, imu_oven):
    fit_csv, apply_csv = imu_oven / "imu_fit.csv", imu_oven / "imu_apply.csv"
    cli("--threads", 2, "calibrate", "--data", fit_csv, "--out", "imu_model.json")
    theirs = json.loads((imu_oven / "imu_model.json").read_text())
    fitted = driftlab.calibrate(driftlab.read_record(fit_csv), threads=2)
    assert json.loads(fitted.model.to_json()) == theirs  # every channel, every number
    roles = [c["role"] for c in fitted.model.channels]
    assert roles == [f"{s}{i}_{a}" for s in ("gyro", "accel") for i in ("", "1") for a in "xyz"]

    cli("compensate", "--model", "imu_model.json", "--data", apply_csv, "--out", "imu_compensated.csv")
    expected = read_csv_columns(imu_oven / "imu_compensated.csv")
    record = driftlab.read_record(apply_csv)
    compensated = fitted.model.compensate(record)
    for channel in fitted.model.channels:
        role, column = channel["role"], channel["column"]
        scale = column_unit_scale(column)
        assert np.array_equal(compensated[role] / scale, expected[column]), role
        assert np.array_equal(compensated["bias_" + role] / scale, expected["bias_" + column]), role
    assert np.array_equal(compensated["extrapolated"], expected["extrapolated"])
    # Independent truth: the simulator's systematic rate. What is left of the gyro drift is small.
    for axis in "xyz":
        drift = record.channels["systematic_gyro_" + axis] - record.channels["true_gyro_" + axis]
        noise = record.channels["gyro_" + axis] - record.channels["systematic_gyro_" + axis]
        left = compensated["gyro_" + axis] - record.channels["true_gyro_" + axis] - noise
        assert np.std(left) < 0.1 * np.std(drift), axis


def test_channel_selection_and_the_same_device_rule_are_the_commands(cli, imu_oven):
    fit_csv = imu_oven / "imu_fit.csv"
    cli("calibrate", "--data", fit_csv, "--channels", "gyro_x,accel1_z", "--model", "poly", "--out", "two.json")
    record = driftlab.read_record(fit_csv)
    fitted = driftlab.calibrate(record, model="poly", channels="gyro_x,accel1_z")
    assert json.loads(fitted.model.to_json()) == json.loads((imu_oven / "two.json").read_text())
    assert [c["role"] for c in fitted.model.channels] == ["gyro_x", "accel1_z"]
    as_list = driftlab.calibrate(record, model="poly", channels=["gyro_x", "accel1_z"])
    assert as_list.model.to_json() == fitted.model.to_json()
    gyros = driftlab.calibrate(record, model="poly", channels="gyro1")
    assert [c["role"] for c in gyros.model.channels] == ["gyro1_x", "gyro1_y", "gyro1_z"]
    # Another unit's run (its bias 0.5 deg/s away) is refused as one device unless same_device=True.
    other = {"time": record.time_s, "gyro_x": record.channels["gyro_x"] + 0.5 * DEG,
             "temperature": record.channels["temperature"]}
    mine = {"time": record.time_s, "gyro_x": record.channels["gyro_x"], "temperature": record.channels["temperature"]}
    with pytest.raises(driftlab.ConfigError, match="look like two devices.*same_device=True"):
        driftlab.calibrate([mine, other], model="poly")
    assert len(driftlab.calibrate([mine, other], model="poly", same_device=True).model.channels) == 1
    with pytest.raises(driftlab.ConfigError, match="channels"):
        driftlab.calibrate(record, channels="wheel")
    with pytest.raises(driftlab.ConfigError, match="gyro1_x"):
        gyros.model.compensate(mine)  # the model's channels are not in this record


THERMAL_CYCLE = (pathlib.Path(os.environ.get("DRIFTLAB_SHARED_DATA", "/nonexistent"))
                 / "real/tofupilot-imu-thermal-cycle/data.csv")


@pytest.mark.skipif(not THERMAL_CYCLE.exists(), reason="no shared data (../shared/data)")
def test_a_real_imus_thermal_cycle_is_calibrated_and_compensated_as_the_commands_do(cli, tmp_path):
    """A real IMU in a chamber (3 gyro + 3 accel axes, -17.6 .. 74 degC, three legs; PROVENANCE.md)."""
    cli("calibrate", "--data", THERMAL_CYCLE, "--out", "real.json")
    cli("compensate", "--model", "real.json", "--data", THERMAL_CYCLE, "--out", "real_compensated.csv")
    record = driftlab.read_record(THERMAL_CYCLE)
    fitted = driftlab.calibrate(record)
    assert json.loads(fitted.model.to_json()) == json.loads((tmp_path / "real.json").read_text())
    expected = read_csv_columns(tmp_path / "real_compensated.csv")
    compensated = fitted.model.compensate(record)
    for channel in fitted.model.channels:  # gyro_x_rps .. acc_z_mps2: written in SI, as read
        assert np.array_equal(compensated[channel["role"]], expected[channel["column"]]), channel["role"]
        assert np.array_equal(compensated["bias_" + channel["role"]], expected["bias_" + channel["column"]])
