"""Pipeline.from_yaml(...).run(...): the pipeline engine on arrays or a Record, against `driftlab run`
on the same record (same code: the same outputs and step diagnostics)."""
import json

import driftlab
import numpy as np
import pytest
from conftest import read_csv_columns

DEG = np.pi / 180  # rad per degree, as framework/units.hpp's deg/s scale


@pytest.fixture
def oven_csv(cli, tmp_path):
    cli("simulate", "--device", "fmvmg", "--fs", 1, "--duration", 7200, "--seed", 5, "--out", "oven.csv")
    return tmp_path / "oven.csv"


def without_seconds(report):
    return [{k: v for k, v in step.items() if k != "seconds"} for step in report["steps"]]


def test_a_run_equals_driftlab_run_on_the_same_record(cli, oven_csv, tmp_path):
    pipeline_file = driftlab.pipelines_dir() / "polynomial_baseline.yaml"
    cli("run", "--pipeline", pipeline_file, "--data", oven_csv, "--out", "run")
    expected = read_csv_columns(tmp_path / "run" / "outputs.csv")
    report = json.loads((tmp_path / "run" / "report.json").read_text())
    record = driftlab.read_record(oven_csv)
    run = driftlab.Pipeline.from_yaml(pipeline_file).run(
        {"time": record.time_s, "rate": record.channels["rate"], "temperature": record.channels["temperature"]})
    assert run.units == {"polynomial": "rad/s"}
    assert np.array_equal(run.outputs["polynomial"] / DEG, expected["polynomial_dps"])  # written in deg/s
    assert without_seconds(run.report) == without_seconds(report)


def test_the_papers_pipeline_by_name_on_a_record_is_reproducible_from_its_effective_yaml(oven_csv):
    record = driftlab.read_record(oven_csv)
    pipeline = driftlab.Pipeline.from_yaml("li2023")
    assert pipeline.inputs == {"rate": "rate", "temperature": "temperature"}
    assert pipeline.outputs == ["rbf", "rbf_ga", "rbf_ga_kf", "drift_model"]
    first = pipeline.run(record)
    again = driftlab.Pipeline.from_yaml(pipeline.effective_yaml()).run(record, threads=2)
    for name in pipeline.outputs:
        assert first.outputs[name].shape == (len(record),)
        assert np.array_equal(first.outputs[name], again.outputs[name]), name
    assert [s["name"] for s in first.report["steps"]] == [name for name, _ in pipeline.steps]


def test_inputs_as_arrays_with_a_sample_rate():
    t = np.arange(600.0)
    temperature = 20 + 0.01 * t
    rate = 1e-3 * (temperature - 25) + 1e-5 * np.sin(t)
    pipeline = driftlab.Pipeline.from_yaml(driftlab.pipelines_dir() / "polynomial_baseline.yaml")
    with_time = pipeline.run({"time": t, "rate": rate, "temperature": temperature})
    with_rate = pipeline.run({"rate": rate.tolist(), "temperature": temperature}, fs_hz=1.0)
    assert np.array_equal(with_time.outputs["polynomial"], with_rate.outputs["polynomial"])
    assert np.abs(with_time.outputs["polynomial"]).max() < 2e-5  # the linear drift is gone, the sine stays


def test_a_bad_pipeline_lists_every_problem_with_its_line():
    text = ("format: driftlab-pipeline/1\ninputs: {rate: rate}\nsteps:\n"
            "  - name: a\n    plugin: decomposition/nonesuch\n    inputs: {signal: rate}\n"
            "  - name: b\n    plugin: decomposition/emd\n    inputs: {signal: rate}\n    params: {s_number: 0}\n"
            "outputs: {x: c.signal}\n")
    with pytest.raises(driftlab.ConfigError) as info:
        driftlab.Pipeline.from_yaml(text)
    lines = {p["line"] for p in info.value.problems}
    assert len(info.value.problems) >= 3 and {5, 10, 11} <= lines


def test_run_errors():
    pipeline = driftlab.Pipeline.from_yaml("polynomial_baseline")
    with pytest.raises(driftlab.DataError, match="temperature"):
        pipeline.run({"rate": np.zeros(100)}, fs_hz=1.0)
    with pytest.raises(driftlab.ConfigError, match="not both or neither"):
        pipeline.run({"rate": np.zeros(3), "temperature": np.zeros(3)})
    with pytest.raises(driftlab.DataError, match="time stamps must increase"):
        pipeline.run({"time": [0.0, 2.0, 1.0], "rate": np.zeros(3), "temperature": np.zeros(3)})
    with pytest.raises(driftlab.DataError, match="samples"):
        pipeline.run({"time": [0.0, 1.0, 2.0], "rate": np.zeros(2), "temperature": np.zeros(3)})


def test_table2_of_li2023_equals_driftlab_runs_report_and_print(cli, oven_csv, tmp_path):
    printed = cli("run", "--pipeline", driftlab.pipelines_dir() / "li2023.yaml", "--data", oven_csv, "--out", "run")
    report = json.loads((tmp_path / "run" / "report.json").read_text())
    run = driftlab.Pipeline.from_yaml("li2023").run(driftlab.read_record(oven_csv))
    # The same scoring code on the same record: every number equal (JSON keeps doubles exactly).
    for key in ("table2", "allan", "intrinsic_floor", "baselines", "units", "readings"):
        assert run.report[key] == report[key], key
    assert run.table2_text and run.table2_text in printed
    rows = {row["stage"]: row for row in run.report["table2"]}
    assert list(rows) == ["original", "rbf", "rbf_ga", "rbf_ga_kf", "px4_polynomial", "cubic_whole_record"]
    for stage, row in rows.items():
        # A value with its interval only where the deviation has a floor, otherwise the bound alone.
        if row["B_resolved"]:
            low, high = row["B_ci"]
            assert low <= row["B_deg_h"] <= high == row["B_upper_deg_h"], stage
        else:
            assert row["B_deg_h"] is None and "B_ci" not in row and row["B_upper_deg_h"] > 0, stage
        assert row["N_deg_h_rtHz"] > 0
    # Independent check of N on the raw record: the -1/2 line at tau = 1 s of allan() on the same rate.
    record = driftlab.read_record(oven_csv)
    a = driftlab.allan(record.channels["rate"], fs_hz=record.sample_rate_hz)
    assert rows["original"]["N_deg_h_rtHz"] == pytest.approx(a.arw_rad_sqrt_s * driftlab.DEG_H_PER_RAD_S, rel=1e-12)


def test_a_record_without_a_rate_has_no_table2():
    t = np.arange(600.0)
    run = driftlab.Pipeline.from_yaml("polynomial_baseline").run(
        {"time": t, "rate": 1e-3 * np.sin(t / 50), "temperature": 20 + 0.01 * t})
    assert "table2" in run.report  # arrays by role: 'rate' is the rate
    too_short = driftlab.Pipeline.from_yaml("polynomial_baseline").run(
        {"time": t[:8], "rate": np.zeros(8) + 1e-3 * t[:8], "temperature": 20 + t[:8]})
    assert "table2" not in too_short.report and too_short.table2_text == ""
    assert "table2_skipped" in too_short.report
