"""emd, eemd, ceemdan, vmd: the decomposition plugins through the registry, checked against the
reconstruction identity, the command line (`driftlab decompose`, same code: bit-identical) and the
plugins' declared parameter tables."""
import inspect

import driftlab
import numpy as np
import pytest
from conftest import read_csv_columns, write_record

FS_HZ = 64.0  # a power of two: the CSV's time stamps and the derived sample rate are exact


def signal(n=4096, seed=3):
    t = np.arange(n) / FS_HZ
    rng = np.random.default_rng(seed)
    return np.sin(2 * np.pi * 0.2 * t) + 0.5 * np.sin(2 * np.pi * 3.0 * t) + 0.05 * t + 0.2 * rng.standard_normal(n)


def test_emd_residue_is_x_minus_the_imfs_in_extraction_order_and_the_parts_sum_back_to_x():
    x = signal()
    d = driftlab.emd(x)
    assert d.imfs.shape[0] >= 3 and d.imfs.shape[1] == x.size
    expected = x.copy()
    for imf in d.imfs:
        expected -= imf
    assert np.array_equal(d.residue, expected)  # the kernel's definition, bit for bit
    # Summed the other way round the identity holds to rounding: a few ulps of max|x| per IMF.
    tolerance = 4 * d.imfs.shape[0] * np.finfo(float).eps * np.abs(x).max()
    assert np.abs(d.imfs.sum(axis=0) + d.residue - x).max() <= tolerance


@pytest.mark.parametrize("name, sets", [
    ("emd", {}),
    ("emd", {"stop_rule": "cauchy_sd", "end_policy": "linear", "max_imfs": 5}),
    ("eemd", {"ensemble_size": 8, "seed": 7}),
    ("ceemdan", {"ensemble_size": 8, "variant": "colominas2014"}),
    ("vmd", {"modes": 4, "alpha": 500.0}),
])
def test_the_results_equal_driftlab_decompose_on_the_same_data(cli, tmp_path, name, sets):
    x = signal(n=2048)
    args = write_record(tmp_path / "x.csv", x, FS_HZ)
    cli("decompose", *args, "--plugin", f"decomposition/{name}", "--out", "parts.csv",
        *[a for k, v in sets.items() for a in ("--set", f"{k}={v}")])
    expected = read_csv_columns(tmp_path / "parts.csv")
    d = getattr(driftlab, name)(x, **sets)
    assert d.imfs.shape[0] == len(expected) - 2
    for k, imf in enumerate(d.imfs):
        assert np.array_equal(imf, expected[f"imf{k + 1}"])
    assert np.array_equal(d.residue, expected["residue"])


@pytest.mark.parametrize("name", ["emd", "eemd", "ceemdan", "vmd"])
def test_keyword_defaults_are_the_plugins_declared_defaults(name):
    table = driftlab.plugin_info(f"decomposition/{name}")["params"]
    signature = inspect.signature(getattr(driftlab, name))
    for p in table:
        assert signature.parameters[p["key"]].default == p["default"]
    x = signal(n=512)
    d = getattr(driftlab, name)(x, **({"ensemble_size": 4} if name in ("eemd", "ceemdan") else {}))
    assert {k: v for k, v in d.params.items() if k != "ensemble_size"} == \
        {p["key"]: p["default"] for p in table if p["key"] != "ensemble_size"}


def test_lists_and_integer_arrays_are_converted_to_float64():
    x = np.round(signal(n=600) * 100).astype(np.int32)
    expected = driftlab.emd(x.astype(float))
    for given in (x, x.tolist()):
        d = driftlab.emd(given)
        assert np.array_equal(d.imfs, expected.imfs)
        assert np.array_equal(d.residue, expected.residue)


def test_the_results_are_returned_without_a_copy():
    d = driftlab.emd(signal())
    for array in (d.imfs, d.residue):
        assert array.dtype == np.float64
        assert not array.flags.owndata  # numpy views the kernel's own storage
        assert array.base is not None
    assert d.imfs.flags.c_contiguous  # one IMF per row, each contiguous


def test_ensemble_results_do_not_depend_on_the_thread_count():
    x = signal(n=1024)
    one = driftlab.ceemdan(x, ensemble_size=6, threads=1)
    two = driftlab.ceemdan(x, ensemble_size=6, threads=2)
    assert np.array_equal(one.imfs, two.imfs)


def test_vmd_reports_centre_frequencies_in_hz_when_the_sample_rate_is_given():
    t = np.arange(4096) / FS_HZ
    x = np.sin(2 * np.pi * 2.0 * t) + np.sin(2 * np.pi * 10.0 * t)
    d = driftlab.vmd(x, modes=2, fs_hz=FS_HZ)
    assert d.diagnostics["centre_frequencies_hz"] == pytest.approx([10.0, 2.0], abs=0.05)


def test_bad_parameters_raise_ConfigError_listing_every_problem_with_the_tables_messages(cli, tmp_path):
    with pytest.raises(driftlab.ConfigError) as info:
        driftlab.emd(signal(n=256), s_number=0, no_such_key=1)
    problems = {p["field"]: p["message"] for p in info.value.problems}
    assert set(problems) == {"s_number", "no_such_key"}
    assert "valid: stop_rule, s_number" in problems["no_such_key"]
    # The same message as the command line's for the same value.
    args = write_record(tmp_path / "x.csv", signal(n=256), FS_HZ)
    failed = cli.fails("decompose", *args, "--set", "s_number=0", "--out", "parts.csv")
    assert problems["s_number"] in failed.stderr and failed.returncode == 2


def test_a_rule_across_parameters_and_a_wrong_type_are_ConfigErrors():
    with pytest.raises(driftlab.ConfigError, match="fixed_sifts <= max_sifts"):
        driftlab.emd(signal(n=256), stop_rule="fixed_sifts", fixed_sifts=60)
    with pytest.raises(driftlab.ConfigError, match="max_imfs: expected an integer"):
        driftlab.emd(signal(n=256), max_imfs=2.5)


def test_bad_data_raises_DataError_naming_the_sample():
    x = signal(n=256)
    x[17] = np.inf
    with pytest.raises(driftlab.DataError, match="sample 17 is infinite") as info:
        driftlab.emd(x)
    assert info.value.field == "x"
    with pytest.raises(driftlab.DataError, match="1-D"):
        driftlab.emd(np.zeros((3, 3)))


def test_decompose_runs_a_plugin_by_name_and_refuses_other_kinds():
    x = signal(n=512)
    assert np.array_equal(driftlab.decompose(x, "decomposition/emd").imfs, driftlab.emd(x).imfs)
    with pytest.raises(driftlab.ConfigError, match="not a decomposition plugin"):
        driftlab.decompose(x, "filter/kalman")
    with pytest.raises(driftlab.UnknownPluginError):
        driftlab.decompose(x, "decomposition/nonesuch")
