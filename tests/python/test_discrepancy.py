"""discrepancy(): the discrepancy workflow (models/discrepancy) against `driftlab discrepancy` on the
same record (same code: the same report, number for number), and against the effect planted by
`driftlab simulate --effect` (independent truth)."""
import json
import math

import driftlab
import numpy as np
import pytest
from conftest import read_csv_columns

DEG = np.pi / 180  # rad per degree, as framework/units.hpp's deg/s scale
PLANTED = "periodic_disturbance:amplitude_dph=80,period_s=900,phase_deg=30"


def nan_as_none(value):
    """The report as JSON holds it: NaN and infinities are written as null."""
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: nan_as_none(v) for k, v in value.items()}
    if isinstance(value, list):
        return [nan_as_none(v) for v in value]
    return value


@pytest.fixture
def disturbed_csv(cli, tmp_path):
    cli("simulate", "--device", "fmvmg", "--fs", 1, "--seed", 11, "--effect", PLANTED, "--out", "disturbed.csv")
    return tmp_path / "disturbed.csv"


def test_discrepancy_equals_driftlab_discrepancy_and_names_the_planted_effect(cli, disturbed_csv, tmp_path):
    device = driftlab.devices_dir() / "fmvmg.yaml"
    printed = cli("discrepancy", "--data", disturbed_csv, "--device", device, "--report", "report.json",
                  "--series", "series.csv")
    report = json.loads((tmp_path / "report.json").read_text())
    found = driftlab.discrepancy(driftlab.read_record(disturbed_csv), device=device)
    assert nan_as_none(found.report) == report  # every number, the views included
    assert "named periodic_disturbance" in printed
    # The planted disturbance, found by name with its period (1 %: a tenth of a periodogram bin).
    assert [e["effect"] for e in found.named_effects] == ["periodic_disturbance"]
    assert found.named_effects[0]["parameters"]["period_s"] == pytest.approx(900.0, abs=9.0)
    assert found.named_effects[0]["units"]["amplitude_dph"] == "deg/h"
    written = report["named_effects"][0]
    assert found.named_effects[0]["gap_before_deg_h"] == written["gap_before"] == report["gap_initial"]
    assert found.named_effects[0]["gap_after_deg_h"] == written["gap_after"] == report["gap_final"]
    assert found.named_effects[0]["evidence"]["delta_bic"] == written["evidence"]["delta_bic"] > 10.0
    assert found.gap_initial_deg_h == report["gap_initial"] > found.gap_final_deg_h == report["gap_final"]
    assert found.noise_floor_deg_h == report["noise_floor"] and not found.unexplained
    series = read_csv_columns(tmp_path / "series.csv")
    assert np.array_equal(found.model_final_rad_s / DEG, series["model_final_dps"])
    assert np.array_equal(found.model_initial_rad_s / DEG, series["model_initial_dps"])


def test_a_clean_record_from_arrays_names_nothing_and_options_reach_the_workflow(cli, tmp_path):
    cli("simulate", "--device", "fmvmg", "--fs", 1, "--seed", 11, "--out", "clean.csv")
    r = driftlab.read_record(tmp_path / "clean.csv")
    arrays = {"time": r.time_s, "rate": r.channels["rate"], "temperature": r.channels["temperature"]}
    found = driftlab.discrepancy(arrays, device="fmvmg", effects=["hysteresis", "thermal_lag"], block_s=60.0)
    assert found.named_effects == [] and found.report["criterion"]["block_s"] == 60.0
    assert [s["effect"] for s in found.report["final_scores"]] == ["hysteresis", "thermal_lag"]
    assert found.report["model"]["data"] == "<arrays>"


def test_discrepancy_errors(cli, tmp_path):
    cli("simulate", "--device", "fmvmg", "--fs", 1, "--duration", 3600, "--seed", 2, "--out", "r.csv")
    r = driftlab.read_record(tmp_path / "r.csv")
    with pytest.raises(driftlab.ConfigError, match="is not a candidate"):
        driftlab.discrepancy(r, effects=["hysteresis"], sets=["thermal_lag.tau_max_s=100"])
    with pytest.raises(driftlab.ConfigError, match="expected effect/NAME.key=value"):
        driftlab.discrepancy(r, sets=["nonsense"])
    with pytest.raises(driftlab.UnknownPluginError, match="effect/nope"):
        driftlab.discrepancy(r, effects=["nope"])
    with pytest.raises(driftlab.ConfigError, match="bias_degree"):
        driftlab.discrepancy(r, bias_degree=9)
    with pytest.raises(driftlab.ConfigError, match="whole"):
        driftlab.discrepancy(r, device="imu3")
    with pytest.raises(driftlab.DataError, match="temperature"):
        driftlab.discrepancy({"rate": np.zeros(100)}, fs_hz=1.0)
