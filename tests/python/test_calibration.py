"""load_calibration, CalibrationModel.compensate / to_json / export: a model fitted by
`driftlab calibrate` on a simulated oven run, applied here and by `driftlab compensate` to another
run of the same device (same code: the same numbers)."""
import json

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
    assert np.array_equal(c.extrapolated, expected["extrapolated"] == 1)
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
    record = driftlab.read_record(oven / "fit.csv")
    run = {"time_s": record.time_s, "rate_rad_s": record.channels["rate"], "temp_c": record.channels["temperature"],
           "name": "fit.csv"}
    if "true_rate" in record.channels:
        run["true_rate_rad_s"] = record.channels["true_rate"]
    fitted = driftlab.calibrate([run], model="physical")
    ours = json.loads(fitted.model.to_json())["channels"][0]["model"]
    theirs = json.loads((oven / "model.json").read_text())["channels"][0]["model"]
    assert ours["kind"] == theirs["kind"]
    assert ours["bias"] == theirs["bias"]
    assert [f["code"] for f in fitted.gate] == []  # the simulated oven run passes the quality gate


def test_calibrate_reports_the_quality_gate_and_refuses_bad_runs():
    t = np.arange(0, 3600.0, 1.0)
    flat = {"time_s": t, "rate_rad_s": np.zeros_like(t), "temp_c": np.full_like(t, 25.0)}
    with pytest.raises(driftlab.Error):
        driftlab.calibrate([flat])  # no temperature span: nothing to fit
    with pytest.raises(driftlab.ConfigError, match="poly, physical or rbf"):
        driftlab.calibrate([flat], model="cubic")
    with pytest.raises(driftlab.DataError, match="rate_rad_s"):
        driftlab.calibrate([{"time_s": t, "temp_c": t}])
